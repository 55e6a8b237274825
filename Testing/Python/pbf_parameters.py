"""The proxy's defaults are pbf::Parameters' defaults (read from Solver/Physics/Parameters.h, so
the two cannot drift), every field of pbf::Parameters has a property, and every property reaches the
solver: the frame's field data holds the values the solver ran with."""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402

T.load_plugin(globals())
expect = T.expect

# pbf::Parameters field -> (proxy property, field data array of the frame).
FIELDS = {
    "restDensity": ("RestDensity", "RestDensity"),
    "particleSpacing": ("ParticleSpacing", "ParticleSpacing"),
    "smoothingRatio": ("SmoothingRatio", "SmoothingRatio"),
    "solverIterations": ("SolverIterations", "SolverIterations"),
    # AdaptiveIterations ? DensityErrorTolerance : 0 (the solver's fixed mode); checked below.
    "densityErrorTolerance": (None, "DensityErrorTolerance"),
    "maxDensityErrorTolerance": ("MaxDensityErrorTolerance", "MaxDensityErrorTolerance"),
    "relaxation": ("RelaxationEpsilon", "RelaxationEpsilon"),
    "chebyshevRho": ("ChebyshevRho", "ChebyshevRho"),
    "sCorrK": ("SCorrK", "SCorrK"),
    "sCorrN": ("SCorrN", "SCorrN"),
    "sCorrDeltaQ": ("SCorrDeltaQ", "SCorrDeltaQ"),
    "xsphViscosity": ("XSPHViscosity", "XSPHViscosity"),
    "xsphHyperViscosity": ("XSPHHyperViscosity", "XSPHHyperViscosity"),
    "vorticityEpsilon": ("VorticityEpsilon", "VorticityEpsilon"),
    "surfaceTension": ("SurfaceTension", "SurfaceTension"),
    "contactAngle": ("ContactAngle", "ContactAngle"),
    "unilateral": ("Unilateral", "Unilateral"),
    "mirrorWalls": ("MirrorWalls", "MirrorWalls"),
    "tankLoads": ("TankLoads", "TankLoads"),
    "exactBoundaries": ("ExactBoundaries", "ExactBoundaries"),
    "wallFriction": ("WallFriction", "WallFriction"),
    "gravity": ("Gravity", "Gravity"),
    # Automatic (the default): the largest step; Fixed: FrameInterval / SubstepsPerFrame.
    "timeStep": ("MaxTimeStep", "MaxTimeStep"),
    "cflNumber": ("CFLNumber", "CFLNumber"),
}
# The domain comes from the scene; sceneSpeedHint is derived from it by pbf::Simulation.
SCENE_FIELDS = {"domain", "sceneSpeedHint"}


def solver_defaults(header):
    """Fields and default values of struct Parameters, parsed from its declaration."""
    text = open(header).read()
    body = re.search(r"struct Parameters\s*\{(.*?)\n\};", text, re.S)
    expect(body, "struct Parameters not found in %s" % header)
    defaults = {}
    for line in body.group(1).splitlines():
        code = line.split("//")[0].strip()
        match = re.match(r"(double|int|bool|Vec3d|Box)\s+(\w+)\s*(?:=\s*([^;]+)|\{([^}]*)\})?\s*;$",
                         code)
        if not match:
            continue
        kind, name, value, braces = match.groups()
        if kind == "Box":
            defaults[name] = None
        elif kind == "bool":
            defaults[name] = {"true": 1, "false": 0}[value.strip()]
        elif kind == "Vec3d":
            defaults[name] = [float(eval(v)) for v in braces.split(",")]
        else:
            # Plain numeric literals and quotients such as 1.0 / 240.0.
            expect(re.fullmatch(r"[0-9eE.+\-/* ()]+", value), "cannot read %s = %s" % (name, value))
            defaults[name] = eval(value)
    expect(len(defaults) >= 10, "read only %s from %s" % (sorted(defaults), header))
    return defaults


header = os.path.join(os.environ.get("PBF_SOURCE_DIR", ""), "Solver", "Physics", "Parameters.h")
defaults = solver_defaults(header)

unexposed = sorted(set(defaults) - set(FIELDS) - SCENE_FIELDS)
expect(not unexposed, "pbf::Parameters fields without a property: %s" % unexposed)

source = PositionBasedFluids()  # noqa: F821 (defined by LoadPlugin)
for field, (prop, _) in FIELDS.items():
    if prop is None:
        continue
    value = source.GetPropertyValue(prop)
    expected = defaults[field]
    if isinstance(expected, list):
        expect(list(value) == expected, "%s default %s, solver %s" % (prop, list(value), expected))
    else:
        expect(value == expected, "%s default %r, solver %s = %r" % (prop, value, field, expected))
expect(source.FrameInterval / source.SubstepsPerFrame == defaults["timeStep"],
       "FrameInterval / SubstepsPerFrame = %r, solver timeStep = %r"
       % (source.FrameInterval / source.SubstepsPerFrame, defaults["timeStep"]))
expect(source.FrameInterval == 1.0 / 60.0 and source.SubstepsPerFrame == 4 and
       source.NumberOfFrames == 120, "time defaults are not 1/60 s, 4 substeps, 120 frames")
# The solver's default is adaptive, at 0.2 %, with automatic time steps.
expect(defaults["densityErrorTolerance"] == 0.2 and source.AdaptiveIterations == 1 and
       source.DensityErrorTolerance == 0.2,
       "adaptive defaults: AdaptiveIterations %r, DensityErrorTolerance %r, solver tolerance %r"
       % (source.AdaptiveIterations, source.DensityErrorTolerance,
          defaults["densityErrorTolerance"]))
