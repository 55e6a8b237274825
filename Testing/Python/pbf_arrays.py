"""A frame holds one vertex per particle with density, lambda, velocity and id arrays of the right
sizes and types and plausible values, and field data from which the density can be recomputed."""
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from vtkmodules.util import numpy_support  # noqa: E402

T.load_plugin(globals())
expect = T.expect

FIELD_ARRAYS = ["SmoothingLength", "RestDensity", "ParticleMass", "ParticleSpacing",
                "SmoothingRatio", "SolverIterations", "RelaxationEpsilon", "SCorrK", "SCorrN",
                "SCorrDeltaQ", "XSPHViscosity", "VorticityEpsilon", "Unilateral", "MirrorWalls", "Gravity",
                "Domain", "TimeStep", "FrameInterval", "SubstepsPerFrame", "Frame", "StepCount",
                "ReleasedParticles", "RemovedParticles", "Time", "Backend", "Precision", "Scene"]


def pairwise_distances(points):
    difference = points[:, None, :] - points[None, :, :]
    return numpy.sqrt(numpy.einsum("ijk,ijk->ij", difference, difference))


def check_structure(source, time, precision):
    data = T.output_at(source, time)
    n = data.GetNumberOfPoints()
    expect(n == T.QUICK_PARTICLES, "%d particles, expected %d" % (n, T.QUICK_PARTICLES))

    # One vertex cell per particle, in one cell array of vertices, nothing else.
    expect(data.GetNumberOfVerts() == n and data.GetNumberOfCells() == n,
           "%d vertex cells and %d cells for %d particles"
           % (data.GetNumberOfVerts(), data.GetNumberOfCells(), n))
    connectivity = numpy_support.vtk_to_numpy(data.GetVerts().GetConnectivityArray())
    offsets = numpy_support.vtk_to_numpy(data.GetVerts().GetOffsetsArray())
    expect(numpy.array_equal(numpy.sort(connectivity), numpy.arange(n)) and
           numpy.array_equal(numpy.diff(offsets), numpy.ones(n)),
           "the vertices do not reference each particle once")

    real = {"Single": "vtkFloatArray", "Double": "vtkDoubleArray"}[precision]
    expect(data.GetPoints().GetData().GetClassName() == real,
           "%s precision points are %s" % (precision, data.GetPoints().GetData().GetClassName()))
    point_data = data.GetPointData()
    for name, components, kind in (("density", 1, real), ("lambda", 1, real),
                                   ("pressure", 1, real),
                                   ("velocity", 3, real), ("id", 1, "vtkIdTypeArray")):
        array = point_data.GetArray(name)
        expect(array is not None, "point array %s is missing" % name)
        expect(array.GetNumberOfTuples() == n and array.GetNumberOfComponents() == components,
               "%s has %d x %d values, expected %d x %d"
               % (name, array.GetNumberOfTuples(), array.GetNumberOfComponents(), n, components))
        expect(array.GetClassName() == kind, "%s is a %s, expected %s"
               % (name, array.GetClassName(), kind))
    expect(point_data.GetGlobalIds() is not None and point_data.GetGlobalIds().GetName() == "id",
           "the id array is not the GlobalIds")
    expect(point_data.GetScalars() is not None and
           point_data.GetScalars().GetName() == "velocity",
           "velocity is not the active scalars (views would not color by it)")
    for name in FIELD_ARRAYS:
        T.field_value(data, name)
    expect(T.field_value(data, "Precision") == precision.lower(),
           "field Precision = %s" % T.field_value(data, "Precision"))


source = PositionBasedFluids(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=6,  # noqa: F821
                             Backend="Serial")
check_structure(source, 0.0, "Single")
check_structure(source, 6 / 60.0, "Single")
source.Precision = "Double"
check_structure(source, 0.0, "Double")

