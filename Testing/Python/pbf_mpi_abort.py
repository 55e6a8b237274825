"""Abort in a decomposed run: under mpiexec -n 2 pvbatch only rank 0 sees the Cancel
(a ProgressEvent observer on its algorithm sets AbortExecute, as the button would), yet every rank
stops at the same step: the ranks agree after each step, so none is left waiting for another in an
exchange (without that agreement this test hangs until CTest's timeout). Every rank keeps its
previous output, and the next request resumes on both ranks and is bit-identical, matched by id,
to a straight run of the same source.

Run with: mpiexec -n 2 pvbatch pbf_mpi_abort.py --plugin PATH"""
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
TARGET = 500  # far enough that finishing it instead of aborting would show in the time
RESUME = 12

ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
expect(ranks == 2, "expected 2 MPI ranks, running on %d" % ranks)


def source():
    return PositionBasedFluids(ParticleSpacing=0.05, NumberOfFrames=TARGET,  # noqa: F821
                               SubstepsPerFrame=2, CheckpointInterval=10)


def fetched(owners, frame):
    """Every rank's particles of a frame, gathered on rank 0, sorted by id."""
    owners.UpdatePipeline(frame * FRAME)
    data = servermanager.Fetch(owners)
    ids = numpy_support.vtk_to_numpy(data.GetPointData().GetArray("id"))
    order = numpy.argsort(ids, kind="stable")
    points = numpy_support.vtk_to_numpy(data.GetPoints().GetData())
    process = numpy_support.vtk_to_numpy(data.GetPointData().GetArray("ProcessId"))
    return ids[order], points[order], set(process.tolist())


aborting = source()
owners = ProcessIdScalars(Input=aborting)
before = fetched(owners, 4)
expect(before[2] == {0, 1}, "frame 4 came from ranks %s" % sorted(before[2]))

algorithm = aborting.GetClientSideObject()  # rank 0's: pvbatch's script runs on rank 0 only
after_abort, progress, elapsed = T.cancelled_request(algorithm, lambda: fetched(owners, TARGET))
stepped = [p for p in progress if 0.0 < p < 1.0]
print("abort on rank 0 after %d steps; the request returned in %.2f s" % (len(stepped), elapsed))
# 1 % of the jump is about 5 frames of 4 automatic steps (1/240 s at this spacing): about 20
# steps, then the abort within one more.
expect(len(stepped) <= 24, "the abort took %d steps to be honoured" % len(stepped))
expect(elapsed < 60.0, "the aborted request took %.1f s" % elapsed)
expect(numpy.array_equal(after_abort[0], before[0]) and
       numpy.array_equal(after_abort[1], before[1]) and after_abort[2] == {0, 1},
       "after the abort the ranks' outputs are not frame 4 as before")

# Rank 0's AbortExecute is cleared by whoever set it; the next request resumes on every rank.
algorithm.SetAbortExecute(0)
resumed = fetched(owners, RESUME)
straight = fetched(ProcessIdScalars(Input=source()), RESUME)
expect(resumed[2] == {0, 1}, "frame %d came from ranks %s" % (RESUME, sorted(resumed[2])))
expect(numpy.array_equal(resumed[0], straight[0]),
       "frame %d after the abort: the particle ids differ from a straight run" % RESUME)
expect(numpy.array_equal(resumed[1], straight[1]),
       "frame %d after the abort differs from a straight run (max %.3g)"
       % (RESUME, float(numpy.max(numpy.abs(resumed[1] - straight[1])))))
print("MPI abort: passed (%d particles on 2 ranks)" % len(resumed[0]))
