"""ParaView's GUI (run by smTestDriver under Xvfb, the plugin loaded with --plugins) creates the
source with its defaults, shows it as the proxy's hints say, plays the animation to the last frame
and saves a screenshot in which the particles must be visible and colored by |velocity|. Going
back in time resumes from a checkpoint, display changes re-execute nothing, a preset and its
scene file give the same fluid, and the Diagnostics output, shown in a Line Chart View, holds a
row per frame and plots the density errors as lines. The Surface output of the dam break (with
GenerateSurface) is shown colored by |velocity|.

PBF_GUI_FRAMES, when set, shortens the animation (NumberOfFrames); everything else is default."""
import os
import sys

import numpy
from paraview import servermanager, simple
from vtkmodules.util import numpy_support

# The GUI runs this with --script, where __file__ is not always defined: the test's environment
# names the source tree.
sys.path.insert(0, os.path.join(os.environ["PBF_SOURCE_DIR"], "Testing", "Python"))
from pbf_images import corners_off_view, read_png  # noqa: E402


def expect(condition, message):
    if not condition:
        raise RuntimeError("pbf_gui: " + message)


expect(hasattr(simple, "PositionBasedFluids"),
       "the plugin's source is not available: was it loaded with --plugins?")
output_dir = os.environ.get("PBF_GUI_OUTPUT", os.getcwd())
os.makedirs(output_dir, exist_ok=True)

# Apply, as the GUI does it (pqApplyBehavior::showData): every output port in its preferred view
# (the Diagnostics port's View hint is None: no chart opens), then the camera reset of a view's
# first data. The Domain outline (port 2) is shown with the particles, so the reset frames the
# whole tank, not frame 0's particles.
controller = servermanager.vtkSMParaViewPipelineControllerWithRendering()


def apply(source, view):
    views_before = len(servermanager.ProxyManager().GetProxiesInGroup("views"))
    for port in range(source.SMProxy.GetNumberOfOutputPorts()):
        controller.ShowInPreferredView(source.SMProxy, port, view.SMProxy)
    simple.ResetCamera(view)
    simple.Render(view)
    views = len(servermanager.ProxyManager().GetProxiesInGroup("views"))
    expect(views == views_before, "Apply opened %d more views" % (views - views_before))


def expect_tank_in_view(view, tank, when):
    off = corners_off_view(view, tank.GetBounds())
    expect(not off, "%s: tank corners off the view (corner, pixel): %s" % (when, off))


# Each preset as a new user sees it: Apply, Play to the last frame; the whole tank in
# view throughout, colors that cover the last frame's speeds, spheres that follow the spacing.
# 0.04 m and PBF_GUI_FRAMES frames keep this to seconds a preset; the screenshots are
# Plugin/README.md's.
view = simple.GetActiveViewOrCreate("RenderView")
view.ViewSize = [800, 450]
scene = simple.GetAnimationScene()
keeper = simple.GetTimeKeeper()
for preset in ("dam_break", "double_dam_break", "blob", "stream", "marin_dam_break"):
    fluid = simple.PositionBasedFluids(Preset=preset, ParticleSpacing=0.04,
                                       NumberOfFrames=int(os.environ.get("PBF_GUI_FRAMES", 24)))
    apply(fluid, view)
    tank = fluid.GetClientSideObject().GetOutputDataObject(2)
    expect(tank.GetNumberOfLines() == 12, "%s: the Domain output has %d lines"
           % (preset, tank.GetNumberOfLines()))
    expect_tank_in_view(view, tank, preset + " frame 0")
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = keeper.TimestepValues[-1]
    simple.Render(view)
    expect_tank_in_view(view, tank, preset + " last frame")
    last = fluid.GetClientSideObject().GetOutputDataObject(0)
    count = last.GetNumberOfPoints()  # the live output changes with the spacing below
    speeds = numpy.linalg.norm(
        numpy_support.vtk_to_numpy(last.GetPointData().GetArray("velocity")), axis=1)
    lut = simple.GetColorTransferFunction("velocity")
    low, high = lut.RGBPoints[0], lut.RGBPoints[-4]
    # ParaView stores the range it grew to; 1e-6 relative is the rounding of that range.
    expect(low <= speeds.min() + 1e-6 and high >= speeds.max() * (1 - 1e-6),
           "%s: the color map runs %g..%g; the last frame's speeds %g..%g"
           % (preset, low, high, speeds.min(), speeds.max()))
    simple.SaveScreenshot(os.path.join(os.environ.get("PBF_GUI_OUTPUT", os.getcwd()),
                                       "pbf_gui_%s.png" % preset), view,
                          ImageResolution=[800, 450])
    fluid.ParticleSpacing = 0.05
    simple.Render(view)
    radius = simple.GetDisplayProperties(fluid, view).GaussianRadius
    expect(abs(radius - 0.025) <= 0.1 * 0.025,
           "%s: spacing 0.05 gave a Point Gaussian radius of %g" % (preset, radius))
    simple.Delete(fluid)
    del fluid
    print("pbf_gui: %s: tank in view at frames 0 and last, %d particles, speeds up to %.2f m/s"
          % (preset, count, speeds.max()))

