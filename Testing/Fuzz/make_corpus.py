#!/usr/bin/env python3
"""Writes the seed corpus of pbf_fuzz_scene into corpus/: the shipped scenes as they are (parsed
and validated at the default spacing, too many particles to step), the same at a coarse spacing
with a parameter tail (stepped), and broken ones. Input format: see FuzzScene.cpp."""
import json
import math
import os
import shutil
import struct

here = os.path.dirname(os.path.abspath(__file__))
corpus = os.path.join(here, "corpus")
data = os.path.join(here, "..", "..", "Data")

# Parameters in FuzzScene.cpp's kFields order, then gravity: the defaults of Parameters.h.
DEFAULTS = dict(particleSpacing=0.02, timeStep=1 / 240, relaxation=0.01, smoothingRatio=2.0,
                restDensity=1000.0, sCorrK=0.1, sCorrN=4.0, sCorrDeltaQ=0.2, xsphViscosity=0.05,
                vorticityEpsilon=0.01, densityErrorTolerance=0.2, maxDensityErrorTolerance=5.0,
                cflNumber=0.4, gx=0.0, gy=-9.81, gz=0.0)


def tail(iterations=40, flags=0, **changes):
    values = dict(DEFAULTS, **changes)
    return (b"\0" + struct.pack("<%dd" % len(values), *values.values()) +
            struct.pack("<bB", iterations, flags))


def scene(name):
    with open(os.path.join(data, name + ".json"), "rb") as f:
        return f.read()


def write(name, content):
    with open(os.path.join(corpus, name), "wb") as f:
        f.write(content)


shutil.rmtree(corpus, ignore_errors=True)
os.makedirs(corpus)
for name in ("dam_break", "double_dam_break", "blob", "stream", "channel"):
    write(name + ".json", scene(name))
write("dam_break_coarse", scene("dam_break") + tail(particleSpacing=0.2))
write("stream_coarse_double", scene("stream") + tail(particleSpacing=0.1, flags=1))
write("blob_given_points_adaptive",
      scene("blob") + tail(particleSpacing=0.2, densityErrorTolerance=0.5, iterations=20, flags=8))
# Fixed steps (flag 16), 4 projections: the old defaults, which blow up here.
write("dam_break_blows_up", scene("dam_break") + tail(particleSpacing=0.2, timeStep=0.05, gy=-1e4,
                                                     densityErrorTolerance=0, iterations=4,
                                                     flags=16))
write("nan_spacing", scene("dam_break") + tail(particleSpacing=math.nan))
# Found by fuzzing: NaN from (W / W(delta_q))^n with n = 2e174 (sCorrN is now at most 16).
write("huge_scorr_n", scene("dam_break") + tail(particleSpacing=0.2, timeStep=0.05, gy=-1e4,
                                               sCorrN=2.2e174, sCorrDeltaQ=6e-154))
# Found by fuzzing: gravity 1.7e156 made the automatic time step 0 (now InvalidInput naming it).
write("automatic_step_underflow", scene("stream") + tail(particleSpacing=0.1, gy=1.7164750796028833e156,
                                                         iterations=40, flags=1))
# Solids: a sphere in the surge's way and a box cutting into the column (its fluid removed).
write("dam_break_obstacles_coarse", json.dumps({
    "domain": {"min": [0, 0, 0], "max": [1.6, 0.8, 0.6]},
    "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.4, 0.6, 0.6]}],
    "obstacles": [{"type": "sphere", "center": [0.9, 0.12, 0.3], "radius": 0.12},
                  {"type": "box", "min": [0.3, -0.5, -0.5], "max": [0.5, 0.2, 0.2]}]}).encode()
      + tail(particleSpacing=0.1))
# Open boundaries: the channel stepped (its inflow by rate, the +x face an outflow), and a dam
# break whose box outflow eats the column's top and a face's slab its far end.
write("channel_coarse", scene("channel") + tail(particleSpacing=0.05))
write("dam_break_outflows_coarse", json.dumps({
    "domain": {"min": [0, 0, 0], "max": [1.6, 0.8, 0.6]},
    "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.4, 0.6, 0.6]}],
    "outflows": [{"min": [0, 0.4, 0], "max": [0.4, 0.8, 0.6]}, {"face": "+x", "depth": 0.3}]}).encode()
      + tail(particleSpacing=0.1))
write("not_json", b"domain: [0, 1]\n")
write("number_beyond_double", b'{"domain": {"min": [0,0,0], "max": [1e400,1,1]}, "fluid": []}')
write("unknown_key", json.dumps({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]}, "fluid": [],
                                  "colour": "blue"}).encode())
