"""Figures and tables of validate.py's runs. Reads the runs' CSVs and summaries from the results
folder (output/validation/) and writes the figures beside them: they record one machine's runs,
so they stay out of the tree like the data they are drawn from."""
import glob
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                    "Testing", "Validation")  # the experiments' records
DPI = 80
ACROSS = [10, 20, 40, 80]
COLORS = {10: "tab:orange", 20: "tab:green", 40: "tab:blue", 80: "tab:purple"}


def csv(path):
    return np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")


def summary(path):
    """key,value lines and the per-point table of a pbf_martin_moyce output."""
    values, table = {}, []
    for line in open(path):
        parts = line.strip().split(",")
        if len(parts) == 2:
            try:
                values[parts[0]] = float(parts[1])
            except ValueError:
                pass
        elif len(parts) == 4 and parts[0][0].isdigit():
            table.append([float(p) for p in parts])
    return values, np.array(table)


def arrival(front, z):
    """T at which the front first reaches z, interpolated (NaN when never)."""
    T, Z = front["T"], front["Z"]
    for k in range(1, len(T)):
        if Z[k] >= z > Z[k - 1]:
            return T[k - 1] + (z - Z[k - 1]) / (Z[k] - Z[k - 1]) * (T[k] - T[k - 1])
    return float("nan")


def relative(front, exp, shift):
    t = np.array([arrival(front, z) for z in exp["Z"]]) + shift
    return (t - exp["T"]) / exp["T"]


def rms_relative(front, exp, shift, first=0):
    return float(np.sqrt(np.mean(relative(front, exp, shift)[first:] ** 2)))


