"""Figure of the Kramer et al. (2021) floating sphere: the simulated heave of each drop (pbf_kramer
--csv: spacing, drop, t, heave, record) against the measured record, one panel per drop.

    python3 Utilities/validation/kramer_plot.py kramer.csv [more.csv ...] OUT.png
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(inputs, figure):
    rows = np.vstack([np.genfromtxt(name, delimiter=",", skip_header=1) for name in inputs])
    drops = sorted(set(rows[:, 1]))
    fig, axes = plt.subplots(len(drops), 1, figsize=(8, 2.4 * len(drops)), sharex=True,
                             squeeze=False)
    for axis, drop in zip(axes[:, 0], drops):
        of_drop = rows[rows[:, 1] == drop]
        first = of_drop[of_drop[:, 0] == of_drop[0, 0]]
        axis.plot(first[:, 2], 1e3 * first[:, 4], color="black", lw=1.2, label="experiment")
        for spacing, color in zip(sorted(set(of_drop[:, 0]), reverse=True),
                                  ("tab:orange", "tab:blue", "tab:green")):
            run = of_drop[of_drop[:, 0] == spacing]
            axis.plot(run[:, 2], 1e3 * run[:, 3], color=color, lw=1.0,
                      label="PBF, D / s = %.0f" % (0.3 / spacing))
        axis.set_ylabel("heave [mm], %.1f D" % drop)
        axis.grid(alpha=0.3)
        axis.legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("t after the release [s]")
    fig.tight_layout()
    fig.savefig(figure, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1:-1], sys.argv[-1])
