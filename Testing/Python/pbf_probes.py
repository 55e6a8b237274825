"""Probes in ParaView: the points of a Poly Line source on the Probes input read the water at rest
in the hydrostatic tank (0.6 m deep). The Probes output (port 4) has a row per probe: a probe on
the floor reads the water's depth, one in the water the depth above it and rho_0 g d, one in the
air nothing, one outside the domain NaN (with a warning, not an error). Probes do not change the
particles, and Plot Data Over Time on the table gives each probe's curve."""
import os
import sys

import numpy
from paraview import simple
from vtk.util import numpy_support

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402

T.load_plugin(globals())
expect = T.expect

S = 0.05
DEPTH = 0.6
RHO_G = 1000.0 * 9.81
INTERVAL = 1.0 / 60.0
FRAMES = 60
scene = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "Validation",
                     "hydrostatic_tank.json")
# The floor, two depths in the water, the air, and a point outside the 0.4 x 0.8 x 0.4 m domain.
PROBES = [(0.2, 0.0, 0.2), (0.2, 0.2, 0.2), (0.2, 0.4, 0.2), (0.2, 0.75, 0.2), (1.0, 0.2, 0.2)]
line = simple.PolyLineSource(Points=[c for p in PROBES for c in p])
source = PositionBasedFluids(SceneFile=scene, ParticleSpacing=S, NumberOfFrames=FRAMES,  # noqa: F821
                             Backend="CPU (OpenMP)", Probes=line)
plain = PositionBasedFluids(SceneFile=scene, ParticleSpacing=S, NumberOfFrames=FRAMES,  # noqa: F821
                            Backend="CPU (OpenMP)")


def table_at(time):
    source.UpdatePipeline(time)
    table = source.GetClientSideObject().GetOutputDataObject(4)
    return {table.GetColumn(c).GetName(): numpy_support.vtk_to_numpy(table.GetColumn(c)).copy()
            for c in range(table.GetNumberOfColumns())}


_, messages = T.capture_messages(lambda: source.UpdatePipeline(0.0))
expect("probe 4 at (1, 0.2, 0.2)" in messages and "outside the domain" in messages,
       "no warning names the probe outside the domain: %s" % messages)
first = table_at(0.0)
for name, components in (("Probe", 1), ("Position", 3), ("velocity", 3), ("pressure", 1),
                         ("WaterHeight", 1), ("FluidFraction", 1)):
    expect(name in first, "the Probes table has no %s column (%s)" % (name, sorted(first)))
    shape = (len(PROBES),) if components == 1 else (len(PROBES), components)
    expect(first[name].shape == shape, "%s has shape %s" % (name, first[name].shape))
expect(numpy.array_equal(first["Probe"], numpy.arange(len(PROBES))), "Probe %s" % first["Probe"])
expect(numpy.allclose(first["Position"], PROBES), "Position %s" % first["Position"])
# Frame 0 is the lattice, before any step: heights already, no pressure yet (particles have none).
expect(abs(first["WaterHeight"][0] - DEPTH) <= 0.25 * S,
       "frame 0: the floor probe reads %.4f m of a %.2f m column" % (first["WaterHeight"][0], DEPTH))
expect(numpy.all(first["pressure"][:4] == 0), "frame 0 reads a pressure %s" % first["pressure"])
expect(numpy.all(numpy.isnan(first["pressure"][4])) and numpy.isnan(first["WaterHeight"][4]) and
       numpy.all(numpy.isnan(first["velocity"][4])), "the probe outside reads %s" % first["pressure"][4])

