"""As a filter the algorithm makes the input's points the fluid: point i is particle i at frame 0
(with the input's "velocity" when it has one), the fluid then falls inside the scene's domain,
an input change restarts it, and an empty input, a NaN coordinate or a point outside the domain is
an error naming the point and its value, with the previous output kept."""
import os
import sys
import time

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview.simple import Delete, PointSource, ProgrammableSource  # noqa: E402
from vtkmodules.util import numpy_support  # noqa: E402

T.load_plugin(globals())
expect = T.expect

# A ball of random points in the middle of the dam break tank (x 0..1.6, y 0..0.8, z 0..0.6),
# about as dense as the lattice: a 0.12 m ball holds 113 sites of 0.04 m.
SPACING = 0.04
seed = PointSource(Center=[0.8, 0.35, 0.3], Radius=0.12, NumberOfPoints=100)
fluid = PositionBasedFluidsFromPoints(Input=seed, ParticleSpacing=SPACING,  # noqa: F821
                                      NumberOfFrames=6, SubstepsPerFrame=2)

seed.UpdatePipeline()
seed_points = numpy_support.vtk_to_numpy(
    seed.GetClientSideObject().GetOutputDataObject(0).GetPoints().GetData()).copy()
start = T.frame(fluid, 0.0)
expect(start["n"] == 100, "100 input points became %d particles" % start["n"])
expect(numpy.array_equal(start["id"], numpy.arange(100)), "ids are not the input's point ids")
expect(numpy.array_equal(start["points"], seed_points.astype(start["points"].dtype)),
       "frame 0 is not the input's points, point i as particle i")
expect(not start["velocity"].any(), "an input without velocity must start at rest")

later = T.frame(fluid, 6 / 60.0)
expect(T.finite(later["points"]) and T.finite(later["velocity"]), "non-finite values at frame 6")
expect(later["n"] == 100 and numpy.array_equal(later["id"], numpy.arange(100)),
       "the particles changed")
domain = T.field_value(T.output_at(fluid, 6 / 60.0), "Domain")
expect(domain == (0.0, 1.6, 0.0, 0.8, 0.0, 0.6), "the scene's domain is %s" % (domain,))
# The ball is in free fall for 0.1 s (12 steps of 1/120 s, far from the floor): its internal
# pressure is pairwise, so its centre falls as one body, v_y = -g t = -0.981 m/s and, with the
# solver's symplectic Euler, g dt^2 (12 * 13 / 2) = 5.31 cm. The tolerance (5%, 10%) leaves room
# for the vorticity confinement and the spreading of a random ball.
fall = start["points"][:, 1].mean() - later["points"][:, 1].mean()
expect(abs(fall - 0.0531) < 0.1 * 0.0531, "the ball's centre fell %.4f m in 0.1 s" % fall)
vy = later["velocity"][:, 1].mean()
expect(abs(vy + 0.981) < 0.05 * 0.981, "the ball's centre falls at %.3f m/s" % vy)
speed = numpy.linalg.norm(later["velocity"], axis=1)
expect(speed.max() < 4.0, "a particle of the ball moves at %.2f m/s" % speed.max())

# The input changes: the simulation restarts from the new points.
seed.NumberOfPoints = 80
expect(T.frame(fluid, 3 / 60.0)["n"] == 80, "a changed input was not used")

# An input with a "velocity" point array starts with that velocity.
LATTICE = """
import numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkPolyData
from vtkmodules.util import numpy_support
g = numpy.arange(%(n)d) * 0.05 + 0.5
x = numpy.array(numpy.meshgrid(g, g - 0.3, g - 0.3, indexing="ij")).reshape(3, -1).T.copy()
%(edit)s
points = vtkPoints()
points.SetData(numpy_support.numpy_to_vtk(x, deep=True))
output.SetPoints(points)
v = numpy_support.numpy_to_vtk(numpy.tile([1.0, 0.0, -0.5], (len(x), 1)), deep=True)
v.SetName("velocity")
output.GetPointData().AddArray(v)
"""
lattice = ProgrammableSource(OutputDataSetType="vtkPolyData",
                             Script=LATTICE % {"n": 4, "edit": ""})
fluid.Input = lattice
moving = T.frame(fluid, 0.0)
expect(moving["n"] == 64, "the lattice gave %d particles" % moving["n"])
expect(numpy.all(moving["velocity"] == numpy.array([1.0, 0.0, -0.5], dtype=numpy.float32)),
       "the input's velocity array was not the initial velocity")

