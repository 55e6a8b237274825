"""MARIN's pressure sensors P1-P4 against the record: pbf_marin --csv's series (one P column per
sensor and spacing) and Testing/Validation/marin_2005_pressure.csv, both as 25 ms running means
(centred) for the first impact's peak over t < 1 s, and the first sample above 1 kPa for the
arrival. Prints a Markdown table (relative peak, arrival lag) and draws the figure.

    python3 Utilities/validation/marin_pressure.py marin.csv [OUT.png]
"""
import os
import sys

import numpy as np

DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                    "Testing", "Validation")
WINDOW = 0.025   # [s] the means' length
IMPACT = 1000.0  # [Pa] the first wave, clear of the sensors' noise
HORIZON = 1.0    # [s] the first impact's window


def running_mean(t, p):
    """The mean of the samples within WINDOW / 2 of each one."""
    out = np.empty_like(p)
    for k, tk in enumerate(t):
        near = np.abs(t - tk) <= 0.5 * WINDOW + 1e-9
        out[k] = p[near].mean()
    return out


def impact(t, p):
    """(peak of the 25 ms means over t < 1 s, first time above IMPACT)."""
    first = t < HORIZON
    smooth = running_mean(t[first], p[first])
    above = np.nonzero(p[first] > IMPACT)[0]
    return smooth.max(), (t[first][above[0]] if above.size else float("nan"))


def main(simulated, figure=None):
    with open(simulated) as f:
        header = f.readline().strip().split(",")
    runs = np.genfromtxt(simulated, delimiter=",", skip_header=1)
    record = np.genfromtxt(os.path.join(DATA, "marin_2005_pressure.csv"), delimiter=",",
                           skip_header=2)
    spacings = [name.split("_", 1)[1] for name in header if name.startswith("P1_")]
    print("| sensor | peak, record | " + " | ".join("%s m" % s for s in spacings) +
          " | arrival, record | " + " | ".join("%s m" % s for s in spacings) + " |")
    print("|---|---:|" + "---:|" * len(spacings) + "---:|" + "---:|" * len(spacings))
    for sensor in range(1, 5):
        peak, arrival = impact(record[:, 0], record[:, sensor])
        peaks, lags = [], []
        for s in spacings:
            k = header.index("P%d_%s" % (sensor, s))
            p, a = impact(runs[:, 0], runs[:, k])
            peaks.append("%+.0f %%" % (100 * (p / peak - 1)))
            lags.append("%+.0f ms" % (1000 * (a - arrival)))
        print("| P%d | %.0f Pa | %s | %.3f s | %s |" % (sensor, peak, " | ".join(peaks), arrival,
                                                       " | ".join(lags)))
    if figure:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
        for sensor, axis in zip(range(1, 5), axes):
            first = record[:, 0] < 2.0
            axis.plot(record[first, 0], running_mean(record[first, 0], record[first, sensor]),
                      color="black", lw=1.4, label="experiment, 25 ms means")
            for s, color in zip(spacings, ("tab:orange", "tab:blue", "tab:green")):
                k = header.index("P%d_%s" % (sensor, s))
                keep = runs[:, 0] < 2.0
                axis.plot(runs[keep, 0], runs[keep, k], color=color, lw=0.5, alpha=0.5)
                axis.plot(runs[keep, 0], running_mean(runs[keep, 0], runs[keep, k]), color=color,
                          lw=1.2, label="PBF, s = %s m, 25 ms means" % s)
            axis.set_ylabel("P%d [Pa]" % sensor)
            axis.grid(alpha=0.3)
        axes[0].legend(loc="upper right", fontsize=7)
        axes[-1].set_xlabel("t [s]")
        fig.suptitle("MARIN box: pressure at P1-P4 (thin: each frame's mean over its steps)")
        fig.tight_layout()
        fig.savefig(figure, dpi=72)


if __name__ == "__main__":
    main(*sys.argv[1:])
