"""The main job: the default dam break with pvbatch, every frame written and rendered.

    xvfb-run -a pvbatch Utilities/dam_break.py --output OUT [--plugin PATH] [--frames N]
        [--spacing S] [--substeps K] [--preset NAME] [--backend NAME] [--size W H]

Writes OUT/dam_break.pvd with one .vtp per frame (ParaView's PVD writer, OUT/dam_break/) and the
solver's diagnostics per frame (density errors, neighbours, iterations and milliseconds per step)
to OUT/dam_break_diagnostics.csv, then reads the time series back and renders
OUT/frames/frame_NNNN.png: a side view of the tank,
particles colored by |velocity| on one color scale for the whole run. Rendering needs an X
server (Debian's VTK has no EGL/OSMesa): wrap the command in xvfb-run -a. --no-render skips it.

The plugin is --plugin PATH, else $PBF_PLUGIN, else the first build folder next to the sources
(build*/ or /tmp/build*/) that holds it. Without --frames and --spacing the run is the plugin's
default: 120 frames of 1/60 s, 0.02 m spacing, about 18000 particles (a few minutes on 2 cores).
"""
import argparse
import glob
import os
import sys
import time

from paraview import simple

PLUGIN_RELATIVE = os.path.join("lib", "paraview-5.11", "plugins", "PositionBasedFluids",
                               "PositionBasedFluids.so")


def parse_arguments():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", required=True, help="output folder (created)")
    parser.add_argument("--plugin", help="PositionBasedFluids.so")
    parser.add_argument("--preset", default="dam_break", help="scene preset (default dam_break)")
    parser.add_argument("--frames", type=int, help="NumberOfFrames (default: the plugin's, 120)")
    parser.add_argument("--spacing", type=float,
                        help="ParticleSpacing [m] (default: the plugin's, 0.02)")
    parser.add_argument("--substeps", type=int,
                        help="fixed time stepping with this many steps per frame (default: automatic)")
    parser.add_argument("--backend", help="Auto, CUDA, CPU (OpenMP) or Serial (default Auto)")
    parser.add_argument("--size", type=int, nargs=2, default=[1280, 720], metavar=("W", "H"),
                        help="PNG size in pixels (default 1280 720)")
    parser.add_argument("--no-render", action="store_true", help="write the data only")
    return parser.parse_args()


def find_plugin(given):
    if given:
        return given
    if os.environ.get("PBF_PLUGIN"):
        return os.environ["PBF_PLUGIN"]
    sources = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    for folder in sorted(glob.glob(os.path.join(sources, "build*"))) + \
            sorted(glob.glob("/tmp/build*")):
        candidate = os.path.join(folder, PLUGIN_RELATIVE)
        if os.path.isfile(candidate):
            return candidate
    sys.exit("dam_break.py: plugin not found; pass --plugin PATH or set PBF_PLUGIN")


def simulate_and_write(args, output, constructors):
    """Runs the simulation frame after frame (each frame steps on from the previous one) and
    writes the time series; returns the series' path and the number of frames written."""
    # Frames are written in order and never revisited: checkpoints would only cost time.
    source = constructors["PositionBasedFluids"](Preset=args.preset, CheckpointInterval=0)
    if args.frames is not None:
        source.NumberOfFrames = args.frames
    if args.spacing is not None:
        source.ParticleSpacing = args.spacing
    if args.substeps is not None:
        source.TimeStepping = "Fixed"
        source.SubstepsPerFrame = args.substeps
    if args.backend is not None:
        source.Backend = args.backend
    source.UpdatePipelineInformation()
    times = list(source.TimestepValues)
    print("dam_break.py: %s, %d frames of %g s, spacing %g m"
          % (args.preset, len(times) - 1, source.FrameInterval, source.ParticleSpacing))

    # The writer asks for the frames in order from 0, so the simulation starts once and steps on
    # from one frame to the next. The algorithm's EndEvent marks each frame done.
    start = time.time()
    algorithm = source.GetClientSideObject()

    reported = set()

    def report(caller, event):
        data = caller.GetOutputDataObject(0)
        frame = data.GetFieldData().GetArray("Frame")
        if frame is not None:
            k = int(frame.GetTuple1(0))
            if (k % 10 == 0 or k == len(times) - 1) and k not in reported:
                reported.add(k)
                print("  frame %4d  t = %.3f s  %d particles  %.1f s elapsed"
                      % (k, k * source.FrameInterval, data.GetNumberOfPoints(),
                         time.time() - start))
                sys.stdout.flush()

    observer = algorithm.AddObserver("EndEvent", report)
    series = os.path.join(output, args.preset + ".pvd")
    # Binary (inline base64), not the default raw appended data: this ParaView's own XML reader
    # (Debian's VTK with expat 2.5.0-1+deb12u5) fails on appended data of more than a few
    # hundred values, so the series would not load back.
    simple.SaveData(series, proxy=source, WriteTimeSteps=1, DataMode="Binary")
    algorithm.RemoveObserver(observer)
    print("dam_break.py: wrote %s (%.1f s)" % (series, time.time() - start))
    # The diagnostics table (output port 1) now holds a row per frame written; asked at the last
    # frame's time so that the writer takes it as it is now, not as it was at time 0.
    diagnostics = os.path.join(output, args.preset + "_diagnostics.csv")
    writer = simple.CreateWriter(diagnostics, simple.OutputPort(source, 1), Precision=9)
    writer.UpdatePipeline(times[-1])
    simple.Delete(writer)
    print("dam_break.py: wrote %s" % diagnostics)
    simple.Delete(source)
    return series, len(times)


