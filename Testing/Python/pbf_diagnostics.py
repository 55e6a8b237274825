"""The second output port, Diagnostics, is a vtkTable with one row per computed frame (0 to the
furthest computed, in order), kept while scrubbing and replaced after a physics change, with sane
values; and adaptive iterations stop early within the SolverIterations cap."""
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import servermanager  # noqa: E402
from paraview.simple import CreateRenderView, Delete, GetViews  # noqa: E402
from vtkmodules.util import numpy_support  # noqa: E402

T.load_plugin(globals())
expect = T.expect

INTERVAL = 1.0 / 60.0
COLUMNS = ["Time", "Frame", "AverageDensityError", "MaxDensityError", "AverageNeighbors",
           "SolverIterations", "MillisecondsPerStep", "Substeps", "MinTimeStep", "MaxTimeStep",
           "MaxSpeed", "KineticEnergy", "Particles", "Backend"]
# Then the loads on the tank's six mirror walls, asked for (TankLoads; every backend sums them).
COLUMNS += [what + " tank " + wall for wall in ("-x", "+x", "-y", "+y", "-z", "+z")
            for what in ("Force", "Torque")]
DETERMINISTIC = [c for c in COLUMNS if c != "MillisecondsPerStep"]

# Automatic time steps (the default) and the fixed count of projections, so that every step's
# iterations are known.
source = PositionBasedFluids(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=12,  # noqa: F821
                             AdaptiveIterations=0, SolverIterations=4, MaxTimeStep=0.002,
                             TankLoads=1)
expect(source.SMProxy.GetOutputPortName(1) == "Diagnostics",
       "output port 1 is named %r" % source.SMProxy.GetOutputPortName(1))
# What Apply does with the two ports: the particles go to the active render
# view, the Diagnostics to no view at all, so a first Apply opens no second view and draws no
# chart of a single row ("Attempted to paint a line with <2 points"); a Line Chart View shows
# them when its eye is clicked.
controller = servermanager.vtkSMParaViewPipelineControllerWithRendering()
render_view = CreateRenderView()
views_before = len(GetViews())
expect(controller.ShowInPreferredView(source.SMProxy, 1, render_view.SMProxy) is None,
       "Apply would show the Diagnostics in a view of their own")
expect(controller.ShowInPreferredView(source.SMProxy, 0, render_view.SMProxy) is not None,
       "Apply would not show the particles in the render view")
expect(len(GetViews()) == views_before,
       "Apply opened %d more views" % (len(GetViews()) - views_before))
Delete(render_view)
particles = T.output_at(source, 8 * INTERVAL)
table_object = source.GetClientSideObject().GetOutputDataObject(1)
expect(table_object.IsA("vtkTable"), "port 1 is a %s" % table_object.GetClassName())
# Through the server manager too, as a Line Chart View or a spreadsheet gets it.
fetched = servermanager.Fetch(source, idx=1)
expect(fetched.IsA("vtkTable") and fetched.GetNumberOfRows() == 9,
       "Fetch of port 1 gave a %s of %d rows" % (fetched.GetClassName(), fetched.GetNumberOfRows()))

table = T.diagnostics(source)
expect(list(table) == COLUMNS, "columns %s, expected %s" % (list(table), COLUMNS))
expect(table_object.GetColumnByName("Backend").IsA("vtkStringArray"), "Backend is not a string column")
frames = numpy.arange(9)
expect(list(table["Frame"]) == list(frames), "rows of frames %s, expected 0..8" % list(table["Frame"]))
# Frame k lands on k * INTERVAL exactly, however many steps it took.
expect(numpy.array_equal(table["Time"], frames * INTERVAL), "times %s" % table["Time"])
# Each frame's steps: whole, at most MaxTimeStep, and adding up to the interval.
n, low, high = table["Substeps"][1:], table["MinTimeStep"][1:], table["MaxTimeStep"][1:]
expect(numpy.all(n >= numpy.ceil(INTERVAL / 0.002)) and numpy.all(n == numpy.round(n)),
       "substeps per frame %s (at most 0.002 s each)" % n)
expect(numpy.all((low > 0) & (low <= high) & (high <= 0.002 * (1 + 1e-12))) and
       numpy.all(n * low <= INTERVAL * (1 + 1e-9)) and numpy.all(n * high >= INTERVAL * (1 - 1e-9)),
       "time steps per frame: %s substeps of %s..%s s" % (n, low, high))
expect(numpy.isnan(table["Substeps"][0]) and numpy.isnan(table["MinTimeStep"][0]),
       "frame 0 has time steps")
expect(all(table["Particles"] == T.QUICK_PARTICLES), "particles %s" % table["Particles"])
expect(table["Backend"] == [T.field_value(particles, "Backend")] * 9,
       "backend %s, the frame says %s" % (table["Backend"], T.field_value(particles, "Backend")))
# The rest lattice: about 25 neighbours within h = 2 s at this spacing (30 in the bulk, fewer at
# the free surface), no compression; then the column falls and compresses a little.
expect(numpy.all((table["AverageNeighbors"] > 15) & (table["AverageNeighbors"] < 40)),
       "average neighbours %s" % table["AverageNeighbors"])
