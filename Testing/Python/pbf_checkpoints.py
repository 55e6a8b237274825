"""Time without waiting: checkpoints taken while stepping let an earlier frame resume from the
latest checkpoint at or before it, the frame just shown is handed out again without stepping or
copying, and every path gives frames bit-identical to a straight run. The memory budget thins the
checkpoints evenly and keeps frame 0. A physics change invalidates the simulation, the checkpoints
and the diagnostics; NumberOfFrames and the checkpoint settings invalidate nothing.

Each output says how it was made (field data): RequestSteps (solver steps the request took),
ResumedFrom ("output", "live", "checkpoint" or "initial"), ResumedFromStep, CheckpointFrames."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview.simple import Delete  # noqa: E402

T.load_plugin(globals())
expect = T.expect

FRAMES = 24
SUBSTEPS = 2
INTERVAL = 1.0 / 60.0
# Fixed steps, so that the steps each path takes can be counted here; pbf_time_order.py checks
# resuming from checkpoints with the default automatic steps.
SETTINGS = dict(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=FRAMES, SubstepsPerFrame=SUBSTEPS,
                TimeStepping="Fixed")
# One checkpoint of the quick dam break: position, velocity (3 floats each), density, lambda,
# pressure (1 float each) and the id (8 bytes) per particle.
CHECKPOINT_BYTES = T.QUICK_PARTICLES * (12 + 12 + 4 + 4 + 4 + 8)


def how(data):
    """(ResumedFrom, ResumedFromStep, RequestSteps) of an output."""
    return (T.field_value(data, "ResumedFrom"), int(T.field_value(data, "ResumedFromStep")),
            int(T.field_value(data, "RequestSteps")))


def held(data):
    array = data.GetFieldData().GetArray("CheckpointFrames")
    return [int(array.GetTuple1(i)) for i in range(array.GetNumberOfTuples())]


def visit(source, k, expected_how, what):
    """Asks for frame k, checks it against the straight run and how it was made."""
    data = T.output_at(source, k * INTERVAL)
    got = how(data)
    expect(got == expected_how, "%s: frame %d made as %s, expected %s" % (what, k, got, expected_how))
    T.expect_identical(T.frame(source, k * INTERVAL), straight[k], "%s: frame %d" % (what, k))
    return data


# The reference: one source stepping forward from frame 0, no checkpoints.
reference = PositionBasedFluids(CheckpointInterval=0, **SETTINGS)  # noqa: F821 (LoadPlugin)
straight = {k: T.frame(reference, k * INTERVAL) for k in range(FRAMES + 1)}
expect(how(T.output_at(reference, FRAMES * INTERVAL)) == ("live", (FRAMES - 1) * SUBSTEPS, SUBSTEPS),
       "the reference did not step on frame after frame")
Delete(reference)

source = PositionBasedFluids(CheckpointInterval=4, **SETTINGS)  # noqa: F821
data = visit(source, 20, ("initial", 0, 20 * SUBSTEPS), "straight to 20")
expect(held(data) == [0, 4, 8, 12, 16, 20], "checkpoints %s, expected every 4 frames" % held(data))
# Back: from the latest checkpoint at or before the frame, not from the start.
visit(source, 10, ("checkpoint", 8 * SUBSTEPS, 2 * SUBSTEPS), "back to 10")
visit(source, 9, ("checkpoint", 8 * SUBSTEPS, 1 * SUBSTEPS), "back to 9")
# Forward: the live simulation steps on, unless a checkpoint is nearer.
visit(source, 11, ("live", 9 * SUBSTEPS, 2 * SUBSTEPS), "on to 11")
visit(source, 17, ("checkpoint", 16 * SUBSTEPS, 1 * SUBSTEPS), "on to 17")
visit(source, 19, ("live", 17 * SUBSTEPS, 2 * SUBSTEPS), "on to 19")
data = visit(source, 24, ("checkpoint", 20 * SUBSTEPS, 4 * SUBSTEPS), "on to 24")
expect(held(data) == [0, 4, 8, 12, 16, 20, 24], "checkpoints %s after frame 24" % held(data))

# The frame just shown costs nothing: after a change that re-executes the algorithm but changes
# no frame, the same frame comes back with the same arrays (no copy) and no step.
shown = T.output_at(source, 24 * INTERVAL)
address = shown.GetPoints().GetData().GetVoidPointer(0)
for name, value in (("NumberOfFrames", 30), ("CheckpointInterval", 6),
                    ("CheckpointMemoryMB", 512.0)):
    source.SetPropertyWithName(name, value)
    data = T.output_at(source, 24 * INTERVAL)
    expect(how(data) == ("output", 24 * SUBSTEPS, 0),
           "%s = %s: frame 24 made as %s, expected the output again" % (name, value, how(data)))
    expect(data.GetPoints().GetData().GetVoidPointer(0) == address,
           "%s = %s: frame 24 was copied again" % (name, value))
# ... and nothing computed was dropped: an earlier frame still resumes from a checkpoint.
visit(source, 13, ("checkpoint", 12 * SUBSTEPS, 1 * SUBSTEPS), "back to 13 after the changes")
rows = len(T.diagnostics(source)["Frame"])
expect(rows == 25, "the diagnostics hold %d rows after the changes, expected 25 (frames 0..24)"
       % rows)
source.NumberOfFrames = FRAMES
source.CheckpointInterval = 4
source.CheckpointMemoryMB = 1024.0

# A physics change invalidates everything: the next frame starts over, the old checkpoints and
# rows are gone. Changing it back starts over again (nothing of the old run was kept to reuse).
source.XSPHViscosity = 0.1
data = T.output_at(source, 6 * INTERVAL)
expect(how(data) == ("initial", 0, 6 * SUBSTEPS),
       "XSPHViscosity 0.1: frame 6 made as %s, expected from the initial state" % (how(data),))
expect(held(data) == [0, 4], "XSPHViscosity 0.1: checkpoints %s, expected [0, 4]" % held(data))
table = T.diagnostics(source)
expect(list(table["Frame"]) == list(range(7)),
       "XSPHViscosity 0.1: diagnostics of frames %s, expected 0..6" % list(table["Frame"]))
expect(abs(T.frame(source, 6 * INTERVAL)["velocity"] - straight[6]["velocity"]).max() > 1e-4,
       "XSPHViscosity 0.1 left frame 6 unchanged")
source.XSPHViscosity = 0.0125
visit(source, 5, ("initial", 0, 5 * SUBSTEPS), "XSPHViscosity back to 0.0125")

# Memory budget: room for 5.5 checkpoints, one taken every frame. Each time the sixth arrives,
# the interval doubles and those off it go: 0..5 -> 0 2 4 -> ... -> 0 8 16 24.
budget = 5.5 * CHECKPOINT_BYTES
thin = PositionBasedFluids(CheckpointInterval=1, CheckpointMemoryMB=budget / 1048576.0,  # noqa: F821
                           **SETTINGS)
data = visit(thin, 24, ("initial", 0, 24 * SUBSTEPS), "budget: straight to 24")
frames = held(data)
expect(frames == [0, 8, 16, 24], "budget of 5.5 checkpoints kept frames %s, expected "
       "[0, 8, 16, 24]" % frames)
memory = T.field_value(data, "CheckpointMemoryMB") * 1048576.0
expect(abs(memory - len(frames) * CHECKPOINT_BYTES) < 1 and memory <= budget,
       "the checkpoints hold %d bytes for %d of them, budget %d" % (memory, len(frames), budget))
visit(thin, 13, ("checkpoint", 8 * SUBSTEPS, 5 * SUBSTEPS), "budget: back to 13")
visit(thin, 7, ("checkpoint", 0, 7 * SUBSTEPS), "budget: back to 7")
# A budget smaller than one checkpoint still keeps frame 0.
thin.CheckpointMemoryMB = 0.0
data = visit(thin, 9, ("live", 7 * SUBSTEPS, 2 * SUBSTEPS), "budget 0: on to 9")
expect(held(data) == [0], "budget 0 kept %s, expected frame 0 only" % held(data))

# CheckpointInterval 0 frees them: an earlier frame then starts from the initial state.
thin.CheckpointInterval = 0
data = visit(thin, 10, ("live", 9 * SUBSTEPS, 1 * SUBSTEPS), "interval 0: on to 10")
expect(held(data) == [], "interval 0 still holds %s" % held(data))
visit(thin, 3, ("initial", 0, 3 * SUBSTEPS), "interval 0: back to 3")

T.passed("Checkpoints")
