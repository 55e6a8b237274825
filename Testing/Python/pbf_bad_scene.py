"""A bad scene file (missing, empty, not JSON, an unknown key, a bad value) or a bad parameter is an
error naming the key and the value; the request fails without crashing, the previous output is
kept, and the next valid request works."""
import json
import math
import os
import re
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402

T.load_plugin(globals())
expect = T.expect

folder = tempfile.mkdtemp(prefix="pbf_bad_scene_")
GOOD = {"name": "small_box", "domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
        "fluid": [{"type": "box", "min": [0.1, 0.0, 0.1], "max": [0.4, 0.3, 0.4]}]}


def scene_file(name, text):
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def with_fluid(region):
    scene = json.loads(json.dumps(GOOD))
    scene["fluid"] = [region]
    return json.dumps(scene)


unknown_key = dict(GOOD, colour="blue")
missing = os.path.join(folder, "does_not_exist.json")
CASES = [
    # (what, scene file, parameter changes, texts the error must contain)
    ("missing file", missing, {}, [missing, "cannot be opened"]),
    ("empty file", scene_file("empty.json", ""), {}, ["empty.json", "is empty"]),
    ("not JSON", scene_file("not_json.json", "domain: [0, 1]\n"), {}, ["not_json.json",
                                                                         "not valid JSON"]),
    ("unknown key", scene_file("unknown_key.json", json.dumps(unknown_key)), {},
     [".colour", "blue", "unknown key"]),
    ("negative radius", scene_file("negative_radius.json", with_fluid(
        {"type": "sphere", "center": [0.5, 0.5, 0.5], "radius": -0.2})), {},
     [".fluid[0].radius", "-0.2", "must be > 0"]),
    ("box outside the domain", scene_file("outside.json", with_fluid(
        {"type": "box", "min": [0.5, 0.5, 0.5], "max": [1.5, 0.9, 0.9]})), {},
     [".fluid[0]", "inside the domain"]),
    ("NaN gravity", "", {"Gravity": [math.nan, -9.81, 0.0]}, ["gravity.x", "nan", "finite"]),
]

source = PositionBasedFluids(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=4)  # noqa: F821
previous = T.frame(source, 2 / 60.0)
expect(previous["n"] == T.QUICK_PARTICLES, "the preset gave %d particles" % previous["n"])

for what, path, changes, needles in CASES:
    source.SceneFile = path
    for name, value in changes.items():
        source.SetPropertyWithName(name, value)
    data, text = T.capture_messages(lambda: T.output_at(source, 3 / 60.0))
    errors = [line for line in text.splitlines() if line.startswith("vtkPBFSimulation")]
    expect(len(errors) == 1, "%s: expected one vtkPBFSimulation error, got %r" % (what, text))
    for needle in needles:
        expect(needle in errors[0], "%s: the error %r does not name %r" % (what, errors[0], needle))
    # The previous output is kept: the same particles, bit for bit, at the previous time.
    kept = T.frame(source, 3 / 60.0)
    T.expect_identical(kept, previous, "%s: the output after the error" % what)
    expect(kept["time"] == 2 / 60.0, "%s: the kept output claims time %g" % (what, kept["time"]))
    source.SceneFile = ""
    source.Gravity = [0.0, -9.81, 0.0]

# A blow-up is reported in the GUI's words: the properties that exist (Substeps Per
# Frame, Frame Interval, Time Stepping), never the solver's field names (timeStep). Fixed steps of
# 0.05 s with light XSPH and no bi-Laplacian pile the fluid up within a few steps
# (DivergenceTest.cpp).
source.TimeStepping = "Fixed"
source.FrameInterval = 0.05
source.SubstepsPerFrame = 1
source.AdaptiveIterations = 0
source.XSPHViscosity = 0.001
source.XSPHHyperViscosity = 0
data, text = T.capture_messages(lambda: T.output_at(source, 0.3))
errors = [line for line in text.splitlines() if line.startswith("vtkPBFSimulation")]
expect(len(errors) == 1 and "diverged" in errors[0], "a fixed-step blow-up gave %r" % text)
print("divergence message: %s" % errors[0])
for needle in ("Substeps Per Frame", "Frame Interval", "Time Stepping"):
    expect(needle in errors[0], "the divergence message %r does not name %r" % (errors[0], needle))
for solver_name in ("timeStep", "cflNumber", "solverIterations"):
    expect(not re.search(r"\b%s\b" % solver_name, errors[0]),
           "the divergence message %r names the solver's %s" % (errors[0], solver_name))
source.TimeStepping = "Automatic"
source.FrameInterval = 1 / 60.0
source.SubstepsPerFrame = 4
source.AdaptiveIterations = 1
source.XSPHViscosity = 0.0125
source.XSPHHyperViscosity = 0.05

# A valid scene file after the errors: 0.3 / 0.05 = 6 sites per axis.
source.SceneFile = scene_file("good.json", json.dumps(GOOD))
good = T.frame(source, 1 / 60.0)
expect(good["n"] == 6 * 6 * 6, "the good scene file gave %d particles" % good["n"])
data = T.output_at(source, 1 / 60.0)
expect(T.field_value(data, "Scene") == "small_box", "scene %s" % T.field_value(data, "Scene"))
expect(T.field_value(data, "Domain") == (0.0, 1.0, 0.0, 1.0, 0.0, 1.0), "the file's domain")

# The file is read again when it changes, even under the same name.
with open(source.SceneFile, "w") as f:
    f.write(with_fluid({"type": "box", "min": [0.1, 0.0, 0.1], "max": [0.3, 0.3, 0.3]}))
source.SceneFile = ""
source.SceneFile = os.path.join(folder, "good.json")
expect(T.frame(source, 1 / 60.0)["n"] == 4 * 6 * 4, "an edited scene file was not read again")

# And the preset again, equal to what it gave before the errors.
source.SceneFile = ""
T.expect_identical(T.frame(source, 2 / 60.0), previous, "the preset after the errors")

shutil.rmtree(folder)
T.passed("BadScene")
