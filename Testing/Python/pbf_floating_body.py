"""A body the fluid moves, through ParaView: a scene file's obstacle with a "density" floats. The
Diagnostics table gains its Position, Orientation, Velocity and AngularVelocity columns, the
particles' field data its BodyPosition and friends, the Domain output draws the box where it is,
and a frame asked again after others gives the same bits."""
import json
import os
import sys
import tempfile

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402

T.load_plugin(globals())
expect = T.expect

HEIGHT = 0.16
scene = {
    "name": "floating box",
    "domain": {"min": [0, 0, 0], "max": [0.6, 0.6, 0.6]},
    "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.6, 0.3, 0.6]}],
    "obstacles": [{"type": "box", "name": "crate", "min": [0.2, 0.28, 0.2],
                   "max": [0.4, 0.28 + HEIGHT, 0.4], "density": 500}],
}
folder = tempfile.mkdtemp()
path = os.path.join(folder, "floating.json")
with open(path, "w") as f:
    json.dump(scene, f)

INTERVAL = 1.0 / 30.0
FRAMES = 24
source = PositionBasedFluids(SceneFile=path, ParticleSpacing=0.04, FrameInterval=INTERVAL,  # noqa: F821
                             NumberOfFrames=FRAMES + 1, Backend="CPU (OpenMP)")
late = T.frame(source, FRAMES * INTERVAL)
particles = T.output_at(source, FRAMES * INTERVAL)
centre = T.field_value(particles, "BodyPosition")
expect(T.field_value(particles, "BodyNames") == "crate", "BodyNames %s" % T.field_value(particles, "BodyNames"))
# Let go 0.02 m into the water, it sinks towards its draft of half its height.
start_y = 0.28 + HEIGHT / 2
expect(centre[1] < start_y - 0.005, "the crate did not sink: centre y %.4f from %.4f" % (centre[1], start_y))
expect(abs(centre[0] - 0.3) < 0.01 and abs(centre[2] - 0.3) < 0.01, "the crate drifted to %s" % (centre,))
# The Domain output draws the crate where it is: its cube's top face at the centre + H / 2.
domain = source.GetClientSideObject().GetOutputDataObject(2)
# (The crate may tilt a little: a box this wide and this light floats just stable, its metacentre
# 1.7 mm above its centre of mass; so its top corners are compared within 1 cm.)
ys = numpy.array([domain.GetPoint(k)[1] for k in range(domain.GetNumberOfPoints())])
cube = ys[(ys > 1e-9) & (ys < 0.6 - 1e-6)]
top = centre[1] + HEIGHT / 2
expect(abs(cube.max() - top) < 0.01, "the crate's cube tops out at %.5f, its centre says %.5f" % (cube.max(), top))
expect(not numpy.any(numpy.abs(cube - (0.28 + HEIGHT)) < 1e-6), "the Domain still draws the crate where it started")
print("crate centre %s" % (centre,))

table = T.diagnostics(source)
for column in ("Position crate", "Orientation crate", "Velocity crate", "AngularVelocity crate",
               "Force crate", "Torque crate"):
    expect(column in table, "no column %r" % column)
positions = table["Position crate"]
expect(positions.shape == (FRAMES + 1, 3), "Position crate has shape %s" % (positions.shape,))
expect(abs(positions[0][1] - start_y) < 1e-12, "frame 0 is not where the scene puts it: %s" % positions[0])
expect(numpy.allclose(positions[FRAMES], centre, rtol=0, atol=0), "the table's last row is not the field data's")
quaternions = table["Orientation crate"]
expect(numpy.allclose(numpy.linalg.norm(quaternions, axis=1), 1, atol=1e-12), "orientations are not unit")

# Scrubbing back and forth: the frame comes back bit for bit (the bodies' states are in the
# checkpoints).
T.output_at(source, 5 * INTERVAL)
again = T.frame(source, FRAMES * INTERVAL)
expect(numpy.array_equal(again["points"], late["points"]), "frame %d changed after going back" % FRAMES)