expect(table["AverageDensityError"][0] < 1e-3, "frame 0 compressed by %g %%"
       % table["AverageDensityError"][0])
expect(numpy.all(table["AverageDensityError"] >= 0) and
       numpy.all(table["AverageDensityError"] <= table["MaxDensityError"]) and
       numpy.all(table["MaxDensityError"] < 20),
       "density errors [%%]: average %s, max %s" % (table["AverageDensityError"],
                                                     table["MaxDensityError"]))
expect(numpy.all(numpy.diff(table["MaxSpeed"][:6]) > 0) and table["KineticEnergy"][8] > 0,
       "the falling column does not speed up: %s" % table["MaxSpeed"])
# Frame 0 took no step; every later frame's steps took SolverIterations (fixed count).
expect(numpy.isnan(table["SolverIterations"][0]) and numpy.isnan(table["MillisecondsPerStep"][0]),
       "frame 0 has per-step values")
expect(numpy.all(table["SolverIterations"][1:] == source.SolverIterations),
       "iterations per step %s, fixed at %d" % (table["SolverIterations"], source.SolverIterations))
expect(numpy.all((table["MillisecondsPerStep"][1:] > 0) & (table["MillisecondsPerStep"][1:] < 1e4)),
       "milliseconds per step %s" % table["MillisecondsPerStep"])

# Scrubbing back keeps the rows; going further adds rows in order.
first = table
T.output_at(source, 3 * INTERVAL)
table = T.diagnostics(source)
expect(list(table["Frame"]) == list(frames), "after going back to 3 the rows are %s"
       % list(table["Frame"]))
for name in DETERMINISTIC:
    same = table[name] == first[name] if name == "Backend" else \
        numpy.array_equal(table[name], first[name], equal_nan=True)
    expect(same, "going back to 3 changed the %s column" % name)
T.output_at(source, 12 * INTERVAL)
table = T.diagnostics(source)
expect(list(table["Frame"]) == list(range(13)), "after frame 12 the rows are %s"
       % list(table["Frame"]))

# The density errors are the solver's own, frame by frame: 100 max(rho_i / rho_0 - 1, 0) over
# the frame's `density` array (rho_i of the last constraint evaluation, which the statistics
# read), the same double operations on the same floats, so the max agrees exactly and the
# average to the summation order (1e-12 relative). On a moving frame the most compressed
# particle is compressed well beyond the mean.
rest = source.RestDensity
for frame in (4, 8, 12):
    data = T.output_at(source, frame * INTERVAL)
    density = numpy_support.vtk_to_numpy(data.GetPointData().GetArray("density"))
    errors = numpy.maximum(density.astype(numpy.float64) / rest - 1.0, 0.0)
    row = list(table["Frame"]).index(frame)
    expect(table["MaxDensityError"][row] == 100.0 * errors.max(),
           "frame %d: MaxDensityError %.17g %%, the frame's densities give %.17g %%"
           % (frame, table["MaxDensityError"][row], 100.0 * errors.max()))
    expect(abs(table["AverageDensityError"][row] - 100.0 * errors.mean())
           <= 1e-12 * 100.0 * errors.mean(),
           "frame %d: AverageDensityError %.17g %%, the frame's densities give %.17g %%"
           % (frame, table["AverageDensityError"][row], 100.0 * errors.mean()))
    expect(table["MaxDensityError"][row] > 2 * table["AverageDensityError"][row] > 0,
           "frame %d: max %g %% not above twice the average %g %% on a moving frame"
           % (frame, table["MaxDensityError"][row], table["AverageDensityError"][row]))
table = T.diagnostics(source)

# A physics change replaces the rows by those of the new run.
source.SolverIterations = 2
T.output_at(source, 4 * INTERVAL)
table = T.diagnostics(source)
expect(list(table["Frame"]) == list(range(5)), "after SolverIterations 2 the rows are %s"
       % list(table["Frame"]))
expect(numpy.all(table["SolverIterations"][1:] == 2), "iterations %s after SolverIterations 2"
       % table["SolverIterations"])
expect(not numpy.array_equal(table["AverageDensityError"][1:], first["AverageDensityError"][1:5]),
       "SolverIterations 2 left the density errors unchanged")

# Adaptive iterations: at most SolverIterations per step, fewer where the fluid is barely
# compressed (1 %), all of them where the tolerance cannot be met (1e-6 %).
source.SolverIterations = 6
source.AdaptiveIterations = 1
source.DensityErrorTolerance = 1.0
data = T.output_at(source, 10 * INTERVAL)
expect(T.field_value(data, "DensityErrorTolerance") == 1.0, "the tolerance did not reach the solver")
iterations = T.diagnostics(source)["SolverIterations"][1:]
expect(numpy.all((iterations >= 0) & (iterations <= 6)) and iterations.min() < 6,
       "adaptive iterations per step at 1 %%: %s (cap 6)" % iterations)
source.DensityErrorTolerance = 1e-6
T.output_at(source, 3 * INTERVAL)
iterations = T.diagnostics(source)["SolverIterations"][1:]
expect(numpy.all(iterations == 6), "adaptive iterations at 1e-6 %%: %s, expected the cap 6"
       % iterations)

T.passed("Diagnostics")
