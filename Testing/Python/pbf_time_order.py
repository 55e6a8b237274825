"""Any frame asked in any order (forward, backward, jumping, repeated) is bit-identical to a fresh
run straight to it; a physics change restarts the simulation, changing it back restores the
original frames, and NumberOfFrames does not change them."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview.simple import Delete  # noqa: E402

T.load_plugin(globals())
expect = T.expect

FRAMES = 6
# The default (automatic) time stepping: the steps of each frame are chosen from the state, so
# a frame reached from a checkpoint (every 2 frames here) must take the same steps as a straight
# run.
SETTINGS = dict(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=FRAMES, CheckpointInterval=2)
INTERVAL = 1.0 / 60.0


def straight(frame, **extra):
    """A fresh source run from the initial state straight to frame."""
    settings = dict(SETTINGS)
    settings.update(extra)
    fresh = PositionBasedFluids(**settings)  # noqa: F821 (defined by LoadPlugin)
    result = T.frame(fresh, frame * INTERVAL)
    Delete(fresh)
    return result


reference = {k: straight(k) for k in range(FRAMES + 1)}
# The frames differ from one another, or equality below would prove nothing.
for k in range(1, FRAMES + 1):
    expect(reference[k]["step"] > reference[k - 1]["step"],
           "frame %d ran no step (%d steps in all)" % (k, reference[k]["step"]))
    moved = abs(reference[k]["points"] - reference[k - 1]["points"]).max()
    expect(moved > 0, "frames %d and %d are equal: the fluid does not move" % (k - 1, k))

source = PositionBasedFluids(**SETTINGS)  # noqa: F821
order = [3, 1, 4, 4, 0, 2, 6, 5, 1, 6]  # forward, backward, repeat, to 0, jumps
for k in order:
    T.expect_identical(T.frame(source, k * INTERVAL), reference[k], "frame %d in order %s"
                       % (k, order))

# Times between frames are answered with the nearest frame.
T.expect_identical(T.frame(source, 2.3 * INTERVAL), reference[2], "time 2.3 intervals")

# More frames do not restart or change the simulation.
source.NumberOfFrames = 12
T.expect_identical(T.frame(source, 5 * INTERVAL), reference[5], "frame 5 after NumberOfFrames=12")
source.NumberOfFrames = FRAMES

# A physics change gives another motion; changing it back gives the original frames again.
source.XSPHViscosity = 0.2
viscous = T.frame(source, 4 * INTERVAL)
expect(abs(viscous["velocity"] - reference[4]["velocity"]).max() > 1e-4,
       "XSPHViscosity 0.0125 -> 0.2 left frame 4 unchanged")
T.expect_identical(viscous, straight(4, XSPHViscosity=0.2), "frame 4 with XSPHViscosity 0.2")
source.XSPHViscosity = 0.0125
T.expect_identical(T.frame(source, 3 * INTERVAL), reference[3], "frame 3 after changing back")

# Every physics property restarts the simulation, even when the next frame is later: step on
# from frame 1 of the old settings and frame 2 would differ from a straight run of the new ones.
CHANGES = [("RestDensity", 900.0), ("ParticleSpacing", 0.06), ("SmoothingRatio", 2.2),
           ("SolverIterations", 3), ("RelaxationEpsilon", 0.02), ("SCorrK", 0.05),
           ("SCorrN", 3.0), ("SCorrDeltaQ", 0.25), ("XSPHViscosity", 0.1),
           ("VorticityEpsilon", 0.02), ("Unilateral", 0), ("MirrorWalls", 0),
           ("Gravity", [0.0, -9.0, 0.0]), ("FrameInterval", 0.02), ("CFLNumber", 0.3),
           ("MaxTimeStep", 0.0005)]
# (TimeStepping Fixed is absent: at this spacing the automatic step is the largest one, 1/240 s,
# which is also Fixed's FrameInterval / SubstepsPerFrame, so the frames are the same.)
for name, value in CHANGES:
    original = source.GetPropertyValue(name)
    original = list(original) if hasattr(original, "__len__") else original
    T.expect_identical(T.frame(source, 1 * INTERVAL), reference[1], "frame 1 before %s" % name)
    source.SetPropertyWithName(name, value)
    interval = source.FrameInterval
    changed = T.frame(source, 2 * interval)
    T.expect_identical(changed, straight(2 * interval / INTERVAL, **{name: value}),
                       "frame 2 after %s = %s" % (name, value))
    different = changed["n"] != reference[2]["n"] or any(
        not (changed[a] == reference[2][a]).all() for a in ("points", "density"))
    expect(different, "%s = %s left frame 2 unchanged" % (name, value))
    source.SetPropertyWithName(name, original)

# A change of scene too: another preset, then back.
source.Preset = "double_dam_break"
other = T.frame(source, 2 * INTERVAL)
expect(other["n"] == 2 * reference[2]["n"],
       "the double dam break has %d particles, expected %d" % (other["n"], 2 * reference[2]["n"]))
source.Preset = "dam_break"
T.expect_identical(T.frame(source, 2 * INTERVAL), reference[2], "frame 2 after the preset round trip")

T.passed("TimeOrder")