expect(source.TimeStepping == "Automatic", "TimeStepping default %r" % source.TimeStepping)
expect(source.CheckpointInterval == 10 and source.CheckpointMemoryMB == 1024,
       "checkpoint defaults: every %r frames, %r MiB"
       % (source.CheckpointInterval, source.CheckpointMemoryMB))

# The defaults as the solver saw them (frame 0 needs no step, so the full dam break is quick).
data = T.output_at(source, 0.0)
expect(data.GetNumberOfPoints() == 20 * 30 * 30,
       "default dam break: %d particles, expected 20 x 30 x 30" % data.GetNumberOfPoints())
for field, (_, array) in FIELDS.items():
    value = T.field_value(data, array)
    expected = defaults[field]
    if isinstance(expected, list):
        expect(list(value) == expected, "solver ran with %s = %s, default %s" % (array, value, expected))
    else:
        expect(value == expected, "solver ran with %s = %r, default %r" % (array, value, expected))
expect(T.field_value(data, "Domain") == (0.0, 1.6, 0.0, 0.8, 0.0, 0.6),
       "the dam break domain is %s" % (T.field_value(data, "Domain"),))

# Every property set to a non-default value reaches the solver.
changed = {
    "RestDensity": 800.0, "ParticleSpacing": 0.05, "SmoothingRatio": 2.5, "SolverIterations": 3,
    "RelaxationEpsilon": 0.02, "SCorrK": 0.05, "SCorrN": 3.0, "SCorrDeltaQ": 0.25,
    "XSPHViscosity": 0.02, "XSPHHyperViscosity": 0.03, "VorticityEpsilon": 0.005, "Unilateral": 0, "MirrorWalls": 0,
    "ExactBoundaries": 0, "TankLoads": 1,
    "WallFriction": 0.25, "ChebyshevRho": 0.5, "SurfaceTension": 0.5, "ContactAngle": 120.0,
    "Gravity": [0.5, -5.0, 0.25], "CFLNumber": 0.3, "MaxTimeStep": 0.005, "MaxDensityErrorTolerance": 3.0,
}
for prop, value in changed.items():
    source.SetPropertyWithName(prop, value)
source.FrameInterval = 0.02
source.SubstepsPerFrame = 5
source.AdaptiveIterations = 1
source.DensityErrorTolerance = 0.5
data = T.output_at(source, 0.02)
expect(T.field_value(data, "DensityErrorTolerance") == 0.5 and
       T.field_value(data, "AdaptiveIterations") == 1,
       "AdaptiveIterations on, DensityErrorTolerance 0.5 reached the solver as %r, %r"
       % (T.field_value(data, "AdaptiveIterations"), T.field_value(data, "DensityErrorTolerance")))
for field, (prop, array) in FIELDS.items():
    if prop is None:
        continue
    got = T.field_value(data, array)
    want = changed[prop]
    if isinstance(want, list):
        expect(list(got) == want, "%s = %s reached the solver as %s" % (prop, want, list(got)))
    else:
        expect(got == want, "%s = %r reached the solver as %r" % (prop, want, got))
# Automatic: frame 1 lands on 0.02 s exactly in steps of at most MaxTimeStep.
expect(T.field_value(data, "Time") == 0.02, "frame 1 at t = %r" % T.field_value(data, "Time"))
expect(T.field_value(data, "TimeStepping") == "Automatic",
       "TimeStepping reached the solver as %r" % T.field_value(data, "TimeStepping"))
# CFL 0.3 at s = 0.05 m and the scene's fall speed of about 3 m/s: steps of about 5 ms.
expect(T.field_value(data, "StepCount") >= 4 and T.field_value(data, "TimeStep") <= 0.005,
       "frame 1 of 0.02 s ran %d steps, the last of %r s (at most 0.005)"
       % (T.field_value(data, "StepCount"), T.field_value(data, "TimeStep")))
# Fixed: SubstepsPerFrame equal steps.
source.TimeStepping = "Fixed"
data = T.output_at(source, 0.02)
expect(T.field_value(data, "TimeStepping") == "Fixed", "TimeStepping Fixed did not reach the solver")
expect(T.field_value(data, "TimeStep") == 0.02 / 5, "dt = %r" % T.field_value(data, "TimeStep"))
expect(T.field_value(data, "StepCount") == 5, "frame 1 at 5 substeps ran %d steps"
       % T.field_value(data, "StepCount"))
expect(T.field_value(data, "SmoothingLength") == 2.5 * 0.05, "h = %r"
       % T.field_value(data, "SmoothingLength"))

# Labels read as words: ParaView splits a name without a label at every capital, so
# XSPHViscosity read "X SPHViscosity". No label may hold a lone capital before an acronym or a
# word run together from an acronym.
labels = {}
for name in source.ListProperties():
    labels[name] = source.GetProperty(name).SMProperty.GetXMLLabel()
for name, label in sorted(labels.items()):
    expect(not re.search(r"\b[A-Z] [A-Z]{2,}|[A-Z]{3,}[a-z]", label),
           "property %s has the label %r" % (name, label))
for name, label in (("XSPHViscosity", "XSPH Viscosity"), ("CFLNumber", "CFL Number")):
    expect(labels.get(name) == label, "%s is labelled %r, expected %r" % (name, labels.get(name), label))
# paraview.simple names a property after its label without the spaces: a label must keep the
# scripting name (SCorrK, not S_corrK), or scripts, traces and states break.
for name in ("XSPHViscosity", "CFLNumber", "SCorrK", "SCorrN", "SCorrDeltaQ", "MaxTimeStep"):
    expect(name in labels, "the scripting name %s is gone (properties: %s)" % (name, sorted(labels)))

T.passed("Parameters")
