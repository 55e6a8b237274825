"""Figure of the MARIN dam break: the simulated water heights at gauges H2 and H4 (pbf_marin
--csv, one pair of columns per spacing) against the measured records next to this script.

    python3 Utilities/validation/marin_plot.py output/gpu-run/resolution/marin.csv OUT.png
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                    "Testing", "Validation")  # the experiments' records


def record(name):
    return np.genfromtxt(os.path.join(DATA, "marin_2005_%s.csv" % name), delimiter=",",
                         skip_header=2)


def main(simulated, figure):
    with open(simulated) as f:
        header = f.readline().strip().split(",")
    runs = np.genfromtxt(simulated, delimiter=",", skip_header=1)
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    for axis, gauge in zip(axes, ("H2", "H4")):
        measured = record(gauge)
        axis.plot(measured[:, 0], measured[:, 1], color="black", lw=1.2, label="experiment")
        columns = [k for k, name in enumerate(header) if name.startswith(gauge + "_")]
        for k, color in zip(columns, ("tab:orange", "tab:blue", "tab:green")):
            spacing = header[k].split("_", 1)[1]
            axis.plot(runs[:, 0], runs[:, k], color=color, lw=1.0, label="PBF, s = %s m" % spacing)
        axis.set_ylabel("%s water height [m]" % gauge)
        axis.set_xlim(0, runs[-1, 0])
        axis.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("t [s]")
    fig.suptitle("MARIN dam break with a box (Kleefsman et al. 2005)")
    fig.tight_layout()
    fig.savefig(figure, dpi=72)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
