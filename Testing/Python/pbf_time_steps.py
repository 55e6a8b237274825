"""The animation sees NumberOfFrames + 1 time steps k * FrameInterval, follows changes to them,
and a request is answered with the nearest frame (clamped to the range) and its DATA_TIME_STEP."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview.simple import GetAnimationScene, GetTimeKeeper  # noqa: E402

T.load_plugin(globals())
expect = T.expect

source = PositionBasedFluids(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=6)  # noqa: F821
keeper = GetTimeKeeper()
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()


def expect_steps(frames, interval, what):
    source.UpdatePipelineInformation()
    scene.UpdateAnimationUsingDataTimeSteps()
    expected = [k * interval for k in range(frames + 1)]
    announced = list(source.TimestepValues)
    expect(announced == expected, "%s: the source announces %s, expected %s"
           % (what, announced, expected))
    seen = list(keeper.TimestepValues)
    # Exact: the keeper holds the very doubles the algorithm announced.
    expect(seen == expected, "%s: the time keeper sees %d steps %s, expected %d"
           % (what, len(seen), seen, len(expected)))
    expect(scene.PlayMode == "Snap To TimeSteps", "%s: play mode %s" % (what, scene.PlayMode))
    expect(scene.StartTime == 0.0 and scene.EndTime == expected[-1],
           "%s: the animation runs %g..%g, expected 0..%g"
           % (what, scene.StartTime, scene.EndTime, expected[-1]))


expect_steps(6, 1.0 / 60.0, "defaults")

source.NumberOfFrames = 9
expect_steps(9, 1.0 / 60.0, "NumberOfFrames = 9")

source.FrameInterval = 0.025
expect_steps(9, 0.025, "FrameInterval = 0.025")

# The last frame of the animation is the last frame of the simulation.
scene.GoToLast()
expect(keeper.Time == 9 * 0.025, "GoToLast went to %g" % keeper.Time)
data = T.output_at(source, keeper.Time)
# The solver's steps (automatic by default) land on every frame's time exactly.
expect(T.field_value(data, "Frame") == 9 and T.field_value(data, "Time") == 9 * 0.025,
       "the last frame is frame %d at t = %r" % (T.field_value(data, "Frame"),
                                                 T.field_value(data, "Time")))

# Nearest frame: 2.4 intervals is frame 2, 2.6 is frame 3; before 0 and past the end clamp.
for requested, frame in ((2.4 * 0.025, 2), (2.6 * 0.025, 3), (-1.0, 0), (100.0, 9), (0.0, 0)):
    data = T.output_at(source, requested)
    got = data.GetInformation().Get(data.DATA_TIME_STEP())
    expect(got == frame * 0.025, "time %g answered with DATA_TIME_STEP %g, expected %g"
           % (requested, got, frame * 0.025))
    expect(T.field_value(data, "Frame") == frame, "time %g gave frame %d, expected %d"
           % (requested, T.field_value(data, "Frame"), frame))
    expect(T.field_value(data, "Time") == frame * 0.025, "frame %d is at t = %r"
           % (frame, T.field_value(data, "Time")))

T.passed("TimeSteps")
