"""The main job (Utilities/dam_break.py) in a short run: it writes a .pvd time series with one .vtp
per frame holding every particle, the diagnostics as CSV (a row per frame), and one PNG per frame
in which the particles are visible.

Runs with the system python3 (matplotlib reads the PNGs), pvbatch under a private Xvfb:
    python3 pbf_dam_break_job.py --pvbatch P --script dam_break.py --plugin SO --output DIR"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

import numpy
from matplotlib import image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pbf_xvfb import run_with_xvfb  # noqa: E402

FRAMES = 3
SPACING = 0.05
PARTICLES = 8 * 12 * 12  # the dam break column 0.4 x 0.6 x 0.6 m at 0.05 m


def fail(message):
    sys.exit("pbf_dam_break_job: FAILED: " + message)


parser = argparse.ArgumentParser()
for name in ("--pvbatch", "--script", "--plugin", "--output"):
    parser.add_argument(name, required=True)
args = parser.parse_args()

shutil.rmtree(args.output, ignore_errors=True)
command = [args.pvbatch, "--dr", args.script, "--plugin", args.plugin,
           "--output", args.output, "--frames", str(FRAMES), "--spacing", str(SPACING),
           "--size", "640", "360"]
print(" ".join(command))
run = run_with_xvfb(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
print(run.stdout)
if run.returncode != 0:
    fail("dam_break.py exited with %d" % run.returncode)
if re.search(r"(^|\n)ERROR: |ERR\||Traceback", run.stdout):
    fail("dam_break.py reported an error")

# The time series: frames k / 60 s, each file with every particle and its arrays.
series = os.path.join(args.output, "dam_break.pvd")
if not os.path.isfile(series):
    fail("no %s" % series)
datasets = ElementTree.parse(series).getroot().findall("./Collection/DataSet")
if len(datasets) != FRAMES + 1:
    fail("the series lists %d datasets, expected %d" % (len(datasets), FRAMES + 1))
for k, dataset in enumerate(datasets):
    time = float(dataset.get("timestep"))
    # The writer prints 6 significant digits.
    if abs(time - k / 60.0) > 1e-6:
        fail("dataset %d is at t = %g, expected %g" % (k, time, k / 60.0))
    path = os.path.join(args.output, dataset.get("file"))
    if not path.endswith(".vtp") or not os.path.isfile(path):
        fail("dataset %d: no .vtp file %s" % (k, path))
    with open(path, "rb") as f:
        header = f.read().decode("latin-1")
    piece = re.search(r'<Piece NumberOfPoints="(\d+)"\s+NumberOfVerts="(\d+)"', header)
    if not piece or int(piece.group(1)) != PARTICLES or int(piece.group(2)) != PARTICLES:
        fail("%s does not hold %d particles as vertices" % (path, PARTICLES))
    for array in ("density", "lambda", "velocity", "id", "ParticleMass", "SmoothingLength"):
        if 'Name="%s"' % array not in header:
            fail("%s has no %s array" % (path, array))

# The diagnostics: a row per frame written, in order.
diagnostics = os.path.join(args.output, "dam_break_diagnostics.csv")
if not os.path.isfile(diagnostics):
    fail("no %s" % diagnostics)
with open(diagnostics) as f:
    rows = f.read().splitlines()
if len(rows) != FRAMES + 2 or "AverageDensityError" not in rows[0]:
    fail("%s holds %d lines, expected a header and %d rows" % (diagnostics, len(rows), FRAMES + 1))

# The pictures: one per frame, particles over the background (the most common color).
for k in range(FRAMES + 1):
    path = os.path.join(args.output, "frames", "frame_%04d.png" % k)
    if not os.path.isfile(path):
        fail("no %s" % path)
    pixels = (image.imread(path)[:, :, :3] * 255).round().astype(int)
    if pixels.shape[:2] != (360, 640):
        fail("%s is %dx%d, expected 640x360" % (path, pixels.shape[1], pixels.shape[0]))
    flat = pixels.reshape(-1, 3)
    colors, counts = numpy.unique(flat, axis=0, return_counts=True)
    background = colors[counts.argmax()]
    foreground = numpy.any(flat != background, axis=1)
    # The column alone covers about 5% of this view; the tank's outline and the labels well
    # under 1%, so 2% means particles are drawn.
    if foreground.mean() < 0.02:
        fail("%s: only %.2f%% of the picture differs from the background"
             % (path, 100 * foreground.mean()))
    if k == FRAMES:
        hues = {tuple(c // 16) for c in flat[foreground]}
        if len(hues) < 8:
            fail("%s: the particles show %d colors, not a velocity color map" % (path, len(hues)))
print("pbf_dam_break_job: passed (%d frames written and rendered)" % (FRAMES + 1))
