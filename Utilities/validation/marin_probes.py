"""MARIN's wave gauges H2 and H4 read in ParaView: the marin_dam_break preset with a Probes input
(a Poly Line Source through the two gauges' feet on the tank's floor) and Plot Data Over Time on
the Probes output, against the records in Testing/Validation. Writes the figure and the curves.

    PBF_PLUGIN=build/lib/paraview-5.11/plugins/PositionBasedFluids/PositionBasedFluids.so \\
      pvbatch Utilities/validation/marin_probes.py [spacing] [until] [figure.png]

The defaults (4 cm to 6 s on the CPU, a few minutes here) draw Documentation/images/marin_probes.png.
"""
import os
import sys

import numpy
from paraview import simple
from vtk.util import numpy_support

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RECORDS = os.path.join(ROOT, "Testing", "Validation")
GAUGES = {"H2": (0.992, 0.0, 0.5), "H4": (2.638, 0.0, 0.5)}  # the project's axes, y up


def record(name):
    return numpy.genfromtxt(os.path.join(RECORDS, "marin_2005_%s.csv" % name), delimiter=",",
                            skip_header=2)


def main(spacing, until, figure):
    simple.LoadPlugin(os.environ["PBF_PLUGIN"], remote=False, ns=globals())
    interval = 1.0 / 60.0
    frames = int(round(until / interval))
    probes = simple.PolyLineSource(Points=[c for name in GAUGES for c in GAUGES[name]])
    source = PositionBasedFluids(Preset="marin_dam_break", ParticleSpacing=spacing,  # noqa: F821
                                 NumberOfFrames=frames, Backend="CPU (OpenMP)", Probes=probes)
    over_time = simple.PlotDataOverTime(Input=simple.OutputPort(source, 4),
                                        OnlyReportSelectionStatistics=0, FieldAssociation="Rows")
    over_time.UpdatePipeline()
    curves = simple.servermanager.Fetch(over_time)
    simulated = {}
    for k, name in enumerate(GAUGES):
        table = curves.GetBlock(k)
        simulated[name] = (numpy_support.vtk_to_numpy(table.GetColumnByName("Time")),
                           numpy_support.vtk_to_numpy(table.GetColumnByName("WaterHeight")))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    with open(os.path.splitext(figure)[0] + ".csv", "w") as out:
        out.write("t,H2,H4\n")
        for row in zip(simulated["H2"][0], simulated["H2"][1], simulated["H4"][1]):
            out.write("%.5f,%.5f,%.5f\n" % row)
    for axis, name in zip(axes, GAUGES):
        measured = record(name)
        t, height = simulated[name]
        rms = numpy.sqrt(numpy.mean((height - numpy.interp(t, measured[:, 0], measured[:, 1])) ** 2))
        print("%s: RMS %.4f m against the record over 0-%.1f s" % (name, rms, until))
        axis.plot(measured[:, 0], measured[:, 1], color="black", lw=1.2, label="experiment")
        axis.plot(t, height, color="tab:blue", lw=1.0,
                  label="ParaView Probes, s = %g m (RMS %.3f m)" % (spacing, rms))
        axis.set_ylabel("%s water height [m]" % name)
        axis.set_xlim(0, until)
        axis.grid(alpha=0.3)
        axis.legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(figure, dpi=80)


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 0.04,
         float(sys.argv[2]) if len(sys.argv) > 2 else 6.0,
         sys.argv[3] if len(sys.argv) > 3 else os.path.join(ROOT, "Documentation", "images",
                                                            "marin_probes.png"))
