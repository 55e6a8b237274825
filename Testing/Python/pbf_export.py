"""Saving all time steps with ParaView 5.11's writers writes every frame, and the files read back
identical to the live output: a .pvd series of .vtp files (DataMode Binary and Ascii), a .vtpc
file series (through Group Datasets, the only way 5.11 writes a partitioned dataset collection),
and the diagnostics table as CSV. 5.11 has a VTKHDF reader but no VTKHDF writer.

Not the XML writers' default appended raw data: this Debian's expat fails to read appended data
of more than a few hundred values back ("not well-formed (invalid token)"); Binary (inline base64)
and Ascii read back."""
import csv
import glob
import os
import shutil
import sys
import tempfile

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import simple  # noqa: E402

T.load_plugin(globals())
expect = T.expect

FRAMES = 4
INTERVAL = 1.0 / 60.0
folder = tempfile.mkdtemp(prefix="pbf_export_")
source = PositionBasedFluids(ParticleSpacing=T.QUICK_SPACING, NumberOfFrames=FRAMES,  # noqa: F821
                             SubstepsPerFrame=2)
live = {k: T.frame(source, k * INTERVAL) for k in range(FRAMES + 1)}

# .pvd + .vtp, every time step, inline binary and ASCII.
for mode in ("Binary", "Ascii"):
    series = os.path.join(folder, mode, "fluid.pvd")
    simple.SaveData(series, proxy=source, WriteTimeSteps=1, DataMode=mode)
    files = sorted(glob.glob(os.path.join(folder, mode, "fluid", "*.vtp")))
    expect(len(files) == FRAMES + 1, "%s: %d .vtp files for %d frames" % (mode, len(files), FRAMES + 1))
    reader = simple.PVDReader(FileName=series)
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues)
    # The .pvd file writes its times with 6 significant digits; the data files are exact.
    expect(numpy.allclose(times, [k * INTERVAL for k in range(FRAMES + 1)], rtol=1e-5, atol=0),
           "%s: the series has times %s" % (mode, times))
    for k, t in enumerate(times):
        again = T.frame(reader, t)
        expect(again["frame"] == k, "%s: time %g holds frame %d" % (mode, t, again["frame"]))
        T.expect_identical(again, live[k], "%s .pvd, frame %d" % (mode, k))
    simple.Delete(reader)

# .vtpc file series: one collection per frame holding the frame's particles.
group = simple.GroupDatasets(Input=source, OutputType="vtkPartitionedDataSetCollection")
simple.SaveData(os.path.join(folder, "vtpc", "fluid.vtpc"), proxy=group,
                Writetimestepsasfileseries=1, DataMode="Binary")
files = sorted(glob.glob(os.path.join(folder, "vtpc", "fluid_*.vtpc")),
               key=lambda f: int(f.rsplit("_", 1)[1].split(".")[0]))
expect(len(files) == FRAMES + 1, ".vtpc: %d files for %d frames" % (len(files), FRAMES + 1))
for k, path in enumerate(files):
    reader = simple.XMLPartitionedDatasetCollectionReader(FileName=[path])
    reader.UpdatePipeline()
    collection = reader.GetClientSideObject().GetOutputDataObject(0)
    again = T.particles_of(collection.GetPartition(0, 0))
    expect(again["frame"] == k, ".vtpc: %s holds frame %d" % (path, again["frame"]))
    T.expect_identical(again, live[k], ".vtpc, frame %d" % k)
    simple.Delete(reader)

# The diagnostics table as CSV, with every digit a double has.
table = T.diagnostics(source)
csv_path = os.path.join(folder, "diagnostics.csv")
simple.SaveData(csv_path, proxy=simple.OutputPort(source, 1), Precision=17, UseScientificNotation=1)
with open(csv_path, newline="") as stream:
    rows = list(csv.DictReader(stream))
expect(len(rows) == FRAMES + 1, "the CSV has %d rows" % len(rows))
for name in ("Time", "Frame", "AverageDensityError", "MaxDensityError", "AverageNeighbors",
             "SolverIterations", "MillisecondsPerStep", "MaxSpeed", "KineticEnergy", "Particles"):
    column = numpy.array([float(row[name]) for row in rows])
    expect(numpy.array_equal(column, table[name].astype(float), equal_nan=True),
           "the CSV column %s differs: %s vs %s" % (name, column, table[name]))
expect([row["Backend"] for row in rows] == table["Backend"],
       "the CSV backend column %s" % [row["Backend"] for row in rows])

shutil.rmtree(folder)
T.passed("Export")
