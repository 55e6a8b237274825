"""The checks of the clicked Surface test (pbf_gui_surface.xml.in): ParaView runs this with
--script at startup, before its event player replays the clicks (Apply, then the eye of the
Surface output), so it only watches. When Play starts, the eye's click has shown port 3: its
representation is visible, its data holds the shown frame's triangles, and they are on screen
(pixels that change when it is hidden). When Play ends, the surface is the last frame's.
GenerateSurface stays off throughout.

Prints one line per check; the last says the test passed. A failed check prints
"pbf_gui_surface: FAILED" (the test's failure pattern). Screenshots go to PBF_GUI_OUTPUT as
pbf_gui_surface_{start,end}.png."""
import os
import sys

from paraview import simple

sys.path.insert(0, os.path.join(os.environ["PBF_SOURCE_DIR"], "Testing", "Python"))
from pbf_images import source_pixels  # noqa: E402

output_dir = os.environ.get("PBF_GUI_OUTPUT", os.getcwd())
os.makedirs(output_dir, exist_ok=True)
state = {"checked": 0}


def fail(message):
    print("pbf_gui_surface: FAILED: " + message, flush=True)


def simulation():
    sources = [s for s in simple.GetSources().values()
               if s.GetXMLName() == "PBFSimulationSource"]
    return sources[0] if len(sources) == 1 else None


def check(when):
    source, view = simulation(), simple.GetActiveView()
    if source is None or view is None:
        fail("%s: no Position Based Fluids source or no active view" % when)
        return
    if source.SMProxy.GetProperty("GenerateSurface").GetElement(0) != 0:
        fail("%s: GenerateSurface is on; the test shows the surface without it" % when)
        return
    port = simple.OutputPort(source, 3)
    display = simple.GetDisplayProperties(port, view)
    if display is None or not display.Visibility:
        fail("%s: the Surface output is not shown after its eye was clicked" % when)
        return
    surface = source.GetClientSideObject().GetOutputDataObject(3)
    info = surface.GetInformation()
    shown = simple.GetTimeKeeper().Time
    made = info.Get(surface.DATA_TIME_STEP()) if info.Has(surface.DATA_TIME_STEP()) else None
    triangles = surface.GetNumberOfCells()
    if triangles <= 100 or made is None or abs(made - shown) > 1e-9:
        fail("%s: the Surface output holds %d triangles of time %r; the view shows t = %g"
             % (when, triangles, made, shown))
        return
    _, pixels = source_pixels(view, port, os.path.join(output_dir, "pbf_gui_surface_%s.png" % when))
    if pixels.mean() < 0.01:
        fail("%s: the surface's %d triangles cover %.2f %% of the view"
             % (when, triangles, 100 * pixels.mean()))
        return
    state["checked"] += 1
    print("pbf_gui_surface: %s: %d triangles at t = %g s on %.1f %% of the view"
          % (when, triangles, shown, 100 * pixels.mean()), flush=True)
    if state["checked"] == 2:
        print("pbf_gui_surface: passed", flush=True)


scene = simple.GetAnimationScene().GetClientSideObject()
scene.AddObserver("StartEvent", lambda *args: check("start"))
scene.AddObserver("EndEvent", lambda *args: check("end"))
print("pbf_gui_surface: watching", flush=True)
