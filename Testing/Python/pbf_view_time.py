"""paraview.simple's ways to show another time, none of them the animation scene: a source's
UpdatePipeline(t), then a view's ViewTime and Render. The velocity color map must start from the
scene's speed scale (field data SceneSpeed, not frame 0's 0 to 1e-38) and grow with what is
shown, so the last frame's particles cover the view in several hues, not in one saturated color.

Run under Xvfb (pbf_xvfb.py): pvbatch --dr pbf_view_time.py --plugin PositionBasedFluids.so
--output DIR."""
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import simple  # noqa: E402
from pbf_images import hues, source_pixels  # noqa: E402
from vtkmodules.util import numpy_support  # noqa: E402

T.load_plugin(globals())
expect = T.expect
output_dir = T.output_directory()


def speeds_of(fluid):
    data = fluid.GetClientSideObject().GetOutputDataObject(0)
    return numpy.linalg.norm(
        numpy_support.vtk_to_numpy(data.GetPointData().GetArray("velocity")), axis=1)


def color_range():
    lut = simple.GetColorTransferFunction("velocity")
    return lut.RGBPoints[0], lut.RGBPoints[-4]


# 36 frames of 1/60 s: the surge reaches the far wall at 0.6 s.
fluid = PositionBasedFluids(ParticleSpacing=0.04, NumberOfFrames=36)  # noqa: F821
view = simple.CreateView("RenderView")
view.ViewSize = [800, 450]
simple.Show(fluid, view)
simple.Show(simple.OutputPort(fluid, 2), view)
simple.ResetCamera(view)
simple.Render(view)
scene_speed = fluid.GetClientSideObject().GetOutputDataObject(0).GetFieldData() \
    .GetArray("SceneSpeed").GetTuple1(0)
# sqrt(2 g H) of the 0.8 m tank; the stored range rounds to 1e-6 relative.
expect(abs(scene_speed - (2 * 9.81 * 0.8) ** 0.5) <= 1e-6 * scene_speed,
       "SceneSpeed %g, not sqrt(2 g 0.8 m)" % scene_speed)
low, high = color_range()
expect(low == 0.0 and abs(high - scene_speed) <= 1e-6 * scene_speed,
       "after Show at rest the color map runs %g..%g, not 0..SceneSpeed %g"
       % (low, high, scene_speed))

# UpdatePipeline(t) on the source: the map grows to the speeds computed, though nothing is drawn.
fluid.UpdatePipeline(0.3)
low, high = color_range()
fastest = speeds_of(fluid).max()
expect(high >= max(scene_speed, fastest) * (1 - 1e-6),
       "after UpdatePipeline(0.3) the color map runs %g..%g; the frame's fastest is %g m/s"
       % (low, high, fastest))

# view.ViewTime and Render: the last frame drawn in the map that the frames shown grew.
view.ViewTime = 0.6
simple.Render(view)
speeds = speeds_of(fluid)
low, high = color_range()
expect(low <= speeds.min() and high >= speeds.max() * (1 - 1e-6),
       "at ViewTime 0.6 the color map runs %g..%g; the frame's speeds %g..%g"
       % (low, high, speeds.min(), speeds.max()))
shot, changed = source_pixels(view, fluid, os.path.join(output_dir, "pbf_view_time.png"),
                              [800, 450])
seen = hues(shot[changed])
expect(changed.mean() >= 0.01, "the particles cover %.2f%% of the view" % (100 * changed.mean()))
expect(len(seen) >= 3, "the particles show the hues %s (15-degree bins): fewer than three" % seen)
print("pbf_view_time: SceneSpeed %.3f m/s; at ViewTime 0.6 the map runs %.3g..%.3g m/s, the "
      "particles cover %.1f%% of the view in the hues %s" % (scene_speed, low, high,
                                                            100 * changed.mean(), seen))
T.passed("ViewTime")
