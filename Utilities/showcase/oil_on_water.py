"""Several liquids: a column of oil collapses onto a layer of water (Data/Examples/oil_on_water.json)
and spreads over it. Renders the frame at `at` seconds, the particles colored by their liquid
(the point array "liquid", an index into the field data's LiquidNames), and prints how far the
oil reached and how much of it lies below the water's surface.

    xvfb-run -a env PBF_PLUGIN=build/lib/paraview-5.11/plugins/PositionBasedFluids/PositionBasedFluids.so \\
      pvbatch Utilities/showcase/oil_on_water.py [spacing] [at] [folder]

The defaults (2 cm to 1.5 s on the CPU, a few minutes here) draw Documentation/images/oil_on_water.png.
"""
import os
import sys

import numpy
from paraview import simple
from vtk.util import numpy_support

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = os.path.join(ROOT, "Data", "Examples", "oil_on_water.json")


def main(spacing, at, folder):
    simple.LoadPlugin(os.environ["PBF_PLUGIN"], remote=False, ns=globals())
    interval = 1.0 / 60.0
    frames = int(round(at / interval)) + 1
    source = PositionBasedFluids(SceneFile=SCENE, ParticleSpacing=spacing,  # noqa: F821
                                 NumberOfFrames=frames, Backend="CPU (OpenMP)")
    source.UpdatePipeline(at)
    data = source.GetClientSideObject().GetOutputDataObject(0)
    points = numpy_support.vtk_to_numpy(data.GetPoints().GetData())
    liquid = numpy_support.vtk_to_numpy(data.GetPointData().GetArray("liquid"))
    density = numpy_support.vtk_to_numpy(data.GetPointData().GetArray("density"))
    oil = points[liquid == 1]
    water = points[liquid == 0]
    surface = numpy.percentile(water[:, 1], 95)
    print("at %.2f s: oil reached x = %.2f m; %.1f %% of the oil below the water's surface "
          "(%.3f m); median densities %.1f (water) and %.1f (oil) kg/m^3"
          % (at, oil[:, 0].max(), 100 * numpy.mean(oil[:, 1] < surface - spacing), surface,
             numpy.median(density[liquid == 0]), numpy.median(density[liquid == 1])))

    view = simple.CreateView("RenderView")
    view.ViewSize = [900, 480]
    view.OrientationAxesVisibility = 0
    view.ViewTime = at
    particles = simple.Show(simple.OutputPort(source, 0), view)
    particles.SetRepresentationType("Points")
    particles.PointSize = 4
    simple.ColorBy(particles, ("POINTS", "liquid"))
    lut = simple.GetColorTransferFunction("liquid")
    lut.InterpretValuesAsCategories = 1
    lut.Annotations = ["0", "water", "1", "oil"]
    lut.IndexedColors = [0.2, 0.45, 0.85, 0.95, 0.7, 0.1]
    particles.SetScalarBarVisibility(view, True)
    simple.Show(simple.OutputPort(source, 2), view)
    simple.Render(view)  # the first render frames everything; the camera is set after it
    view.CameraPosition = [0.5, 0.95, 2.1]
    view.CameraFocalPoint = [0.5, 0.28, 0.2]
    view.CameraViewUp = [0, 1, 0]
    simple.Render(view)
    simple.SaveScreenshot(os.path.join(folder, "oil_on_water.png"), view,
                          ImageResolution=[900, 480])


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 0.02,
         float(sys.argv[2]) if len(sys.argv) > 2 else 1.5,
         sys.argv[3] if len(sys.argv) > 3 else os.path.join(ROOT, "Documentation", "images"))
