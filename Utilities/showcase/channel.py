"""Open boundaries: the shipped channel preset, an inflow of 0.01 m^3/s that runs along the floor
and leaves over the +x end (an outflow). Renders the frame at `at` seconds, the particles colored
by their speed, and prints the particles, those released and those removed.

    xvfb-run -a env PBF_PLUGIN=build/lib/paraview-5.11/plugins/PositionBasedFluids/PositionBasedFluids.so \\
      pvbatch Utilities/showcase/channel.py [spacing] [at] [folder]

The defaults (2 cm to 6 s on the CPU, under a minute here) draw Documentation/images/channel.png.
"""
import os
import sys

from paraview import simple

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main(spacing, at, folder):
    simple.LoadPlugin(os.environ["PBF_PLUGIN"], remote=False, ns=globals())
    interval = 1.0 / 60.0
    frames = int(round(at / interval)) + 1
    source = PositionBasedFluids(Preset="channel", ParticleSpacing=spacing,  # noqa: F821
                                 NumberOfFrames=frames, Backend="CPU (OpenMP)")
    source.UpdatePipeline(at)
    data = source.GetClientSideObject().GetOutputDataObject(0)
    field = data.GetFieldData()
    print("at %.2f s: %d particles, %d released, %d removed through the outflow"
          % (at, data.GetNumberOfPoints(), field.GetArray("ReleasedParticles").GetTuple1(0),
             field.GetArray("RemovedParticles").GetTuple1(0)))

    view = simple.CreateView("RenderView")
    view.ViewSize = [900, 360]
    view.OrientationAxesVisibility = 0
    view.ViewTime = at
    particles = simple.Show(simple.OutputPort(source, 0), view)
    particles.SetRepresentationType("Points")
    particles.PointSize = 4
    simple.ColorBy(particles, ("POINTS", "velocity", "Magnitude"))
    lut = simple.GetColorTransferFunction("velocity")
    lut.AutomaticRescaleRangeMode = "Never"
    lut.RescaleTransferFunction(0.0, 1.5)
    particles.SetScalarBarVisibility(view, True)
    bar = simple.GetScalarBar(lut, view)
    bar.WindowLocation = "Upper Right Corner"
    bar.Title = "|velocity| [m/s]"
    bar.ComponentTitle = ""
    simple.Show(simple.OutputPort(source, 2), view)
    simple.Render(view)  # the first render frames everything; the camera is set after it
    view.CameraPosition = [0.85, 0.6, 1.45]
    view.CameraFocalPoint = [0.8, 0.12, 0.1]
    view.CameraViewUp = [0, 1, 0]
    simple.Render(view)
    simple.SaveScreenshot(os.path.join(folder, "channel.png"), view, ImageResolution=[900, 360])


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 0.02,
         float(sys.argv[2]) if len(sys.argv) > 2 else 6.0,
         sys.argv[3] if len(sys.argv) > 3 else os.path.join(ROOT, "Documentation", "images"))
