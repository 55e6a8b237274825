#!/usr/bin/env python3
"""The resolution tables and figure of Documentation/Validation.md from the CSVs that
pbf_bench --refined and pbf_martin_moyce write (Utilities/gpu/run.sh with PBF_GPU_RESOLUTION=3
puts them in resolution.tar.gz):

    Utilities/validation/resolution.py FOLDER [--plots [DIR]]

prints the tables and, with --plots, draws resolution_front.png into DIR (default
Documentation/images/, where Validation.md shows it). Every number comes from the CSVs; nothing
is fitted except the one time-origin shift of the Martin & Moyce comparison, fitted on the
finest run and stated."""
import argparse
import csv
import glob
import math
import os

G = 9.81
COLUMN = 0.4      # the dam_break preset's column: 0.4 m wide (x), 0.6 m high
HEIGHT = 0.6
SPEED_BOUND = 7.5  # the criterion: 3 sqrt(g H) for the 0.6 m column, rounded up
FRONT_X = [0.6, 0.8, 1.0, 1.2, 1.4]  # where the dam-break front's arrival times are compared
# The flow after the collapse has started (Validation.md, "Criteria"): the points from
# x = 0.8 m, and Martin & Moyce's from Z = 2.11. Printed beside the criteria's own figures, for
# criteria the owner may choose.
STARTED_X = FRONT_X[1:]
STARTED_Z = 2.11
MM_A = 0.05715
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The figure is part of the documentation; the CSVs it is drawn from stay wherever they were run.
IMAGES = os.path.join(ROOT, "Documentation", "images")


def rows(path):
    with open(path) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def arrival(frames, x):
    """The time the front first reaches x, linear between frames; None when it never does."""
    previous = None
    for r in frames:
        if r["front"] >= x:
            if previous is None:
                return r["time"]
            t0, x0 = previous["time"], previous["front"]
            return t0 + (x - x0) / (r["front"] - x0) * (r["time"] - t0)
        previous = r
    return None


def largest_gap(a, b, points=FRONT_X):
    """Largest |T_a - T_b| / T_b over the points both reach (T in any unit: the ratio is
    dimensionless)."""
    gaps = []
    for x in points:
        ta, tb = arrival(a, x), arrival(b, x)
        if ta is not None and tb is not None:
            gaps.append(abs(ta - tb) / tb)
    return max(gaps) if gaps else float("nan")


def summary(name, frames):
    steps = sum(r["steps"] for r in frames)
    iterations = sum(r["iterations"] for r in frames)
    ms = sum(r["milliseconds"] for r in frames)
    return {
        "name": name,
        "frames": len(frames),
        "until": frames[-1]["time"] if frames else 0,
        "mean": max(r["average_error"] for r in frames) * 100,
        "max": max(r["max_error"] for r in frames) * 100,
        "speed": max(r["max_speed"] for r in frames),
        "speed_p99": sorted(r["max_speed"] for r in frames)[int(0.99 * (len(frames) - 1))],
        # The 99.9th and 99.99th percentiles of the particles' speeds, each in its worst frame
        # (CSVs since the fourteenth session; NaN before).
        "speed_p999": max(r.get("speed_p999", float("nan")) for r in frames),
        "speed_p9999": max(r.get("speed_p9999", float("nan")) for r in frames),
        "steps_per_frame": steps / max(1, len(frames)),
        "iterations_per_step": iterations / max(1, steps),
        "ms_per_step": ms / max(1, steps),
        "ms_per_frame": ms / max(1, len(frames)),
        "seconds_per_simulated_second": ms / 1000 / max(1e-9, frames[-1]["time"]) if frames else 0,
    }


