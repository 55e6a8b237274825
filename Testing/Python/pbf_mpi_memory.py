"""One rank's host memory while the filter builds a decomposed run, printed for
check_filter_memory.py: run on every rank with mpiexec -n N pvbatch --symmetric.

Each rank first builds a small run (the plugin's and MPI's first use, the libraries it loads),
then sets the fine spacing, resets the kernel's peak (/proc/self/clear_refs), builds again at
frame 0 (the scene's slab or the input's pieces, the stepper, the first evaluation, the output)
and prints its resident memory before, its peak during, and its particles.

Run with: mpiexec -n N pvbatch --symmetric pbf_mpi_memory.py --plugin PATH --spacing S [--points]
(--points: the fluid comes as a lattice through the From Points filter, each rank given its piece
of it by a programmable source. ParaView runs a programmable source's script in this module's
namespace after "from numpy import *", hence names numpy does not have.)"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import servermanager  # noqa: E402

run_spacing = float(sys.argv[sys.argv.index("--spacing") + 1])
from_points = "--points" in sys.argv
T.load_plugin(globals())
controller = servermanager.vtkProcessModule.GetProcessModule().GetGlobalController()
rank = controller.GetLocalProcessId()
ranks = controller.GetNumberOfProcesses()


def kilobytes(field):
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise RuntimeError("no %s in /proc/self/status" % field)


# The dam break's column (0.58 x 0.5 x 0.6 m from the corner of the 1.6 x 0.6 x 0.6 m tank, half a
# spacing in) as a lattice at the run's spacing; rank p's piece is the p-th share of it.
LATTICE = """
def lattice(algorithm, s):
    import numpy
    from vtkmodules.numpy_interface import dataset_adapter as dsa
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as sddp
    from vtkmodules.vtkCommonCore import vtkPoints
    info = algorithm.GetOutputInformation(0)
    piece = info.Get(sddp.UPDATE_PIECE_NUMBER()) if info.Has(sddp.UPDATE_PIECE_NUMBER()) else 0
    pieces = info.Get(sddp.UPDATE_NUMBER_OF_PIECES()) if info.Has(sddp.UPDATE_NUMBER_OF_PIECES()) else 1
    nx, ny, nz = int(0.58 / s), int(0.5 / s), int(0.6 / s)
    n = nx * ny * nz
    k = numpy.arange(n * piece // pieces, n * (piece + 1) // pieces, dtype=numpy.int64)
    share = numpy.stack([(k // (ny * nz)) * s, (k // nz %% ny) * s, (k %% nz) * s], axis=1) + 0.5 * s
    points = vtkPoints()
    points.SetData(dsa.numpyTovtkDataArray(numpy.ascontiguousarray(share)))
    algorithm.GetPolyDataOutput().SetPoints(points)
lattice(self, %r)
"""


def build(s):
    if from_points:
        from paraview.simple import ProgrammableSource
        lattice = ProgrammableSource(
            OutputDataSetType="vtkPolyData", Script=LATTICE % s,
            ScriptRequestInformation="from vtkmodules.vtkCommonExecutionModel import vtkAlgorithm\n"
            "self.GetOutputInformation(0).Set(vtkAlgorithm.CAN_HANDLE_PIECE_REQUEST(), 1)")
        return PositionBasedFluidsFromPoints(  # noqa: F821
            Input=lattice, ParticleSpacing=s, NumberOfFrames=2, Backend="Serial",
            GenerateSurface=0)
    return PositionBasedFluids(ParticleSpacing=s, NumberOfFrames=2,  # noqa: F821
                               Backend="Serial", GenerateSurface=0)


warm = build(0.05)
warm.UpdatePipeline(0.0)
fluid = build(run_spacing)
base = kilobytes("VmRSS")
with open("/proc/self/clear_refs", "w") as refs:
    refs.write("5")  # the peak (VmHWM) restarts from the current resident size
fluid.UpdatePipeline(0.0)
peak = kilobytes("VmHWM")
held = fluid.GetClientSideObject().GetOutputDataObject(0).GetNumberOfPoints()
print("PBF_MEMORY rank %d ranks %d particles %d base_kb %d peak_kb %d"
      % (rank, ranks, held, base, peak), flush=True)