# Water at rest, frames 30-60 (0.5-1 s): the means per probe.
rows = [table_at(k * INTERVAL) for k in range(FRAMES // 2, FRAMES + 1)]
pressure = numpy.mean([r["pressure"] for r in rows], axis=0)
height = numpy.mean([r["WaterHeight"] for r in rows], axis=0)
speed = numpy.max([numpy.linalg.norm(r["velocity"][:4], axis=1) for r in rows])
for k, (x, y, z) in enumerate(PROBES[:3]):
    print("probe %d at y = %.2f m: water height %.4f m (column %.4f m), pressure %.1f Pa "
          "(rho g d %.1f Pa, %+.2f %%)" % (k, y, height[k], DEPTH - y, pressure[k], RHO_G * (DEPTH - y),
                                         100 * (pressure[k] / (RHO_G * (DEPTH - y)) - 1)))
    # The settled column's surface within half a spacing of the lattice's top.
    expect(abs(height[k] - (DEPTH - y)) < 0.5 * S,
           "probe %d reads %.4f m of water above it, expected %.2f" % (k, height[k], DEPTH - y))
# In the water, rho_0 g d within 12 % at this coarse spacing (measured over 0.5-1 s: +5.1 % on the
# floor, -5.4 % and -9.4 % at 0.2 and 0.4 m). An 8 x 8 column of particles settles with pressures
# that differ by several % from layer to layer (Pressure.WaterAtRestIsHydrostatic bounds the
# layers' means over 12 x 12 columns by 6 %); at 2.5 cm the probes read -1 % to -7 % once settled
# (Documentation/ValidationBoundaries.md). A lost factor (dt, rho_0) is far outside.
for k in (0, 1, 2):
    d = DEPTH - PROBES[k][1]
    expect(abs(pressure[k] / (RHO_G * d) - 1) < 0.12,
           "probe %d reads %.1f Pa at depth %.2f m (rho g d %.1f Pa)" % (k, pressure[k], d, RHO_G * d))
expect(height[3] == 0 and pressure[3] == 0, "the probe in the air reads %.4f m, %.1f Pa" % (height[3], pressure[3]))
expect(speed < 0.05, "water at rest moves at %.3f m/s at a probe" % speed)

# The probe is the particles' poly6 sum (Solver/Surface/Probes.h), recomputed here from the frame's
# particles: F = sum_j (m / rho_0) W_ij and the pressure sum_j (m / rho_0) W_ij p_j / max(F, 1/2),
# to float rounding (1e-5 relative).
last = T.output_at(source, FRAMES * INTERVAL)
x = numpy_support.vtk_to_numpy(last.GetPoints().GetData()).astype(float)
p = numpy_support.vtk_to_numpy(last.GetPointData().GetArray("pressure")).astype(float)
h = T.field_value(last, "SmoothingLength")
volume = T.field_value(last, "ParticleMass") / T.field_value(last, "RestDensity")
r2 = numpy.sum((x - numpy.array(PROBES[1])) ** 2, axis=1)
w = numpy.where(r2 < h * h, 315.0 / (64.0 * numpy.pi * h ** 9) * (h * h - r2) ** 3, 0.0) * volume
expected = numpy.sum(w * p) / max(numpy.sum(w), 0.5)
read = table_at(FRAMES * INTERVAL)
expect(abs(read["FluidFraction"][1] - numpy.sum(w)) < 1e-5 and
       abs(read["pressure"][1] - expected) < 1e-5 * abs(expected),
       "probe 1 reads F %.6f, %.3f Pa; the particles give F %.6f, %.3f Pa"
       % (read["FluidFraction"][1], read["pressure"][1], numpy.sum(w), expected))

# Probes never change the simulation: the particles are those of the same run without them.
with_probes = T.frame(source, FRAMES * INTERVAL)
without = T.frame(plain, FRAMES * INTERVAL)
T.expect_identical(with_probes, without, "frame %d with and without probes" % FRAMES)

# Plot Data Over Time on the table (its rows): a curve per probe over every frame, the rows the
# table had at each frame.
over_time = simple.PlotDataOverTime(Input=simple.OutputPort(source, 4),
                                    OnlyReportSelectionStatistics=0, FieldAssociation="Rows")
over_time.UpdatePipeline()
curves = simple.servermanager.Fetch(over_time)
expect(curves.GetNumberOfBlocks() == len(PROBES),
       "Plot Data Over Time gives %d curves for %d probes" % (curves.GetNumberOfBlocks(), len(PROBES)))
curve = curves.GetBlock(1)
expect(curve.GetNumberOfRows() == FRAMES + 1, "probe 1's curve has %d rows" % curve.GetNumberOfRows())
over = numpy_support.vtk_to_numpy(curve.GetColumnByName("pressure"))
expect(abs(over[FRAMES] - read["pressure"][1]) <= 1e-9 * abs(read["pressure"][1]),
       "the curve's last pressure %.3f Pa, the table's %.3f Pa" % (over[FRAMES], read["pressure"][1]))
T.passed("Probes")
