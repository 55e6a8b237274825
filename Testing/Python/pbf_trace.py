"""Python tracing (paraview.smtrace, as Tools > Start Trace does) of creating the source records a
script that, run in a fresh pvbatch, rebuilds the same pipeline: identical output."""
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import smtrace  # noqa: E402

T.load_plugin(globals())
expect = T.expect

INTERVAL = 1.0 / 60.0
folder = tempfile.mkdtemp(prefix="pbf_trace_")

smtrace.start_trace()
source = PositionBasedFluids(  # noqa: F821 (defined by LoadPlugin)
    registrationName="fluid", Preset="blob", ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=10,
    TimeStepping="Fixed", SubstepsPerFrame=3, XSPHViscosity=0.03, SolverIterations=5,
    AdaptiveIterations=0, DensityErrorTolerance=0.5, CheckpointInterval=2)
trace = smtrace.stop_trace()
for text in ("PositionBasedFluids(registrationName='fluid'", "Preset = 'blob'",
             "DensityErrorTolerance = 0.5", "AdaptiveIterations = 0", "TimeStepping = 'Fixed'"):
    expect(text in trace, "the trace lacks %r:\n%s" % (text, trace))
live = T.frame(source, 6 * INTERVAL)

script = os.path.join(folder, "trace.py")
with open(script, "w") as out:
    out.write(trace)
replayed = os.path.join(folder, "replayed.npz")
T.run_pvbatch(os.path.join(os.path.dirname(os.path.abspath(__file__)), "pbf_replay.py"),
              "--trace", script, "--name", "fluid", "--time", 6 * INTERVAL, "--output", replayed)
T.expect_identical(T.load_frame(replayed), live, "frame 6 from the replayed trace")
shutil.rmtree(folder)
T.passed("Trace")