# Errors name the point and its value; the previous output stays.
BAD = [
    ("empty input", "x = x[:0]", ["input number of points = 0"]),
    ("NaN coordinate", "x[5, 1] = float('nan')", ["input point 5", "nan", "finite"]),
    ("point outside the domain", "x[7] = [5.0, 0.2, 0.3]",
     ["position of particle 7", "(5, 0.2, 0.3)", "outside the domain"]),
    # Input the solver would tear apart is named before any step: packed at 0.4 of the
    # spacing, or lying on the floor, which the floor's mirror image doubles.
    ("points packed denser than the spacing", "x = (x - x.mean(axis=0)) * 0.4 + x.mean(axis=0)",
     ["64 points in", "per cell where the fluid holds 1", "Set Particle Spacing to about"]),
    ("points on the floor", "x[:, 1] -= x[:, 1].min()",
     ["16 points lie within a quarter of Particle Spacing", "a wall of the domain", "dam_break",
      "half a spacing inside"]),
]
for what, edit, needles in BAD:
    lattice.Script = LATTICE % {"n": 4, "edit": edit}
    _, text = T.capture_messages(lambda: T.output_at(fluid, 0.0))
    errors = [line for line in text.splitlines() if line.startswith("vtkPBFSimulation")]
    expect(len(errors) == 1, "%s: expected one vtkPBFSimulation error, got %r" % (what, text))
    for needle in needles:
        expect(needle in errors[0], "%s: the error %r does not name %r" % (what, errors[0], needle))
    T.expect_identical(T.frame(fluid, 0.0), moving, "%s: the output after the error" % what)

# The inputs a new user tried, each named before any step and within 2 s:
# dense random clouds (the number density against the spacing), a lattice at exactly the spacing
# starting on the walls (the wall mirrors it), a single point. 2 s is what a user waits without
# wondering; each check is one pass over the points (200,000 here).
CLOUDS = [
    ("200,000 random points in the tank",
     "x = rng.uniform([0.1, 0.05, 0.05], [1.5, 0.75, 0.55], (200000, 3))",
     ["200000 points in", "per cell where the fluid holds 1", "Set Particle Spacing to about",
      "or resample"]),
    ("500 random points in a 0.1 m ball",
     "d = rng.normal(size=(500, 3)); x = [0.8, 0.4, 0.3] + 0.1 * rng.uniform(size=(500, 1)) ** "
     "(1 / 3) * d / numpy.linalg.norm(d, axis=1)[:, None]",
     ["500 points in", "Set Particle Spacing to about"]),
    ("an 11^3 lattice at the spacing from the corner",
     "g = numpy.arange(11) * 0.04; x = numpy.array(numpy.meshgrid(g, g, g)).reshape(3, -1).T",
     ["331 points lie within a quarter of Particle Spacing", "a wall of the domain",
      'Preset "dam_break"', "a Scene File"]),
    ("a single point", "x = numpy.array([[0.8, 0.4, 0.3]])",
     ["input number of points = 1", "at least 2 points"]),
]
CLOUD = """
import numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.util import numpy_support
rng = numpy.random.default_rng(17)
%s
points = vtkPoints()
points.SetData(numpy_support.numpy_to_vtk(numpy.ascontiguousarray(x, dtype=float), deep=True))
output.SetPoints(points)
"""
for what, make, needles in CLOUDS:
    cloud = ProgrammableSource(OutputDataSetType="vtkPolyData", Script=CLOUD % make)
    cloud.UpdatePipeline()
    checked = PositionBasedFluidsFromPoints(Input=cloud, ParticleSpacing=SPACING)  # noqa: F821
    began = time.monotonic()
    _, text = T.capture_messages(lambda: checked.UpdatePipeline(0.5))
    seconds = time.monotonic() - began
    # A new source says once which backend Auto chose; that line is not an error.
    errors = [line for line in text.splitlines()
              if line.startswith("vtkPBFSimulation") and "Backend Auto" not in line]
    expect(len(errors) == 1, "%s: expected one vtkPBFSimulation error, got %r" % (what, text))
    for needle in needles:
        expect(needle in errors[0], "%s: the error %r does not name %r" % (what, errors[0], needle))
    # No simulation started: no particles out and no frame in the diagnostics.
    algorithm = checked.GetClientSideObject()
    rows = algorithm.GetOutputDataObject(1).GetNumberOfRows()
    expect(algorithm.GetOutputDataObject(0).GetNumberOfPoints() == 0 and rows == 0,
           "%s: a simulation started (%d diagnostics rows)" % (what, rows))
    expect(seconds < 2.0, "%s: the error took %.2f s" % (what, seconds))
    print("%s: named in %.2f s: %s" % (what, seconds, errors[0][errors[0].index(":") + 2:][:160]))
    Delete(checked)
    Delete(cloud)

# A valid input works again.
lattice.Script = LATTICE % {"n": 3, "edit": ""}
expect(T.frame(fluid, 2 / 60.0)["n"] == 27, "a valid input after the errors was not simulated")

T.passed("Filter")