def save(fig, results, name):
    path = os.path.join(results, name)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    print("wrote %s (%d kB)" % (os.path.relpath(path), os.path.getsize(path) // 1024))


def martin_moyce(results, exp):
    fronts = {n: csv(os.path.join(results, "mm_%d_front.csv" % n)) for n in ACROSS}
    info = {n: summary(os.path.join(results, "mm_%d.txt" % n))[0] for n in ACROSS}
    finest = max(ACROSS)
    # The supplementary view's one shift: least squares on T on the finest run, used everywhere.
    shift = float(np.mean(exp["T"] - [arrival(fronts[finest], z) for z in exp["Z"]]))

    print("\n### Martin & Moyce: RMS of relative arrival-time differences over the 15 points\n")
    print("| particles across a | particles | steps | dt [s] | RMS, T = 0 at release | "
          "supplementary: RMS, shifted by %.3f | the same without the first point | "
          "late dZ/dT (Z 2.56-4.11) |" % shift)
    print("|---|---|---|---|---|---|---|---|")
    for n in ACROSS:
        f = fronts[n]
        t1, t2 = arrival(f, 2.56), arrival(f, 4.11)
        print("| %d | %d | %d | %.3g | **%.1f %%** | %.1f %% | %.1f %% | %.2f |" % (
            n, info[n]["particles"], info[n]["steps"], info[n]["dt"],
            100 * rms_relative(f, exp, 0), 100 * rms_relative(f, exp, shift),
            100 * rms_relative(f, exp, shift, first=1), (4.11 - 2.56) / (t2 - t1)))
    print("| experiment | | | | | | | %.2f |" % ((4.11 - 2.56) / (3.33 - 2.20)))
    print("\nPer point, (T_sim - T_exp) / T_exp in %, T = 0 at release / shifted:\n")
    print("| Z | " + " | ".join("%.2f" % z for z in exp["Z"]) + " |")
    print("|---" * (len(exp) + 1) + "|")
    print("| T_exp | " + " | ".join("%.2f" % t for t in exp["T"]) + " |")
    for n in ACROSS:
        for s, tag in [(0.0, ""), (shift, " shifted")]:
            print("| %d%s | " % (n, tag) + " | ".join(
                "%+.0f" % (100 * r) for r in relative(fronts[n], exp, s)) + " |")

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, s, title in [(axes[0], 0.0, "T = 0 at release (the data's convention)"),
                         (axes[1], shift, "supplementary: simulation shifted by "
                          "T0 = %.3f (fitted at %d across)" % (shift, finest))]:
        for n in ACROSS:
            ax.plot(fronts[n]["T"] + s, fronts[n]["Z"], color=COLORS[n],
                    label="PBF, %d across (RMS %.1f %%)" % (n, 100 * rms_relative(fronts[n], exp, s)))
        ax.plot(exp["T"], exp["Z"], "ko", ms=4, label="Martin & Moyce 1952")
        ax.set_xlim(0, 3.6)
        ax.set_ylim(1, 4.3)
        ax.set_xlabel("T = t sqrt(2g/a)")
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    axes[0].set_ylabel("Z = x_front / a")
    fig.tight_layout()
    save(fig, results, "martin_moyce_front.png")

    # The lead per tabulated point, and the time-step / s_corr check at 20 across.
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    ax = axes[0]
    for n in ACROSS:
        lead = exp["T"] - [arrival(fronts[n], z) for z in exp["Z"]]
        ax.plot(exp["Z"], lead, "o-", ms=3, color=COLORS[n], label="%d across" % n)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("Z (tabulated points)")
    ax.set_ylabel("T_experiment - T_simulated")
    ax.set_title("the simulated front's lead in time", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax = axes[1]
    checks = [("mm_20", "default: dt, s_corr k = 0.1", "tab:green", "-"),
              ("mm_20_dt_half", "dt / 2", "tab:green", "--"),
              ("mm_20_k0", "s_corr off (k = 0)", "tab:red", "-"),
              ("mm_20_k0_dt_half", "s_corr off, dt / 2", "tab:red", "--")]
    print("\nWithout s_corr (k = 0): " + ", ".join("%d across %.1f %%" % (
        n, 100 * rms_relative(csv(os.path.join(results, "mm_%d_k0_front.csv" % n)), exp, 0))
        for n in [10, 20, 40]))
    print("\n### Time-step check at 20 across\n")
    print("| run | RMS, T = 0 at release |")
    print("|---|---|")
    for name, label, color, style in checks:
        f = csv(os.path.join(results, name + "_front.csv"))
        r = rms_relative(f, exp, 0)
        print("| %s | %.1f %% |" % (label, 100 * r))
        ax.plot(f["T"], f["Z"], style, color=color, label="%s (RMS %.1f %%)" % (label, 100 * r))
    ax.plot(exp["T"], exp["Z"], "ko", ms=4, label="Martin & Moyce 1952")
    ax.set_xlim(0, 3.6)
    ax.set_ylim(1, 4.3)
    ax.set_xlabel("T")
    ax.set_ylabel("Z")
    ax.set_title("20 across: halving dt, with and without s_corr", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    save(fig, results, "martin_moyce_checks.png")
    return shift


def window_means(rows, start):
    keep = rows["time"] >= start - 1e-9
    return (float(np.mean(rows["avg_error"][keep])), float(np.max(rows["max_error"][keep])),
            float(np.mean(rows["iterations_per_step"][keep])))


def tank(results):
    cases = [("tank_it1", "1"), ("tank_it2", "2"), ("tank_it4", "4"), ("tank_it8", "8"),
             ("tank_adaptive", "adaptive 0.1 %")]
    print("\n### Hydrostatic tank (12,000 particles, 30 layers): settled 1.5 s, window 1.5-2 s\n")
    print("| iterations | average error | max error | iterations per step | note |")
    print("|---|---|---|---|---|")
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    labels, averages, maxima = [], [], []
    for name, label in cases:
        path = os.path.join(results, name + ".csv")
        rows = csv(path)
        err = open(os.path.join(results, name + ".err")).read()
        diverged = "diverged" in err
        if diverged or len(np.atleast_1d(rows)) < 2:
            print("| %s | - | - | - | blew up: %s |" % (
                label, err.split("pbf_validation_run: ")[-1].split(". Likely")[0].strip()))
            continue
        a, m, it = window_means(rows, 1.5)
        print("| %s | %.3f %% | %.2f %% | %.1f | |" % (label, 100 * a, 100 * m, it))
        labels.append(label)
        averages.append(100 * a)
        maxima.append(100 * m)
        axes[1].plot(rows["time"], 100 * rows["avg_error"], label=label)
    x = np.arange(len(labels))
    axes[0].bar(x - 0.2, averages, 0.4, label="average")
    axes[0].bar(x + 0.2, maxima, 0.4, label="max")
    axes[0].axhline(0.1, color="k", lw=0.8, ls=":")
    axes[0].set_yscale("log")
    axes[0].set_xticks(x)
    axes[0].set_xticklabels(labels, fontsize=8)
    axes[0].set_xlabel("solver iterations per step (1: blew up, not shown)")
    axes[0].set_ylabel("compression after settling [%]")
    axes[0].legend(fontsize=8)
    axes[0].grid(alpha=0.3, axis="y")
    axes[1].set_yscale("log")
    axes[1].set_ylim(0.03, 10)
    axes[1].axvspan(1.5, 2.0, color="0.9")
    axes[1].axhline(0.1, color="k", lw=0.8, ls=":")
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylabel("average compression [%]")
    axes[1].set_title("hydrostatic tank over time (grey: the window)", fontsize=9)
    axes[1].legend(fontsize=7)
    axes[1].grid(alpha=0.3)
    fig.tight_layout()
    save(fig, results, "hydrostatic_tank.png")


def dam_break_density(results):
    cases = [("mm_20_it1", "1"), ("mm_20_it2", "2"), ("mm_20", "4 (default)"),
             ("mm_20_it8", "8"), ("mm_20_adaptive", "adaptive 0.1 %")]
    print("\n### Dam break (Martin & Moyce, 20 across, 3,200 particles) while it moves, "
          "T = 0 to 3.4\n")
    print("| iterations | average error (mean over time) | max error (largest seen) | "
          "iterations per step | RMS front error |")
    print("|---|---|---|---|---|")
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    for name, label in cases:
        rows = csv(os.path.join(results, name + "_density.csv"))
        info = summary(os.path.join(results, name + ".txt"))[0]
        moving = rows["T"] > 0
        if info.get("exit_status", 0) != 0:
            err = open(os.path.join(results, name + ".err")).read()
            print("| %s | - | - | - | blew up: %s |" % (
                label, err.split("pbf_martin_moyce: ")[-1].split(". Likely")[0].strip()))
            label += " (blew up)"
        else:
            it = np.sum(rows["iterations_per_step"][moving] * np.diff(rows["step"])) / \
                rows["step"][-1]
            print("| %s | %.3f %% | %.2f %% | %.1f | %.1f %% |" % (
                label, 100 * np.mean(rows["avg_error"][moving]), 100 * np.max(rows["max_error"]),
                it, 100 * info["rms_relative_error"]))
        axes[0].plot(rows["T"][moving], 100 * rows["avg_error"][moving], label=label)
        axes[1].plot(rows["T"][moving], 100 * rows["max_error"][moving], label=label)
    for ax, what in [(axes[0], "average"), (axes[1], "max")]:
        ax.set_yscale("log")
        ax.set_xlabel("T = t sqrt(2g/a)")
        ax.set_ylabel("%s compression [%%]" % what)
        ax.grid(alpha=0.3)
        ax.axhline(0.1, color="k", lw=0.8, ls=":")
    axes[0].legend(fontsize=7, title="iterations", title_fontsize=7)
    axes[0].set_title("dam break, 20 across: density error while it moves", fontsize=9)
    fig.tight_layout()
    save(fig, results, "dam_break_density.png")


def stability(results):
    runs = [("stability_dam_break_vorticity1", "dam_break, confinement 1 m/s (100 x)"),
            ("stability_dam_break", "dam_break"), ("stability_double_dam_break", "double_dam_break"),
            ("stability_blob", "blob"), ("stability_stream", "stream")]
    print("\n### 10,000 steps at s = 0.05 m (checked every 100 steps)\n")
    print("| scene | particles (start -> end) | steps | violations | max kinetic [J] | "
          "kinetic at the end [J] | potential released at the end [J] | max speed [m/s] |")
    print("|---|---|---|---|---|---|---|---|")
    fig, ax = plt.subplots(figsize=(7, 3.8))
    for name, label in runs:
        path = os.path.join(results, name + ".csv")
        if not os.path.exists(path):
            print("| %s | not run | | | | | | |" % label)
            continue
        rows = csv(path)
        bad = [v for v in rows["violation"] if v != "none"]
        print("| %s | %d -> %d | %d | %s | %.3g | %.3g | %.3g | %.2f |" % (
            label, rows["particles"][0], rows["particles"][-1], rows["step"][-1],
            bad[0] if bad else "none", np.max(rows["kinetic_energy"]), rows["kinetic_energy"][-1],
            rows["potential_released"][-1], np.max(rows["max_speed"])))
        ax.plot(rows["step"], np.maximum(rows["kinetic_energy"], 1e-6), label=label)
    ax.set_yscale("log")
    ax.set_xlabel("step (dt = 1/240 s)")
    ax.set_ylabel("kinetic energy [J] (floor 1e-6)")
    ax.set_title("10,000 steps, vorticity confinement on in every run", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save(fig, results, "stability_energy.png")


def main(results):
    exp_path = os.path.join(DATA, "martin_moyce_1952_surge_front_n2.csv")
    exp = csv(exp_path)
    shift = martin_moyce(results, exp)
    print("\nfitted time shift T0 = %.4f" % shift)
    dam_break_density(results)
    tank(results)
    stability(results)
