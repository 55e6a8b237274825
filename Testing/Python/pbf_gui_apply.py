"""The checks of the clicked GUI test (pbf_gui_apply.xml.in): ParaView runs this with --script
at startup, before its event player replays the clicks, so it only watches. Play's start shows
the camera that Apply left; Play's end shows the last frame. At both, the Domain output's eight
corners (the tank, and the obstacles of a scene file) must project inside the view; at the end
the particles must show more than one hue of the velocity color map, and the map must have
started from the scene's speed scale (SceneSpeed), not from frame 0's 0 to 1e-38.

Each case prints one line; after PBF_GUI_APPLY_CASES cases the last line says all passed.
A failed check prints "pbf_gui_apply: FAILED" (the test's failure pattern). Screenshots go to
PBF_GUI_OUTPUT as pbf_gui_apply_<scene>_{apply,last}.png."""
import os
import sys

from paraview import simple

sys.path.insert(0, os.path.join(os.environ["PBF_SOURCE_DIR"], "Testing", "Python"))
from pbf_images import corners_off_view, hues, read_png, source_pixels  # noqa: E402

output_dir = os.environ.get("PBF_GUI_OUTPUT", os.getcwd())
os.makedirs(output_dir, exist_ok=True)
expected_cases = int(os.environ.get("PBF_GUI_APPLY_CASES", "1"))
passed = []


def fail(message):
    print("pbf_gui_apply: FAILED: " + message, flush=True)


def simulation():
    sources = [s for s in simple.GetSources().values()
               if s.GetXMLName() == "PBFSimulationSource"]
    return sources[0] if len(sources) == 1 else None


def scene_name(source):
    data = source.GetClientSideObject().GetOutputDataObject(0)
    return data.GetFieldData().GetAbstractArray("Scene").GetValue(0)


def screenshot(view, name):
    path = os.path.join(output_dir, name)
    simple.SaveScreenshot(path, view)
    return read_png(path)


def check_view(source, view, when):
    domain = source.GetClientSideObject().GetOutputDataObject(2)
    off = corners_off_view(view, domain.GetBounds())
    if off:
        fail("%s: %s: Domain corners off the %s view (corner, pixel): %s"
             % (scene_name(source), when, list(view.ViewSize), off))
        return False
    return True


state = {}


def on_play_started(*args):
    source, view = simulation(), simple.GetActiveView()
    if source is None or view is None:
        fail("Play started with no Position Based Fluids source or no active view")
        return
    name = scene_name(source)
    lut = simple.GetColorTransferFunction("velocity")
    speed = source.GetClientSideObject().GetOutputDataObject(0).GetFieldData() \
        .GetArray("SceneSpeed").GetTuple1(0)
    state.update(name=name, range=(lut.RGBPoints[0], lut.RGBPoints[-4]), speed=speed,
                 ok=check_view(source, view, "after Apply"))
    screenshot(view, "pbf_gui_apply_%s_apply.png" % name)
    # The map at the first Apply: the scene's speed scale (0.1 % is the rounding of the stored
    # range), not a degenerate range from the fluid at rest.
    if not (state["range"][0] <= 0.0 and state["range"][1] >= speed * (1 - 1e-3)):
        fail("%s: the color map after Apply runs %g..%g; the scene's speed scale is %g m/s"
             % ((name,) + state["range"] + (speed,)))
        state["ok"] = False


def on_play_ended(*args):
    source, view = simulation(), simple.GetActiveView()
    if source is None or not state:
        fail("Play ended without a source, or before a Play started")
        return
    name = state["name"]
    ok = state.pop("ok") and check_view(source, view, "last frame")
    shot, changed = source_pixels(
        view, source, os.path.join(output_dir, "pbf_gui_apply_%s_last.png" % name))
    seen = hues(shot[changed])
    if len(seen) < 2:
        fail("%s: the last frame's particles (%.1f %% of the view) show hues %s: one color"
             % (name, 100 * changed.mean(), seen))
        ok = False
    time = simple.GetTimeKeeper().Time
    if ok:
        passed.append(name)
        print("pbf_gui_apply: %s: tank in the %s view after Apply and at t = %g s; color map "
              "after Apply %g..%g m/s (SceneSpeed %g); last frame: particles on %.1f %% of the "
              "view in hues %s" % ((name, list(view.ViewSize), time) + state["range"]
                                   + (state["speed"], 100 * changed.mean(), seen)), flush=True)
    if len(passed) == expected_cases:
        print("pbf_gui_apply: all %d cases passed" % expected_cases, flush=True)


scene = simple.GetAnimationScene().GetClientSideObject()
scene.AddObserver("StartEvent", on_play_started)
scene.AddObserver("EndEvent", on_play_ended)
print("pbf_gui_apply: watching for %d cases" % expected_cases, flush=True)
