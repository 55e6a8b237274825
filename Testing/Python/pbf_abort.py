"""Progress and abort: a long request reports progress after every solver step (ParaView's
progress bar moves), and AbortExecute set while it runs (here by a ProgressEvent observer, as a
Cancel button would) stops a jump to frame 500 within a step. The output stays the previous frame,
the diagnostics hold whole frames only, and the next request resumes from where the simulation
stopped and is bit-identical to a straight run."""
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview.simple import Delete  # noqa: E402

T.load_plugin(globals())
expect = T.expect

INTERVAL = 1.0 / 60.0
SETTINGS = dict(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=500, SubstepsPerFrame=2)
TARGET = 500
RESUME = 12  # the frame asked for after the abort: past where the abort stops

source = PositionBasedFluids(CheckpointInterval=10, **SETTINGS)  # noqa: F821 (LoadPlugin)
algorithm = source.GetClientSideObject()

# Progress: a request of 8 steps reports 8 increasing fractions ending at 1.
progress = []
observer = algorithm.AddObserver("ProgressEvent",
                                 lambda caller, event: progress.append(caller.GetProgress()))
before = T.frame(source, 4 * INTERVAL)
algorithm.RemoveObserver(observer)
steps = [p for p in progress if 0.0 < p < 1.0]
expect(len(steps) >= 7 and steps == sorted(steps) and progress[-1] == 1.0,
       "progress of a 4-frame request: %s" % progress)
rows_before = T.diagnostics(source)

# Abort the jump to frame 500 after 1% of it; the observer plays the Cancel button.
aborted, progress, elapsed = T.cancelled_request(
    algorithm, lambda: T.output_at(source, TARGET * INTERVAL))
expect(algorithm.GetAbortExecute() == 1, "AbortExecute was cleared by the algorithm")

# Promptly: the steps before the abort, not the 1,984 of the jump. Progress counts simulated
# time, and 1 % of the jump is 5 frames of 4 automatic steps (the largest step, 1/240 s, at this
# spacing): about 20 steps, then the abort within one more.
table = T.diagnostics(source)
stepped = [p for p in progress if 0.0 < p < 1.0]
expect(len(stepped) <= 24, "the abort took %d steps to be honoured" % len(stepped))
milliseconds = numpy.nanmean(table["MillisecondsPerStep"])
full = (TARGET - 4) * 4 * milliseconds / 1000.0
expect(elapsed < 0.1 * full + 1.0,
       "the aborted jump took %.2f s; the whole jump takes about %.1f s" % (elapsed, full))

# The output is still the previous frame, at its own time; no half-way state shows as a frame.
expect(int(T.field_value(aborted, "Frame")) == 4 and
       aborted.GetInformation().Get(aborted.DATA_TIME_STEP()) == 4 * INTERVAL,
       "after the abort the output is frame %s at t = %s, not frame 4"
       % (T.field_value(aborted, "Frame"), aborted.GetInformation().Get(aborted.DATA_TIME_STEP())))
T.expect_identical(T.frame(source, TARGET * INTERVAL), before, "the output after the abort")
# The diagnostics grew by whole frames only, in order, the earlier rows unchanged.
frames = list(table["Frame"])
expect(frames == list(range(len(frames))) and 5 <= len(frames) <= 12,
       "after the abort the diagnostics hold frames %s" % frames)
for name in ("AverageDensityError", "MaxDensityError", "AverageNeighbors", "MaxSpeed"):
    expect(numpy.array_equal(table[name][:5], rows_before[name]),
           "the abort changed the rows of frames 0..4 (%s)" % name)

# Whoever set AbortExecute clears it; the next requests run and equal a straight run.
algorithm.SetAbortExecute(0)
resumed = T.output_at(source, RESUME * INTERVAL)
expect(T.field_value(resumed, "ResumedFrom") == "live" and
       T.field_value(resumed, "ResumedFromStep") > 8,
       "frame %d after the abort resumed from %s at step %d, not from where it stopped"
       % (RESUME, T.field_value(resumed, "ResumedFrom"), T.field_value(resumed, "ResumedFromStep")))
reference = PositionBasedFluids(CheckpointInterval=0, **SETTINGS)  # noqa: F821
T.expect_identical(T.frame(source, RESUME * INTERVAL), T.frame(reference, RESUME * INTERVAL),
                   "frame %d after the abort" % RESUME)
T.expect_identical(T.frame(source, 3 * INTERVAL), T.frame(reference, 3 * INTERVAL),
                   "frame 3 after the abort")
# The rows completed before the abort equal those of a run that was never interrupted.
table, straight = T.diagnostics(source), T.diagnostics(reference)
for name in ("Time", "Frame", "AverageDensityError", "MaxDensityError", "AverageNeighbors",
             "SolverIterations", "MaxSpeed", "KineticEnergy", "Particles"):
    expect(numpy.array_equal(table[name][:RESUME + 1], straight[name][:RESUME + 1],
                             equal_nan=True),
           "the diagnostics column %s differs from an uninterrupted run" % name)
Delete(reference)

T.passed("Abort")
