"""Bad input in a decomposed run: under mpiexec -n 2 pvbatch every rank meets the same bad
parameter, fails the request with the same error and keeps its previous output, and nothing hangs
(each rank fails before the first exchange, so none waits for another); the next valid request
works on all ranks. The expected error is printed by every rank, so this test's CTest entry has no
"ERROR" failure pattern; it passes on its last line.

Run with: mpiexec -n 2 pvbatch pbf_mpi_bad_input.py --plugin PATH"""
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import servermanager  # noqa: E402
from paraview.simple import ProcessIdScalars  # noqa: E402
from vtkmodules.util import numpy_support  # noqa: E402

T.load_plugin(globals())
expect = T.expect
FRAME = 1.0 / 60.0

ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
expect(ranks == 2, "expected 2 MPI ranks, running on %d" % ranks)
source = PositionBasedFluids(ParticleSpacing=0.05, NumberOfFrames=10)  # noqa: F821
owners = ProcessIdScalars(Input=source)


def gathered(time):
    owners.UpdatePipeline(time)
    data = servermanager.Fetch(owners)
    process = numpy_support.vtk_to_numpy(data.GetPointData().GetArray("ProcessId"))
    ids = numpy.sort(numpy_support.vtk_to_numpy(data.GetPointData().GetArray("id")))
    return data.GetNumberOfPoints(), set(process.tolist()), ids


before = gathered(2 * FRAME)
expect(before[1] == {0, 1}, "frame 2 came from ranks %s" % sorted(before[1]))

for name, value in (("SmoothingRatio", 0.0), ("ParticleSpacing", float("nan"))):
    good = getattr(source, name)
    setattr(source, name, value)
    (failed, messages) = T.capture_messages(lambda: gathered(3 * FRAME))
    # The message names the property by its label (Smoothing Ratio).
    expect(name.lower() in messages.lower().replace(" ", ""),
           "%s = %s: no error naming it on rank 0: %r" % (name, value, messages[:300]))
    expect(failed[0] == before[0] and numpy.array_equal(failed[2], before[2]),
           "%s = %s: the previous output did not stay on every rank" % (name, value))
    setattr(source, name, good)

# Backend CUDA where the ranks have no GPU: each rank can tell only for itself, so the ranks agree
# first and then all fail alike (without that, a rank with a GPU would wait for one without).
description = servermanager.Fetch(source).GetFieldData().GetAbstractArray("Backend").GetValue(0)
if description.startswith("CUDA"):
    print("the ranks have GPUs (%s): the Backend = CUDA failure is not exercised here" % description)
else:
    source.Backend = "CUDA"
    (failed, messages) = T.capture_messages(lambda: gathered(3 * FRAME))
    expect("backend = cuda" in messages.lower() and "rank" in messages.lower(),
           "Backend = CUDA without GPUs: no error naming the field and the rank: %r" % messages[:300])
    expect(failed[0] == before[0] and numpy.array_equal(failed[2], before[2]),
           "Backend = CUDA: the previous output did not stay on every rank")
    source.Backend = "Auto"

after = gathered(3 * FRAME)
expect(after[0] == before[0] and after[1] == {0, 1}, "the next valid request did not work on both ranks")
T.passed("MPI bad input")