def table(title, runs):
    print("\n" + title)
    print("| run | frames | t end [s] | worst mean % | worst max % | max speed [m/s] "
          "| 99.9th / 99.99th percentile speed [m/s] | steps/frame "
          "| iterations/step | ms/step | ms/frame | s per simulated s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for s in runs:
        print("| %s | %d | %.3f | %.3f | %.2f | %.2f | %.2f / %.2f | %.1f | %.2f | %.3f | %.1f | %.2f |" % (
            s["name"], s["frames"], s["until"], s["mean"], s["max"], s["speed"], s["speed_p999"],
            s["speed_p9999"],
            s["steps_per_frame"], s["iterations_per_step"], s["ms_per_step"], s["ms_per_frame"],
            s["seconds_per_simulated_second"]))


def spacing_ladder(load):
    """1. The default dam break at five spacings: the table of every frame; returns the fronts."""
    ladder = [(0.04, "dam_break_0.04_defaults_CUDA.csv"), (0.02, "dam_break_0.02_defaults_CUDA.csv"),
              (0.01, "dam_break_0.01_defaults_CUDA.csv"), (0.005, "dam_break_0.005_defaults_CUDA.csv"),
              (0.0025, "dam_break_0.0025_defaults_CUDA.csv")]
    runs, fronts = [], {}
    for spacing, name in ladder:
        frames = load(name)
        if frames:
            runs.append(summary("s = %g m, CUDA" % spacing, frames))
            fronts[spacing] = frames
    for spacing in (0.04, 0.02, 0.01):
        frames = load("dam_break_%g_defaults_OpenMP.csv" % spacing)
        if frames:
            runs.append(summary("s = %g m, OpenMP" % spacing, frames))
    for spacing in (0.005, 0.0025):
        frames = load("dam_break_%g_fixed4_CUDA.csv" % spacing)
        if frames:
            runs.append(summary("s = %g m, CUDA, fixed 4 iterations" % spacing, frames))
    table("Dam break, every frame (defaults unless said)", runs)
    return fronts


def front_table(fronts):
    print("\nSurge front: arrival time [s] at x (the column's face starts at 0.4 m)")
    print("| spacing | " + " | ".join("x = %.1f m" % x for x in FRONT_X) +
          " | largest gap to the next finer | the same from x = %.1f m |" % STARTED_X[0])
    print("|---|" + "---:|" * (len(FRONT_X) + 2))
    spacings = sorted(fronts, reverse=True)
    percent = lambda g: "%.2f %%" % (100 * g) if not math.isnan(g) else "-"
    for i, s in enumerate(spacings):
        times = [arrival(fronts[s], x) for x in FRONT_X]
        finer = fronts[spacings[i + 1]] if i + 1 < len(spacings) else None
        gap = largest_gap(fronts[s], finer) if finer else float("nan")
        started = largest_gap(fronts[s], finer, STARTED_X) if finer else float("nan")
        print("| %g | %s | %s | %s |" % (s, " | ".join("%.4f" % t if t else "-" for t in times),
                                         percent(gap), percent(started)))


def smoothing_ratios(load):
    """2. Smoothing ratios."""
    print("\nSmoothing ratio at s = 0.02 m: tank (0.5 s) and dam-break front")
    print("| h/s | neighbours at start | lowest | highest | change | centre height: largest change "
          "| front gap to h/s 2 | worst max % |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    reference = load("dam_break_0.02_ratio_2.csv")
    for ratio in ("1.5", "2", "2.5", "3"):
        tank = load("tank_0.02_ratio_%s.csv" % ratio)
        front = load("dam_break_0.02_ratio_%s.csv" % ratio)
        if not tank or not front:
            continue
        n = [r["average_neighbors"] for r in tank]
        # The CSV's first row is frame 1; frame 0 is the lattice (pbf_bench prints it).
        start = n[0]
        low, high = min(n), max(n)
        change = max(abs(low - start), abs(high - start)) / start
        # The fluid's volume, as its mean height: what the neighbour count is meant to show
        # (a gas-like expansion raises it; a lattice melting into a liquid does not).
        heights = [r.get("centre_height", float("nan")) for r in tank]
        lift = max(abs(c - heights[0]) for c in heights) / heights[0]
        print("| %s | %.1f | %.1f | %.1f | %.1f %% | %.2f %% | %.2f %% | %.2f |" % (
            ratio, start, low, high, 100 * change, 100 * lift,
            100 * largest_gap(front, reference) if reference else float("nan"),
            100 * max(r["max_error"] for r in front)))


def time_step(load):
    """3. The time step."""
    print("\nCFL 0.4 (default) against 0.2: largest change of the front's arrival time")
    for spacing in (0.01, 0.005):
        a = load("dam_break_%g_defaults_CUDA.csv" % spacing)
        b = load("dam_break_%g_defaults_CUDA_cfl0.2.csv" % spacing)
        if a and b:
            print("- s = %g m: %.2f %% (from x = %.1f m: %.2f %%)" % (
                spacing, 100 * largest_gap(a, b), STARTED_X[0], 100 * largest_gap(a, b, STARTED_X)))


def mm_points(path):
    return [line.strip().split(",") for line in open(path)
            if line.count(",") == 3 and not line.startswith("Z")]


def mm_gap(a, b, z_from=0.0):
    return max(abs(p[2] - q[2]) / q[2] for p, q in zip(a, b) if q[0] >= z_from - 1e-9)


def martin_moyce(folder):
    """4. Martin & Moyce."""
    mm = {}
    for across in (10, 20, 40, 80):
        path = os.path.join(folder, "mm_%d.txt" % across)
        if os.path.exists(path):
            text = dict(line.split(",", 1) for line in open(path) if line.count(",") == 1)
            mm[across] = {"rms": float(text["rms_relative_error"]),
                          "points": [(float(z), float(te), float(ts)) for z, te, ts, _ in mm_points(path)]}
    if not mm:
        return
    finest = max(mm)
    pts = mm[finest]["points"]
    # One shift, least squares on T over points 2-15, on the finest run.
    shift = sum(te - ts for _, te, ts in pts[1:]) / len(pts[1:])
    print("\nMartin & Moyce (n^2 = 2): T0 = %.3f fitted on %d across (points 2-15)" % (shift, finest))
    print("| across | RMS unshifted | RMS points 2-15, shifted by T0 | late dZ/dT (Z 2.56-4.11) |")
    print("|---|---:|---:|---:|")
    for across, r in sorted(mm.items()):
        p = r["points"]
        rel = [((ts + shift) - te) / te for _, te, ts in p[1:]]
        rms = math.sqrt(sum(x * x for x in rel) / len(rel))
        late = (p[-1][0] - p[7][0]) / (p[-1][2] - p[7][2])
        print("| %d | %.1f %% | %.1f %% | %.3f |" % (across, 100 * r["rms"], 100 * rms, late))
    experiment_late = (pts[-1][0] - pts[7][0]) / (pts[-1][1] - pts[7][1])
    print("experiment late dZ/dT: %.3f" % experiment_late)
    if 40 in mm and 80 in mm:
        print("40 vs 80 across: largest arrival-time gap %.2f %% (from Z = %.2f: %.2f %%)" % (
            100 * mm_gap(mm[40]["points"], mm[80]["points"]), STARTED_Z,
            100 * mm_gap(mm[40]["points"], mm[80]["points"], STARTED_Z)))
    for across in (40, 80):
        path = os.path.join(folder, "mm_%d_cfl0.2.txt" % across)
        if os.path.exists(path) and across in mm:
            half = [(float(z), 0.0, float(ts)) for z, _, ts, _ in mm_points(path)]
            print("%d across, CFL 0.2 vs 0.4: largest arrival-time change %.2f %% (from Z = %.2f: "
                  "%.2f %%)" % (across, 100 * mm_gap(half, mm[across]["points"]), STARTED_Z,
                                100 * mm_gap(half, mm[across]["points"], STARTED_Z)))


def plot_fronts(fronts, folder):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for s in sorted(fronts, reverse=True):
        f = fronts[s]
        ax[0].plot([r["time"] for r in f], [r["front"] for r in f], label="s = %g m" % s)
        ax[1].plot([r["time"] for r in f], [100 * r["max_error"] for r in f], label="s = %g m" % s)
    ax[0].set_xlabel("t [s]"); ax[0].set_ylabel("surge front x [m]"); ax[0].set_xlim(0, 0.6)
    ax[0].set_title("dam_break preset, defaults"); ax[0].legend()
    ax[1].set_xlabel("t [s]"); ax[1].set_ylabel("max compression [%]")
    ax[1].set_title("largest compression per frame"); ax[1].legend()
    fig.tight_layout()
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, "resolution_front.png")
    fig.savefig(path, dpi=90)
    print("wrote %s" % os.path.relpath(path))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("folder")
    parser.add_argument("--plots", nargs="?", const=IMAGES, metavar="DIR",
                        help="draw resolution_front.png into DIR (default %(const)s)")
    args = parser.parse_args()

    def load(pattern):
        found = sorted(glob.glob(os.path.join(args.folder, pattern)))
        return rows(found[0]) if found else None

    fronts = spacing_ladder(load)
    front_table(fronts)
    smoothing_ratios(load)
    time_step(load)
    martin_moyce(args.folder)
    if args.plots:
        plot_fronts(fronts, args.plots)


if __name__ == "__main__":
    main()
