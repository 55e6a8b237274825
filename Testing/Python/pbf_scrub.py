"""Scrubbing beyond the dam break on OpenMP in single precision: the stream scene, whose
emitter adds particles every frame, the channel, whose outflow removes them, on the Serial
backend in double precision, and the dam break on Serial in double. Every frame asked forwards, backwards and by jumps (from checkpoints every 2
frames, or stepped on) is bit-identical to a straight run's, with as many vertex cells as points
and every cell naming a point that exists (pbf_testing.particles_of checks the cells of every
frame any test reads)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview.simple import Delete  # noqa: E402

T.load_plugin(globals())
expect = T.expect

FRAMES = 8
INTERVAL = 1.0 / 60.0


def scrub(preset, spacing, order, interval=INTERVAL, check=None):
    settings = dict(Preset=preset, ParticleSpacing=spacing, NumberOfFrames=FRAMES,
                    FrameInterval=interval, CheckpointInterval=2, Backend="Serial",
                    Precision="Double")
    straight = PositionBasedFluids(**settings)  # noqa: F821 (defined by LoadPlugin)
    reference = []
    for k in range(FRAMES + 1):  # in order: straight
        data = T.output_at(straight, k * interval)
        if check:
            check(data, k)
        reference.append(T.particles_of(data))
    Delete(straight)
    counts = [r["n"] for r in reference]
    for k in range(1, FRAMES + 1):
        expect(reference[k]["step"] > reference[k - 1]["step"], "%s: frame %d ran no step" % (preset, k))
    scrubbed = PositionBasedFluids(**settings)  # noqa: F821
    for k in order:
        T.expect_identical(T.frame(scrubbed, k * interval), reference[k],
                           "%s, frame %d in order %s" % (preset, k, order))
    Delete(scrubbed)
    return counts


# The stream's emitter grows the fluid, so going back gives fewer points than the last frame had.
# Every frame backwards from the last (the straight reference run took every frame forwards),
# then jumps and a repeat.
counts = scrub("stream", 0.05, list(range(FRAMES, -1, -1)) + [7, 1, 8, 2, 2, 5])
print("stream: particles per frame %s" % counts)
expect(counts[FRAMES] > counts[1] > 0, "the stream emitted nothing: %s" % counts)


# The channel's outflow removes particles from about 2.5 s on: frames every 0.5 s to 4 s. Each
# frame holds the ids released less those removed, each once; removed ids never come back.
def released_less_removed(data, k):
    n = data.GetNumberOfPoints()
    field = data.GetFieldData()
    released = int(field.GetArray("ReleasedParticles").GetTuple1(0))
    removed = int(field.GetArray("RemovedParticles").GetTuple1(0))
    expect(n == released - removed, "channel frame %d: %d particles, %d released less %d removed"
           % (k, n, released, removed))
    if k == FRAMES:
        expect(removed > 0, "channel: nothing left through the outflow by frame %d" % k)


counts = scrub("channel", 0.04, [8, 3, 6, 6, 1, 7, 0, 5], 0.5, released_less_removed)
print("channel: particles per frame %s" % counts)
scrub("dam_break", T.QUICK_SPACING, [5, 2, 8, 0, 7, 3])

T.passed("Scrub")
