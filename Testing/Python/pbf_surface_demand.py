"""The Surface output is made when something asks for it, and only then (GenerateSurface off).

The dam break at 4 cm in a render view:
- the particles shown alone through six frames, and the source's UpdatePipeline: port 3 is never
  made (no time, no triangles);
- Show(OutputPort(fluid, 3)): the surface of the view's frame, on screen (its pixels), made
  without the particles' output executing again;
- both shown: the surface follows every frame shown;
- the surface hidden again: it stays at the last frame it was shown at while the particles go on.
Prints the wall time of a frame with and without the surface shown (Performance.md)."""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import servermanager, simple  # noqa: E402
from pbf_images import source_pixels  # noqa: E402

T.load_plugin(globals())
expect = T.expect

INTERVAL = 1.0 / 30.0
fluid = PositionBasedFluids(ParticleSpacing=0.04, NumberOfFrames=12,  # noqa: F821
                            FrameInterval=INTERVAL)
expect(fluid.SMProxy.GetProperty("GenerateSurface").GetElement(0) == 0,
       "GenerateSurface is on by default")
algorithm = fluid.GetClientSideObject()
view = simple.CreateRenderView()
view.ViewSize = [400, 300]
simple.Show(fluid, view)


def surface_time():
    info = algorithm.GetOutputDataObject(3).GetInformation()
    key = algorithm.GetOutputDataObject(3).DATA_TIME_STEP()
    return info.Get(key) if info.Has(key) else None


def show_frame(f):
    """Renders frame f; returns the wall time in ms."""
    start = time.perf_counter()
    view.ViewTime = f * INTERVAL
    simple.Render(view)
    return 1e3 * (time.perf_counter() - start)


# The particles alone: the surface is never made.
without = [show_frame(f) for f in range(1, 7)]
fluid.UpdatePipeline(6 * INTERVAL)
expect(algorithm.GetOutputDataObject(0).GetNumberOfPoints() > 0, "no particles")
expect(surface_time() is None and algorithm.GetOutputDataObject(3).GetNumberOfCells() == 0,
       "the surface was made with nobody asking for it (time %r, %d cells)"
       % (surface_time(), algorithm.GetOutputDataObject(3).GetNumberOfCells()))

# Show(OutputPort(fluid, 3)): the view's frame, made alone (the particles do not execute again).
particles_made = algorithm.GetOutputDataObject(0).GetMTime()
surface = simple.Show(simple.OutputPort(fluid, 3), view)
simple.Render(view)
made = algorithm.GetOutputDataObject(3)
expect(made.GetNumberOfCells() > 100, "the surface shown has %d triangles" % made.GetNumberOfCells())
expect(surface_time() is not None and abs(surface_time() - 6 * INTERVAL) < 1e-12,
       "the surface shown is of time %r, the view's is %r" % (surface_time(), 6 * INTERVAL))
expect(algorithm.GetOutputDataObject(0).GetMTime() == particles_made,
       "showing the surface made the particles again")
shot, pixels = source_pixels(view, simple.OutputPort(fluid, 3),
                             os.path.join(T.output_directory(), "pbf_surface_demand.png"))
expect(pixels.mean() > 0.01, "the surface covers %.2f %% of the view" % (100 * pixels.mean()))
print("shown: %d triangles at t = %g s on %.1f %% of the view"
      % (made.GetNumberOfCells(), surface_time(), 100 * pixels.mean()))

# Both shown: the surface follows every frame.
with_surface = []
for f in range(7, 13):
    with_surface.append(show_frame(f))
    expect(abs(surface_time() - f * INTERVAL) < 1e-12,
           "frame %d: the surface shown is of time %r" % (f, surface_time()))

# Hidden again: not made while the particles go on.
simple.Hide(simple.OutputPort(fluid, 3), view)
for f in range(0, 6):
    show_frame(f)
expect(abs(surface_time() - 12 * INTERVAL) < 1e-12,
       "the hidden surface was made again (time %r)" % surface_time())
# A Fetch of port 3 (as a script reads it) asks for it too: the frame asked, with triangles.
fetched = servermanager.Fetch(fluid, idx=3)
fetched_time = fetched.GetInformation().Get(fetched.DATA_TIME_STEP()) \
    if fetched.GetInformation().Has(fetched.DATA_TIME_STEP()) else None
expect(fetched.GetNumberOfCells() > 100,
       "a Fetch of the Surface output gave %d triangles" % fetched.GetNumberOfCells())
print("fetched: %d triangles (time %r)" % (fetched.GetNumberOfCells(), fetched_time))
print("ms per frame, median of six: particles alone %.0f, with the surface %.0f"
      % (sorted(without)[3], sorted(with_surface)[3]))
T.passed("pbf_surface_demand")
