"""A pvbatch test that fails under mpiexec must fail every rank within seconds, not leave
`mpiexec -n 2 pvbatch` waiting in a barrier until CTest's 600 s timeout.
This script fails on purpose after a decomposed frame and a fetch; CTest expects the failure's
text within a short timeout (pbf.mpi.pvbatch_failure_ends_every_rank). Here (OpenMPI 4.1,
ParaView 5.11, rank 0 running the script) it ends in about 6 s with or without pbf_testing's
excepthook, which ends the failing rank at once under MPI whatever the other ranks are doing.

Run with: mpiexec -n 2 pvbatch pbf_mpi_failure.py --plugin PATH"""
import pbf_testing as T
from paraview.simple import *  # noqa: F401,F403

T.load_plugin(globals())
fluid = PositionBasedFluids(ParticleSpacing=0.05, DecomposeAcrossRanks=1)  # noqa: F821
owners = ProcessIdScalars(Input=fluid)  # noqa: F405
owners.UpdatePipeline(1.0 / 60.0)
print("MPI failure: fetched %d particles" % servermanager.Fetch(owners).GetNumberOfPoints())  # noqa: F405
print("MPI failure: frame 1 computed; now failing on purpose", flush=True)
raise T.TestFailure("deliberate failure on rank 0 (the other ranks must stop too)")
