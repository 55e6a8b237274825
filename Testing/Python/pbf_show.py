"""Scripting as the README shows: Show(fluid) in pvbatch, the animation set to a
later time, Render. The plugin's display defaults (Plugin/vtkPBFDisplayDefaults.h) hold outside
the GUI too: spheres of half the spacing, a velocity color map that grows as the fluid speeds up,
a radius that follows the spacing, and the Domain outline (port 2) that frames the tank.

Run under Xvfb (pbf_xvfb.py): pvbatch --dr pbf_show.py --plugin PositionBasedFluids.so."""
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import simple  # noqa: E402
from pbf_images import corners_off_view, source_pixels  # noqa: E402
from vtkmodules.util import numpy_support  # noqa: E402

T.load_plugin(globals())
expect = T.expect
output_dir = T.output_directory()


# The README's script, at the spacing of the tests: 36 frames (0.6 s) of the default dam break.
fluid = PositionBasedFluids(ParticleSpacing=0.04, NumberOfFrames=36)  # noqa: F821
view = simple.GetActiveViewOrCreate("RenderView")
display = simple.Show(fluid, view)
expect(display.Representation == "Point Gaussian", "shown as %s" % display.Representation)
expect(display.GaussianRadius == 0.02,
       "Point Gaussian radius %g in pvbatch, not half the spacing 0.04" % display.GaussianRadius)
lut = simple.GetColorTransferFunction("velocity")
expect(lut.AutomaticRescaleRangeMode == "Grow and update every timestep",
       "the velocity color map rescales %r in pvbatch" % lut.AutomaticRescaleRangeMode)
simple.Render(view)

scene = simple.GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = 0.6
simple.Render(view)
data = fluid.GetClientSideObject().GetOutputDataObject(0)
frame = int(data.GetFieldData().GetArray("Frame").GetTuple1(0))
expect(frame == 36, "the view shows frame %d at t = 0.6 s, not 36" % frame)
speeds = numpy.linalg.norm(
    numpy_support.vtk_to_numpy(data.GetPointData().GetArray("velocity")), axis=1)
low, high = lut.RGBPoints[0], lut.RGBPoints[-4]
# The map grew over the frames played: it covers this frame's speeds (up to float rounding of the
# range ParaView stores), and is not frame 0's degenerate range of a fluid at rest.
expect(low <= speeds.min() + 1e-6 and high >= speeds.max() * (1 - 1e-6) and high > 1.0,
       "the color map runs %g..%g; the frame's speeds %g..%g" % (low, high, speeds.min(),
                                                                 speeds.max()))

# Particles are the pixels that change when the fluid is hidden; several colors, not one.
shot, changed = source_pixels(view, fluid, os.path.join(output_dir, "pbf_show.png"), [800, 450])
fraction = changed.mean()
colors = {tuple(c // 16) for c in shot[changed]}
# The collapsing column and the surge cover several % of the view; under 1 % means dots.
expect(fraction >= 0.01, "the particles cover %.2f%% of the view" % (100 * fraction))
expect(len(colors) >= 8, "the particles show %d colors, not a velocity color map" % len(colors))

# The radius follows the spacing; a radius the user set stays.
fluid.ParticleSpacing = 0.05
simple.Render(view)
expect(display.GaussianRadius == 0.025, "spacing 0.05: radius %g" % display.GaussianRadius)
display.GaussianRadius = 0.01
fluid.ParticleSpacing = 0.04
simple.Render(view)
expect(display.GaussianRadius == 0.01, "the user's radius became %g" % display.GaussianRadius)

# The Domain output: the tank's 12 edges, and with it shown a camera reset frames the whole tank.
outline = simple.Show(simple.OutputPort(fluid, 2), view)
simple.ResetCamera(view)
simple.Render(view)
tank = fluid.GetClientSideObject().GetOutputDataObject(2)
# The outline's points are float32: the bounds agree to its rounding (1e-7 m at 1.6 m).
expect(tank.GetNumberOfLines() == 12 and numpy.allclose(tank.GetBounds(),
                                                        (0.0, 1.6, 0.0, 0.8, 0.0, 0.6), atol=1e-6),
       "the Domain output has %d lines, bounds %s" % (tank.GetNumberOfLines(), tank.GetBounds()))
off = corners_off_view(view, tank.GetBounds())
expect(not off, "tank corners off the view (corner, pixel): %s" % off)
print("pbf_show: frame %d, %.1f%% of the view in %d colors, color map %.3g..%.3g m/s"
      % (frame, 100 * fraction, len(colors), low, high))
T.passed("Show")
