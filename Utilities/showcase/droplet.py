"""Surface tension: a cube of liquid without gravity (Data/Examples/droplet.json, sigma 1 N/m)
pulls itself round. Renders the particles at three times side by side (ForceTime pins each copy's
time, Transform moves it), colored by speed, and prints each time's deformation from a sphere
(the largest over the smallest extent through the centre).

    xvfb-run -a env PBF_PLUGIN=build/lib/paraview-5.11/plugins/PositionBasedFluids/PositionBasedFluids.so \\
      pvbatch Utilities/showcase/droplet.py [spacing] [folder]

The defaults (1 cm, 0.6 s on the CPU, under a minute here) draw Documentation/images/droplet.png.
"""
import os
import sys

import numpy
from paraview import simple
from vtk.util import numpy_support

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = os.path.join(ROOT, "Data", "Examples", "droplet.json")
TIMES = [0.0, 0.25, 0.6]


def main(spacing, folder):
    simple.LoadPlugin(os.environ["PBF_PLUGIN"], remote=False, ns=globals())
    interval = 1.0 / 60.0
    frames = int(round(TIMES[-1] / interval)) + 1
    source = PositionBasedFluids(SceneFile=SCENE, ParticleSpacing=spacing,  # noqa: F821
                                 NumberOfFrames=frames, Gravity=[0, 0, 0],
                                 Backend="CPU (OpenMP)")
    view = simple.CreateView("RenderView")
    view.ViewSize = [1200, 420]
    view.OrientationAxesVisibility = 0
    for k, t in enumerate(TIMES):
        source.UpdatePipeline(t)
        data = source.GetClientSideObject().GetOutputDataObject(0)
        points = numpy_support.vtk_to_numpy(data.GetPoints().GetData())
        centre = points.mean(axis=0)
        extents = [numpy.ptp(points[:, a]) for a in range(3)]
        radius = numpy.linalg.norm(points - centre, axis=1)
        print("t = %.2f s: %d particles, extents %.3f %.3f %.3f m, farthest %.3f m from the "
              "centre" % (t, len(points), extents[0], extents[1], extents[2], radius.max()))
        pinned = simple.ForceTime(Input=simple.OutputPort(source, 0), IgnorePipelineTime=1,
                                  ForcedTime=t)
        moved = simple.Transform(Input=pinned)
        moved.Transform.Translate = [0.3 * k, 0, 0]
        shown = simple.Show(moved, view)
        shown.SetRepresentationType("Points")
        shown.PointSize = 5
        simple.ColorBy(shown, ("POINTS", "velocity", "Magnitude"))
        if k == len(TIMES) - 1:
            shown.SetScalarBarVisibility(view, True)
    lut = simple.GetColorTransferFunction("velocity")
    lut.RescaleTransferFunction(0.0, 0.3)
    simple.Render(view)
    view.CameraPosition = [0.5, 0.42, 1.05]
    view.CameraFocalPoint = [0.5, 0.2, 0.2]
    view.CameraViewUp = [0, 1, 0]
    simple.Render(view)
    simple.SaveScreenshot(os.path.join(folder, "droplet.png"), view, ImageResolution=[1200, 420])


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 0.01,
         sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "Documentation", "images"))