# Frame 0, double precision: the density is poly6 summed over the lattice with the particle mass
# and h of the field data. The solver evaluates it on these very positions, so only rounding
# differs (1e-9 relative). Particles within h of a wall are left out: walls may add mirror
# images of neighbours (Solver/Physics/Equations.h), which no particle farther than h from them sees.
data = T.output_at(source, 0.0)
initial = T.frame(source, 0.0)
h = T.field_value(data, "SmoothingLength")
mass = T.field_value(data, "ParticleMass")
rho0 = T.field_value(data, "RestDensity")
lo = numpy.array(T.field_value(data, "Domain")[0::2])
hi = numpy.array(T.field_value(data, "Domain")[1::2])
x = initial["points"]
r = pairwise_distances(x)
poly6 = numpy.where(r < h, 315.0 / (64.0 * numpy.pi * h ** 9) * (h * h - r * r) ** 3, 0.0)
recomputed = mass * poly6.sum(axis=1)
away_from_walls = numpy.all((x - lo > h) & (hi - x > h), axis=1)
expect(numpy.count_nonzero(away_from_walls) > 20,
       "only %d particles farther than h from the walls" % numpy.count_nonzero(away_from_walls))
relative = numpy.abs(recomputed - initial["density"]) / rho0
expect(numpy.max(relative[away_from_walls]) < 1e-9,
       "recomputed density differs from the solver's by %g of rho0"
       % numpy.max(relative[away_from_walls]))
# The mass is calibrated so the lattice interior reads rho_0 (Parameters.h, LatticeCalibration).
interior = numpy.all((x - x.min(axis=0) > h) & (x.max(axis=0) - x > h), axis=1)
expect(numpy.max(numpy.abs(initial["density"][interior] / rho0 - 1)) < 1e-9,
       "the initial lattice interior does not read rho_0")

# Frame 6 (0.1 s): the column is collapsing. The bulk (particles with at least the median
# neighbour count) stays within 0.5..1.5 rho_0; a PBF fluid with 4 iterations holds a few %.
later = T.frame(source, 6 / 60.0)
expect(T.finite(later["points"]) and T.finite(later["velocity"]) and
       T.finite(later["density"]) and T.finite(later["lambda"]), "non-finite values at frame 6")
expect(numpy.array_equal(later["id"], numpy.arange(later["n"])),
       "ids are not unique 0..N-1")
neighbours = (pairwise_distances(later["points"]) < h).sum(axis=1) - 1
bulk = neighbours >= numpy.median(neighbours)
ratio = later["density"][bulk] / rho0
expect(ratio.min() > 0.5 and ratio.max() < 1.5,
       "bulk density spans %.3f..%.3f rho_0" % (ratio.min(), ratio.max()))
expect(numpy.all(later["density"] > 0), "a density is not positive")
inside = numpy.all((later["points"] > lo - 1e-6) & (later["points"] < hi + 1e-6), axis=1)
expect(numpy.all(inside), "%d particles left the domain" % numpy.count_nonzero(~inside))
speed = numpy.linalg.norm(later["velocity"], axis=1)
# Free fall for 0.1 s reaches 0.98 m/s; nothing may outrun a fall from the tank's top (4 m/s).
expect(speed.max() < 4.0, "max speed %.3f m/s" % speed.max())
expect(later["velocity"][:, 1].mean() < -0.05,
       "the column is not falling: mean v_y = %.3f m/s" % later["velocity"][:, 1].mean())
expect(numpy.count_nonzero(later["lambda"]) > 0, "lambda is zero everywhere")
# The pressure is the step's corrections' (recordPressure): none before the first step, and never
# negative where the constraint is unilateral (lambda <= 0 wherever it acts).
expect(numpy.all(initial["pressure"] == 0), "frame 0 has a pressure before any step")
expect(T.finite(later["pressure"]) and numpy.all(later["pressure"] >= 0),
       "pressure at frame 6 is negative or not finite (min %g)" % later["pressure"].min())
expect(numpy.count_nonzero(later["pressure"]) > 0, "pressure is zero everywhere at frame 6")

T.passed("Arrays")
