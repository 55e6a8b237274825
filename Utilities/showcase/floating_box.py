"""The showcase: a box of half the water's density rides the dam break
(Data/Examples/floating_box_dam_break.json). Renders the frame at `at` seconds (particles and the
box colored by pressure, the box from the Domain output) and plots the fluid's force on the box
from the Diagnostics table, with the box's height from the particles' field data.

    xvfb-run -a env PBF_PLUGIN=build/lib/paraview-5.11/plugins/PositionBasedFluids/PositionBasedFluids.so \\
      pvbatch Utilities/showcase/floating_box.py [spacing] [until] [at] [folder]

The defaults (2 cm to 2 s on the CPU, a few minutes here) draw Documentation/images/floating_box.png
and floating_box_force.png.
"""
import os
import sys

import numpy
from paraview import simple
from vtk.util import numpy_support

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = os.path.join(ROOT, "Data", "Examples", "floating_box_dam_break.json")


def column(table, name):
    return numpy_support.vtk_to_numpy(table.GetColumnByName(name))


def main(spacing, until, at, folder):
    simple.LoadPlugin(os.environ["PBF_PLUGIN"], remote=False, ns=globals())
    interval = 1.0 / 60.0
    frames = int(round(until / interval))
    source = PositionBasedFluids(SceneFile=SCENE, ParticleSpacing=spacing,  # noqa: F821
                                 NumberOfFrames=frames, Backend="CPU (OpenMP)")
    # The force curve: the Diagnostics rows of every frame, asked for at the last frame.
    source.UpdatePipeline(until)
    table = source.GetClientSideObject().GetOutputDataObject(1)
    t = column(table, "Time")
    force = column(table, "Force box")

    # The frame: particles and the box colored by pressure.
    view = simple.CreateView("RenderView")
    view.ViewSize = [900, 480]
    view.OrientationAxesVisibility = 0
    view.ViewTime = at
    particles = simple.Show(simple.OutputPort(source, 0), view)
    particles.SetRepresentationType("Points")
    particles.PointSize = 4
    simple.ColorBy(particles, ("POINTS", "pressure"))
    domain = simple.Show(simple.OutputPort(source, 2), view)
    simple.ColorBy(domain, ("POINTS", "pressure"))
    # One scale for the particles and the box: 0 to rho g times the column's height [Pa].
    lut = simple.GetColorTransferFunction("pressure")
    lut.AutomaticRescaleRangeMode = "Never"
    lut.RescaleTransferFunction(0.0, 6000.0)
    particles.SetScalarBarVisibility(view, True)
    simple.Render(view)  # the first render frames everything; the camera is set after it
    view.CameraPosition = [0.95, 0.9, 1.75]
    view.CameraFocalPoint = [0.95, 0.15, 0.3]
    view.CameraViewUp = [0, 1, 0]
    simple.Render(view)
    simple.SaveScreenshot(os.path.join(folder, "floating_box.png"), view,
                          ImageResolution=[900, 480])

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axis = plt.subplots(figsize=(8, 3.2))
    weight = 500.0 * 0.12 ** 3 * 9.81
    axis.plot(t, force[:, 0], lw=1.0, label="Force box x")
    axis.plot(t, force[:, 1], lw=1.0, label="Force box y")
    axis.axhline(weight, color="black", lw=0.8, ls="--", label="the box's weight (%.2f N)" % weight)
    axis.axvline(at, color="grey", lw=0.8, ls=":")
    axis.set_xlabel("t [s]")
    axis.set_ylabel("fluid force on the box [N]")
    axis.set_xlim(0, until)
    axis.grid(alpha=0.3)
    axis.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(folder, "floating_box_force.png"), dpi=80)
    with open(os.path.join(folder, "floating_box_force.csv"), "w") as out:
        out.write("t,Fx,Fy,Fz\n")
        for k in range(len(t)):
            out.write("%.5f,%.5f,%.5f,%.5f\n" % (t[k], force[k, 0], force[k, 1], force[k, 2]))
    print("peak horizontal force %.2f N at %.3f s, peak vertical %.2f N (weight %.2f N)"
          % (numpy.nanmax(force[:, 0]), t[numpy.nanargmax(force[:, 0])],
             numpy.nanmax(force[:, 1]), weight))


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 0.02,
         float(sys.argv[2]) if len(sys.argv) > 2 else 2.0,
         float(sys.argv[3]) if len(sys.argv) > 3 else 0.4,
         sys.argv[4] if len(sys.argv) > 4 else os.path.join(ROOT, "Documentation", "images"))