# The STL example (Data/Examples/dam_break_pillar.json reads pillar.stl): the Domain output draws
# the pillar with the tank, the surge flows around it, no particle centre is inside it.
example = os.path.join(os.environ["PBF_SOURCE_DIR"], "Data", "Examples", "dam_break_pillar.json")
fluid = simple.PositionBasedFluids(SceneFile=example, ParticleSpacing=0.04,
                                   NumberOfFrames=int(os.environ.get("PBF_GUI_FRAMES", 24)))
apply(fluid, view)
domain = fluid.GetClientSideObject().GetOutputDataObject(2)
expect(domain.GetNumberOfLines() == 12 and domain.GetNumberOfPolys() > 0,
       "the example's Domain output has %d lines and %d polygons (the tank and the pillar)"
       % (domain.GetNumberOfLines(), domain.GetNumberOfPolys()))
expect_tank_in_view(view, domain, "the STL example, frame 0")
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = keeper.TimestepValues[-1]
simple.Render(view)
last = numpy_support.vtk_to_numpy(
    fluid.GetClientSideObject().GetOutputDataObject(0).GetPoints().GetData())
below = last[:, 1] < 0.5  # the pillar: radius 0.08 about x = 1.0, z = 0.3, 24 facets
axis = numpy.hypot(last[below, 0] - 1.0, last[below, 2] - 0.3)
expect(axis.min() >= 0.08 * numpy.cos(numpy.pi / 24),
       "the STL example: a particle %.4f m from the pillar's axis" % axis.min())
expect((axis < 0.08 + 2 * 0.04).sum() > 10,
       "the STL example: the surge has not reached the pillar (%d particles by it)"
       % (axis < 0.16).sum())
simple.SaveScreenshot(os.path.join(output_dir, "pbf_gui_dam_break_pillar.png"), view,
                      ImageResolution=[800, 450])
print("pbf_gui: the STL example: %d particles by the pillar, the closest %.4f m from its axis"
      % ((axis < 0.16).sum(), axis.min()))
simple.Delete(fluid)
del fluid

# The fluid's surface (port 3, GenerateSurface): the dam break's last frame shown as a surface
# colored by |velocity| instead of particles. It must cover the fluid's part of the view (the
# pixels that change when it is hidden) in many colors, and be lit by its Normals.
fluid = simple.PositionBasedFluids(ParticleSpacing=0.04, GenerateSurface=1,
                                   NumberOfFrames=int(os.environ.get("PBF_GUI_FRAMES", 24)))
apply(fluid, view)
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = keeper.TimestepValues[-1]
simple.Hide(fluid, view)
surface = simple.Show(simple.OutputPort(fluid, 3), view)
simple.ColorBy(surface, ("POINTS", "velocity", "Magnitude"))
view.CameraPosition = [0.8, 0.9, 2.6]
view.CameraFocalPoint = [0.8, 0.2, 0.3]
view.CameraViewUp = [0.0, 1.0, 0.0]
simple.Render(view)
mesh = fluid.GetClientSideObject().GetOutputDataObject(3)
expect(mesh.GetNumberOfPolys() > 1000 and mesh.GetPointData().GetNormals() is not None,
       "the surface has %d triangles, normals %s" % (mesh.GetNumberOfPolys(),
                                                     mesh.GetPointData().GetNormals()))
