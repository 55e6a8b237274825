"""A body through the Obstacles port: a Box source made a rigid body by the Position Based Fluids
Rigid Body filter (Density, Name) floats in the tank like the scene file's crate of
pbf_floating_body.py. The Diagnostics and field data name it, the Domain output draws it where it
is, another density is another run, and a density that is not positive is an error naming the
body and the value, with the previous output kept. On a vertical guide (FreeAxes 0 1 0, Turns
off) and held until Release, it stays put until then and afterwards moves only up and down; a
negative Release is an error naming it."""
import json
import os
import sys
import tempfile

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402

from paraview import simple  # noqa: E402

T.load_plugin(globals())
expect = T.expect
expect("PositionBasedFluidsRigidBody" in globals(), "LoadPlugin did not define PositionBasedFluidsRigidBody()")

HEIGHT = 0.16
scene = {
    "name": "tank",
    "domain": {"min": [0, 0, 0], "max": [0.6, 0.6, 0.6]},
    "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.6, 0.3, 0.6]}],
}
folder = tempfile.mkdtemp()
path = os.path.join(folder, "tank.json")
with open(path, "w") as f:
    json.dump(scene, f)

INTERVAL = 1.0 / 30.0
FRAMES = 24
box = simple.Box(Center=[0.3, 0.28 + HEIGHT / 2, 0.3], XLength=0.2, YLength=HEIGHT, ZLength=0.2)
crate = PositionBasedFluidsRigidBody(Input=box, Density=500, Name="crate")  # noqa: F821
crate.UpdatePipeline()
tagged = crate.GetClientSideObject().GetOutputDataObject(0).GetFieldData()
expect(tagged.GetArray("PBFBodyDensity").GetTuple1(0) == 500, "the rigid body filter wrote no density")
source = PositionBasedFluids(SceneFile=path, ParticleSpacing=0.04, FrameInterval=INTERVAL,  # noqa: F821
                             NumberOfFrames=FRAMES + 1, Backend="CPU (OpenMP)", Obstacles=[crate])
particles = T.output_at(source, FRAMES * INTERVAL)
expect(T.field_value(particles, "BodyNames") == "crate", "BodyNames %s" % T.field_value(particles, "BodyNames"))
centre = T.field_value(particles, "BodyPosition")
start_y = 0.28 + HEIGHT / 2
# Let go 0.02 m into the water, it sinks towards its draft of half its height (as the scene file's
# crate does in pbf_floating_body.py).
expect(centre[1] < start_y - 0.005, "the crate did not sink: centre y %.4f from %.4f" % (centre[1], start_y))
expect(abs(centre[0] - 0.3) < 0.01 and abs(centre[2] - 0.3) < 0.01, "the crate drifted to %s" % (centre,))
table = T.diagnostics(source)
for column in ("Position crate", "Velocity crate", "Force crate", "Torque crate"):
    expect(column in table, "no column %r" % column)
# The Domain output draws the body where it is, with the pressure the fluid puts on it.
domain = source.GetClientSideObject().GetOutputDataObject(2)
solid = domain.GetPointData().GetArray("Solid")
ys = numpy.array([domain.GetPoint(k)[1] for k in range(domain.GetNumberOfPoints())
                  if solid.GetValue(k) == 0])
expect(ys.size > 0, "the Domain output does not draw the Obstacles port's body")
expect(abs(ys.max() - (centre[1] + HEIGHT / 2)) < 0.01,
       "the body's drawing tops out at %.4f, its centre says %.4f" % (ys.max(), centre[1] + HEIGHT / 2))
pressure = domain.GetPointData().GetArray("pressure")
bottom = [pressure.GetValue(k) for k in range(domain.GetNumberOfPoints())
          if solid.GetValue(k) == 0 and domain.GetPoint(k)[1] < ys.min() + 1e-6]
expect(numpy.mean(bottom) > 0, "no pressure on the body's bottom: %s" % bottom[:4])

# Another density is another run: a denser crate floats deeper.
crate.Density = 800
heavier = T.field_value(T.output_at(source, FRAMES * INTERVAL), "BodyPosition")
expect(heavier[1] < centre[1] - 0.005, "at 800 kg/m^3 the centre is at %.4f, at 500 at %.4f" % (heavier[1], centre[1]))

# A density that is not positive: an error naming the body and the value; the output stays.
kept = T.frame(source, FRAMES * INTERVAL)
crate.Density = -1
_, messages = T.capture_messages(lambda: source.UpdatePipeline(FRAMES * INTERVAL))
expect("crate: Density = -1" in messages, "no error names the density: %s" % messages)
T.expect_identical(T.particles_of(source.GetClientSideObject().GetOutputDataObject(0)), kept,
                   "the output after the bad density")

# On a vertical guide, held until 0.2 s: where it was given (to the last bit: a held body is not
# integrated) at 0.1 s; at the end it has sunk, with x and z as given and no turn (a held axis's
# coordinate is never changed, 1e-12 for the sums that carry it in double).
crate.Density = 500
crate.FreeAxes = [0, 1, 0]
crate.Turns = 0
crate.Release = 0.2
given = T.field_value(T.output_at(source, 0), "BodyPosition")  # the float Box's centre of mass
held = T.field_value(T.output_at(source, 3 * INTERVAL), "BodyPosition")
expect(list(held) == list(given), "held until 0.2 s, the crate is at %s at 0.1 s, given at %s" % (held, given))
guided = T.field_value(T.output_at(source, FRAMES * INTERVAL), "BodyPosition")
turned = T.field_value(T.output_at(source, FRAMES * INTERVAL), "BodyOrientation")
expect(guided[1] < start_y - 0.005, "the guided crate did not sink: centre y %.4f" % guided[1])
expect(abs(guided[0] - given[0]) < 1e-12 and abs(guided[2] - given[2]) < 1e-12,
       "the guided crate left its guide: %s from %s" % (guided, given))
expect(max(abs(q - e) for q, e in zip(turned, (1, 0, 0, 0))) < 1e-12,
       "the crate turned without Turns: %s" % (turned,))
crate.Release = -1
_, messages = T.capture_messages(lambda: source.UpdatePipeline(FRAMES * INTERVAL))
expect("crate: Release = -1" in messages, "no error names the release: %s" % messages)
T.passed("RigidBody")