def render(series, frames, args, output):
    """Renders every frame of the written series with one color scale for the whole run."""
    reader = simple.PVDReader(FileName=series)
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues)
    reader.UpdatePipeline(times[0])
    first = reader.GetClientSideObject().GetOutputDataObject(0)
    domain = first.GetFieldData().GetArray("Domain").GetTuple(0)
    spacing = first.GetFieldData().GetArray("ParticleSpacing").GetTuple1(0)
    lo, hi = domain[0::2], domain[1::2]
    center = [(a + b) / 2 for a, b in zip(lo, hi)]
    size = [b - a for a, b in zip(lo, hi)]

    view = simple.CreateView("RenderView")
    view.ViewSize = list(args.size)
    view.OrientationAxesVisibility = 0
    view.Background = [0.12, 0.13, 0.16]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass

    display = simple.Show(reader, view)
    display.SetRepresentationType("Point Gaussian")
    # Half the spacing: neighbouring particles touch and the fluid reads as a volume.
    display.GaussianRadius = 0.5 * spacing
    simple.ColorBy(display, ("POINTS", "velocity", "Magnitude"))
    colors = simple.GetColorTransferFunction("velocity")
    colors.ApplyPreset("Turbo", True) or colors.ApplyPreset("Jet", True)
    # One scale for all frames, so that a color means the same speed throughout the movie.
    display.RescaleTransferFunctionToDataRangeOverTime()
    colors.AutomaticRescaleRangeMode = "Never"
    bar = simple.GetScalarBar(colors, view)
    bar.Title = "speed [m/s]"
    bar.ComponentTitle = ""
    bar.RangeLabelFormat = "%.1f"
    bar.Visibility = 1

    # The tank: its edges as an outline.
    tank = simple.Box(XLength=size[0], YLength=size[1], ZLength=size[2], Center=center)
    outline = simple.Show(tank, view)
    outline.SetRepresentationType("Outline")
    outline.AmbientColor = outline.DiffuseColor = [0.8, 0.8, 0.8]

    clock = simple.AnnotateTimeFilter(reader, Format="t = {time:.3f} s")
    simple.Show(clock, view).WindowLocation = "Upper Left Corner"

    # paraview.simple resets the camera on a view's first render: render once, then place it.
    simple.Render(view)
    # Gravity is -y: a side view from +z, a little above the rim, the whole tank in frame.
    view.CameraFocalPoint = [center[0], center[1] - 0.1 * size[1], center[2]]
    view.CameraPosition = [center[0], center[1] + 0.6 * size[1], center[2] + 1.6 * size[0]]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraViewAngle = 30.0

    frames_dir = os.path.join(output, "frames")
    os.makedirs(frames_dir, exist_ok=True)
    for k, t in enumerate(times):
        view.ViewTime = t
        simple.Render(view)
        simple.SaveScreenshot(os.path.join(frames_dir, "frame_%04d.png" % k), view,
                              ImageResolution=list(args.size))
    print("dam_break.py: rendered %d frames into %s" % (len(times), frames_dir))
    if len(times) != frames:
        sys.exit("dam_break.py: the series holds %d frames, %d were written" % (len(times), frames))


def main():
    args = parse_arguments()
    output = os.path.abspath(args.output)
    os.makedirs(output, exist_ok=True)
    plugin = find_plugin(args.plugin)
    # LoadPlugin defines the proxies' constructors in the namespace it is given.
    constructors = globals()
    simple.LoadPlugin(plugin, remote=False, ns=constructors)
    if "PositionBasedFluids" not in constructors:
        sys.exit("dam_break.py: %s does not define the PositionBasedFluids source" % plugin)
    series, frames = simulate_and_write(args, output, constructors)
    if not args.no_render:
        render(series, frames, args, output)


main()