surface_shot = os.path.join(output_dir, "pbf_gui_dam_break_surface.png")
simple.SaveScreenshot(surface_shot, view, ImageResolution=[800, 450])
simple.Hide(simple.OutputPort(fluid, 3), view)
bare_shot = os.path.join(output_dir, "pbf_gui_dam_break_no_surface.png")
simple.SaveScreenshot(bare_shot, view, ImageResolution=[800, 450])
with_surface, bare = read_png(surface_shot), read_png(bare_shot)
changed = numpy.any(with_surface != bare, axis=2)
shades = {tuple(c // 16) for c in with_surface[changed]}
expect(changed.mean() > 0.02, "only %.2f%% of the view shows the surface" % (100 * changed.mean()))
expect(len(shades) >= 8, "the surface shows only %d distinct colors" % len(shades))
print("pbf_gui: the surface at the last frame: %d triangles, %.1f%% of the view in %d colors"
      % (mesh.GetNumberOfPolys(), 100 * changed.mean(), len(shades)))
simple.Delete(fluid)
del fluid

source = simple.PositionBasedFluids()
frames = os.environ.get("PBF_GUI_FRAMES")
if frames:
    source.NumberOfFrames = int(frames)
view = simple.GetActiveViewOrCreate("RenderView")
view.ViewSize = [800, 450]
display = simple.Show(source, view)
simple.Render(view)

# What Apply with nothing else set gives: particles, colored by |velocity|.
expect(display.Representation in ("Point Gaussian", "Points"),
       "shown as %s, not as particles" % display.Representation)
expect(list(display.ColorArrayName) == ["POINTS", "velocity"],
       "colored by %s, not by velocity" % list(display.ColorArrayName))
lut = simple.GetColorTransferFunction("velocity")
expect(lut.VectorMode == "Magnitude", "velocity is colored by its %s" % lut.VectorMode)
# The plugin's display defaults (Plugin/vtkPBFDisplayDefaults.h): touching spheres, and a color
# map that follows the speeds as they grow from rest.
expect(display.GaussianRadius == 0.5 * source.ParticleSpacing,
       "Point Gaussian radius %g, expected half the spacing" % display.GaussianRadius)
expect(lut.AutomaticRescaleRangeMode == "Grow and update every timestep",
       "the velocity color map rescales %r" % lut.AutomaticRescaleRangeMode)

scene = simple.GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
keeper = simple.GetTimeKeeper()
steps = list(keeper.TimestepValues)
expect(len(steps) == source.NumberOfFrames + 1,
       "the animation has %d time steps for %d frames" % (len(steps), source.NumberOfFrames))
scene.Play()
expect(keeper.Time == steps[-1], "Play stopped at t = %g, not at the last frame %g"
       % (keeper.Time, steps[-1]))
data = source.GetClientSideObject().GetOutputDataObject(0)
frame = int(data.GetFieldData().GetArray("Frame").GetTuple1(0))
expect(frame == source.NumberOfFrames, "the view shows frame %d, not the last (%d)"
       % (frame, source.NumberOfFrames))

# A side view of the tank (gravity -y, x 0..1.6, y 0..0.8, z 0..0.6), as the main job uses.
view.CameraPosition = [0.8, 0.55, 3.2]
view.CameraFocalPoint = [0.8, 0.3, 0.3]
view.CameraViewUp = [0.0, 1.0, 0.0]
view.CameraParallelProjection = 0
simple.Render(view)
shot = os.path.join(output_dir, "pbf_gui_last_frame.png")
simple.SaveScreenshot(shot, view, ImageResolution=[800, 450])
simple.Hide(source, view)
empty = os.path.join(output_dir, "pbf_gui_empty.png")
simple.SaveScreenshot(empty, view, ImageResolution=[800, 450])
simple.Show(source, view)

# Particles are the pixels that change when the source is hidden. The background is whatever the
# palette makes it; the comparison needs no assumption about it.
with_fluid, without = read_png(shot), read_png(empty)
changed = numpy.any(with_fluid != without, axis=2)
fraction = changed.mean()
# The collapsed dam break covers the tank floor: several % of this view. 0.5% is a floor that only
# an empty or nearly empty view stays under.
expect(fraction > 0.005, "only %.3f%% of the screenshot shows particles" % (100 * fraction))
colors = {tuple(c // 16) for c in with_fluid[changed]}
expect(len(colors) >= 8, "the particles show only %d distinct colors: not colored by |velocity|"
       % len(colors))
# Scrubbing back: frame 13 resumes from the checkpoint of frame 10, one of those taken on Play.
scene.AnimationTime = steps[13]
data = source.GetClientSideObject().GetOutputDataObject(0)
resumed = data.GetFieldData().GetAbstractArray("ResumedFrom").GetValue(0)
stepped = int(data.GetFieldData().GetArray("RequestSteps").GetTuple1(0))
# The steps from frame 10's checkpoint to frame 13: whatever the automatic stepping chose, no
# more than the frame's own step count says.
reached = int(data.GetFieldData().GetArray("StepCount").GetTuple1(0))
start = int(data.GetFieldData().GetArray("ResumedFromStep").GetTuple1(0))
expect(int(data.GetFieldData().GetArray("Frame").GetTuple1(0)) == 13 and resumed == "checkpoint"
       and stepped == reached - start and stepped >= 3,
       "going back to frame 13 resumed from %s at step %d with %d steps to step %d"
       % (resumed, start, stepped, reached))

# Display-only changes do not re-execute the simulation.
executions = []
observer = source.GetClientSideObject().AddObserver("EndEvent", lambda *args: executions.append(1))
display.Opacity = 0.5
display.GaussianRadius = 0.4 * source.ParticleSpacing
simple.Render(view)
display.Opacity = 1.0
display.GaussianRadius = 0.5 * source.ParticleSpacing
simple.Render(view)
source.GetClientSideObject().RemoveObserver(observer)
expect(not executions, "changing the display re-executed the simulation %d times" % len(executions))

# Scenes: a preset, and the same scene through SceneFile (the property the file dialog sets).
data_dir = os.environ.get("PBF_DATA_DIR")
expect(data_dir, "PBF_DATA_DIR is not set")
by_preset = simple.PositionBasedFluids(Preset="blob")
by_file = simple.PositionBasedFluids(SceneFile=os.path.join(data_dir, "blob.json"))
counts = []
for scene_source in (by_preset, by_file):
    scene_source.UpdatePipeline(0.0)
    scene_data = scene_source.GetClientSideObject().GetOutputDataObject(0)
    name = scene_data.GetFieldData().GetAbstractArray("Scene").GetValue(0)
    expect(name == "blob", "the scene ran is %r, not blob" % name)
    counts.append(scene_data.GetNumberOfPoints())
    simple.Delete(scene_source)
expect(counts[0] == counts[1] and counts[0] > 1000,
       "the blob preset has %d particles, its file %d" % tuple(counts))

# The diagnostics in a Line Chart View: a row per frame played, the density errors against Time.
table = source.GetClientSideObject().GetOutputDataObject(1)
expect(table.GetNumberOfRows() == len(steps), "the diagnostics hold %d rows for %d frames"
       % (table.GetNumberOfRows(), len(steps)))
chart = simple.CreateView("XYChartView")
chart.ViewSize = [800, 450]
simple.AssignViewToLayout(view=chart, layout=simple.GetLayout(view), hint=0)
plot = simple.Show(simple.OutputPort(source, 1), chart)
expect(plot.XArrayName == "Time" and not plot.UseIndexForXAxis,
       "the diagnostics are plotted against %s" % ("the row index" if plot.UseIndexForXAxis
                                                   else plot.XArrayName))
expect(sorted(plot.SeriesVisibility) == ["AverageDensityError", "MaxDensityError"],
       "the chart shows %s, not the density errors" % list(plot.SeriesVisibility))
simple.Render(chart)
lines = os.path.join(output_dir, "pbf_gui_diagnostics.png")
simple.SaveScreenshot(lines, chart, ImageResolution=[800, 450])
simple.Hide(simple.OutputPort(source, 1), chart)
simple.Render(chart)
axes = os.path.join(output_dir, "pbf_gui_diagnostics_empty.png")
simple.SaveScreenshot(axes, chart, ImageResolution=[800, 450])
# The plotted lines are the pixels that change when the series are hidden, and they are colored
# (the series colors), not the axes' gray or black.
with_lines, without_lines = read_png(lines), read_png(axes)
changed = numpy.any(with_lines != without_lines, axis=2)
pixels = with_lines[changed]
colored = pixels[(pixels.max(axis=1) - pixels.min(axis=1)) > 60]
columns = numpy.unique(numpy.nonzero(changed)[1])
expect(len(colored) > 200 and len(columns) > 300,
       "the chart shows %d colored line pixels over %d columns: no plotted line"
       % (len(colored), len(columns)))

# The radius follows the spacing: at another spacing the spheres touch again;
# a radius the user set stays. (Last: it recomputes the source, and the diagnostics above count
# the frames played.)
source.ParticleSpacing = 0.08
simple.Render(view)
expect(display.GaussianRadius == 0.04,
       "spacing 0.08: the Point Gaussian radius stayed %g" % display.GaussianRadius)
display.GaussianRadius = 0.03
source.ParticleSpacing = 0.05
simple.Render(view)
expect(display.GaussianRadius == 0.03,
       "a radius the user set was replaced by %g" % display.GaussianRadius)

# The color map starts again with another scene, from that scene's speed scale (SceneSpeed):
# the dam break's range, grown over the whole animation, is not kept for the blob.
grown = lut.RGBPoints[-4]
source.Preset = "blob"
simple.Render(view)
blob = source.GetClientSideObject().GetOutputDataObject(0)
speeds = numpy.linalg.norm(numpy_support.vtk_to_numpy(blob.GetPointData().GetArray("velocity")), axis=1)
blob_scale = blob.GetFieldData().GetArray("SceneSpeed").GetTuple1(0)
top = lut.RGBPoints[-4]
wanted = max(blob_scale, speeds.max())
expect(blob_scale != grown and abs(top - wanted) <= 1e-6 * wanted,
       "after the preset change the color map runs to %g (the blob's speed scale %g, its fastest "
       "%g; the dam break's range %g)" % (top, blob_scale, speeds.max(), grown))

print("pbf_gui: frame %d of %d, %.1f%% of the view is particles in %d colors; saved %s; "
      "diagnostics: %d rows, %d line pixels" % (frame, source.NumberOfFrames, 100 * fraction,
                                                len(colors), shot, table.GetNumberOfRows(),
                                                len(colored)))
