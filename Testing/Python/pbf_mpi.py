"""Under mpiexec -n 2 pvbatch the source and the filter run without error: rank 0 (piece 0)
simulates the whole fluid and the other rank outputs nothing, so every particle is counted once
and comes from process 0. Run with: mpiexec -n 2 pvbatch pbf_mpi.py --plugin PATH"""
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import servermanager  # noqa: E402
from paraview.simple import PointSource, ProcessIdScalars  # noqa: E402
from vtkmodules.util import numpy_support  # noqa: E402

T.load_plugin(globals())
expect = T.expect

ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
expect(ranks == 2, "expected 2 MPI ranks, running on %d (start with mpiexec -n 2 pvbatch)" % ranks)


def check(proxy, particles, what):
    proxy.UpdatePipeline(3 / 60.0)
    information = proxy.GetDataInformation()
    expect(information.GetNumberOfPoints() == particles,
           "%s: %d particles over all ranks, expected %d"
           % (what, information.GetNumberOfPoints(), particles))
    owners = ProcessIdScalars(Input=proxy)
    owners.UpdatePipeline(3 / 60.0)
    merged = servermanager.Fetch(owners)
    expect(merged.GetNumberOfPoints() == particles, "%s: fetched %d particles"
           % (what, merged.GetNumberOfPoints()))
    process = numpy_support.vtk_to_numpy(merged.GetPointData().GetArray("ProcessId"))
    expect(numpy.all(process == 0), "%s: particles on ranks %s, expected rank 0 only"
           % (what, sorted(set(process.tolist()))))
    ids = numpy.sort(numpy_support.vtk_to_numpy(merged.GetPointData().GetArray("id")))
    expect(numpy.array_equal(ids, numpy.arange(particles)), "%s: ids are not 0..N-1" % what)


source = PositionBasedFluids(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=4)  # noqa: F821
check(source, T.QUICK_PARTICLES, "source")

seed = PointSource(Center=[0.8, 0.35, 0.3], Radius=0.12, NumberOfPoints=100)
fluid = PositionBasedFluidsFromPoints(Input=seed, ParticleSpacing=0.04,  # noqa: F821
                                      NumberOfFrames=4)
check(fluid, 100, "filter")

T.passed("MPI")
