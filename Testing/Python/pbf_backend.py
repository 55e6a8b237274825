"""Backend Auto takes CUDA when there is a device and otherwise falls back to OpenMP, saying so
exactly once; asking for CUDA without a device is an error naming the reason; OpenMP and Serial
give bit-identical frames."""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402

T.load_plugin(globals())
expect = T.expect

SETTINGS = dict(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=5, SubstepsPerFrame=2)
source = PositionBasedFluids(**SETTINGS)  # noqa: F821 (defined by LoadPlugin)
expect(source.Backend == "Auto", "the default backend is %s" % source.Backend)


def run_auto():
    descriptions = []
    # Forward, backward (a rebuild) and a physics change (another rebuild).
    for time in (2 / 60.0, 1 / 60.0):
        descriptions.append(T.field_value(T.output_at(source, time), "Backend"))
    source.SCorrK = 0.05
    descriptions.append(T.field_value(T.output_at(source, 3 / 60.0), "Backend"))
    return descriptions


descriptions, text = T.capture_messages(run_auto)
fallbacks = re.findall(r"Backend Auto: no CUDA \((.*)\); falling back to CPU \(OpenMP\)", text)
if all(d.startswith("CUDA") for d in descriptions):
    expect(not fallbacks, "Auto ran on CUDA but said it fell back: %r" % text)
    sys.stdout.write("CUDA device present: %s\n" % descriptions[0])
else:
    expect(all(d.startswith("OpenMP") for d in descriptions),
           "Auto without CUDA ran on %s, expected OpenMP" % descriptions)
    expect(len(fallbacks) == 1 and fallbacks[0].strip(),
           "the fallback must be said once, with its reason; messages were %r" % text)
    reason = fallbacks[0]

    # Explicit CUDA without a device: an error with the reason, the previous output kept.
    before = T.frame(source, 3 / 60.0)
    source.Backend = "CUDA"
    _, text = T.capture_messages(lambda: T.output_at(source, 4 / 60.0))
    errors = [line for line in text.splitlines() if line.startswith("vtkPBFSimulation")]
    expect(len(errors) == 1 and "Backend = CUDA" in errors[0] and reason in errors[0],
           "asking for CUDA without a device: expected one error naming %r, got %r"
           % (reason, text))
    T.expect_identical(T.frame(source, 4 / 60.0), before, "the output after the CUDA error")
    source.Backend = "Auto"
    _, text = T.capture_messages(lambda: T.output_at(source, 4 / 60.0))
    expect("falling back" not in text, "the fallback was said a second time: %r" % text)

# OpenMP runs the very per-particle functions of Serial: bit-identical, in either precision.
for precision in ("Single", "Double"):
    frames = {}
    for backend in ("Serial", "CPU (OpenMP)"):
        run = PositionBasedFluids(Backend=backend, Precision=precision, **SETTINGS)  # noqa: F821
        frames[backend] = T.frame(run, 5 / 60.0)
        expect(T.field_value(T.output_at(run, 5 / 60.0), "Backend").startswith(
            "Serial" if backend == "Serial" else "OpenMP"), "%s did not run on %s"
            % (backend, T.field_value(T.output_at(run, 5 / 60.0), "Backend")))
    T.expect_identical(frames["Serial"], frames["CPU (OpenMP)"],
                       "Serial vs OpenMP, %s precision" % precision)

T.passed("Backend")
