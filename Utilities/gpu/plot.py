#!/usr/bin/env python3
"""Plots ms/step against particle count from the bench.json that Utilities/gpu/run.sh writes.

Usage: python3 Utilities/gpu/plot.py [BENCH_JSON [PNG]]
BENCH_JSON defaults to output/gpu-run/bench.json (gpu/run.sh's output folder; copy the file the
device tool returns there), PNG to Documentation/images/ms_per_step.png (Performance.md's plot).
The serial backend is measured at a few counts only (it takes seconds per step at 1M); its line
beyond the largest measured count is a linear extrapolation, drawn dashed.
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def series(runs, label):
    points = sorted((r["particles"], r["median_ms"]) for r in runs if r["label"] == label)
    return [p[0] for p in points], [p[1] for p in points]


def main(source, target):
    data = json.load(open(source))
    runs = data["runs"]
    fig, ax = plt.subplots(figsize=(7, 4.6), dpi=110)
    single = [r for r in runs if r["label"] in ("cuda_single", "cuda_10M", "cuda_100M")]
    xs, ys = zip(*sorted((r["particles"], r["median_ms"]) for r in single))
    ax.plot(xs, ys, "o-", color="tab:green", label="CUDA, single, neighbour masks")
    for label, style, color, name in (
        ("cuda_double", "s-", "tab:blue", "CUDA, double, neighbour masks"),
        ("cuda_walk", "^--", "tab:olive", "CUDA, single, 27-cell walk"),
        ("openmp", "d-", "tab:purple", "OpenMP (16 cores), single"),
    ):
        x, y = series(runs, label)
        if x:
            ax.plot(x, y, style, color=color, label=name)
    x, y = series(runs, "serial")
    x1, y1 = series(runs, "serial_1M")
    points = sorted(zip(x + x1, y + y1))
    x, y = [p[0] for p in points], [p[1] for p in points]
    if x:
        ax.plot(x, y, "o-", color="tab:red", label="serial, single (measured)")
        per = y[-1] / x[-1]
        ext = [x[-1], max(xs)]
        ax.plot(ext, [per * n for n in ext], "--", color="tab:red",
                label="serial, extrapolated linearly")
    ax.plot([1e6], [1.0], "k*", markersize=10, label="targets: 1M at 1 ms, 10M at 10 ms")
    ax.plot([1e7], [10.0], "k*", markersize=10)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("particles (dam break widened to N)")
    ax.set_ylabel("ms per step (median; 4 iterations, XSPH, vorticity)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    # gpu/run.sh's bench.json names no machine; a "machine" key, where added, goes in the title.
    machine = data.get("machine", "").split(" (")[0].replace("one ", "")
    ax.set_title("Position Based Fluids, dam break" + (": " + machine if machine else ""),
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(target)


if __name__ == "__main__":
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    source = os.path.join(root, "output", "gpu-run", "bench.json")
    target = os.path.join(root, "Documentation", "images", "ms_per_step.png")
    main(sys.argv[1] if len(sys.argv) > 1 else source, sys.argv[2] if len(sys.argv) > 2 else target)
