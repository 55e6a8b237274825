"""A .pvsm state saved with the plugin's source (every kind of property set away from its
default, a scene file included) reloads in a fresh pvbatch and gives identical output."""
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import simple  # noqa: E402

T.load_plugin(globals())
expect = T.expect

INTERVAL = 1.0 / 60.0
folder = tempfile.mkdtemp(prefix="pbf_state_")
scene = os.path.join(folder, "scene.json")
shutil.copy(os.path.join(os.environ["PBF_DATA_DIR"], "dam_break.json"), scene)

source = PositionBasedFluids(  # noqa: F821 (defined by LoadPlugin)
    SceneFile=scene, ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=10, CFLNumber=0.3,
    XSPHViscosity=0.03, Gravity=[0.5, -9.0, 0.0], MirrorWalls=0, SolverIterations=5,
    AdaptiveIterations=1, DensityErrorTolerance=0.5, CheckpointInterval=3, CheckpointMemoryMB=64,
    Precision="Double", Backend="Serial")
simple.RenameSource("fluid", source)
live = T.frame(source, 5 * INTERVAL)
expect(live["points_type"] == "vtkDoubleArray", "Precision Double gave %s" % live["points_type"])

state = os.path.join(folder, "fluid.pvsm")
simple.SaveState(state)
text = open(state).read()
for name in ("SceneFile", "DensityErrorTolerance", "AdaptiveIterations", "CheckpointInterval",
             "CFLNumber", "TimeStepping"):
    expect('name="%s"' % name in text, "the state does not record %s" % name)

replayed = os.path.join(folder, "replayed.npz")
T.run_pvbatch(os.path.join(os.path.dirname(os.path.abspath(__file__)), "pbf_replay.py"),
              "--state", state, "--name", "fluid", "--time", 5 * INTERVAL, "--output", replayed)
again = T.load_frame(replayed)
expect(again["frame"] == 5 and again["step"] == live["step"],
       "the reloaded state gave frame %d (step %d, live %d)"
       % (again["frame"], again["step"], live["step"]))
T.expect_identical(again, live, "frame 5 from the reloaded state")
shutil.rmtree(folder)
T.passed("State")
