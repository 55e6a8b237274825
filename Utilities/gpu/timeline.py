#!/usr/bin/env python3
"""Where a rank's GPU is idle: reads the traces of Utilities/gpu/cupti_trace.cpp (one CSV per rank,
made by Utilities/gpu/timeline.sh) and prints, per rank, over the last STEPS steps (a step starts
at a PredictStage kernel): the GPU's busy and idle time (the union over its streams), the largest
idle gaps grouped by the work before and after them, the busiest kernels, and the host's time in
CUDA synchronisation calls. All figures are per step, in ms.

    gpu/timeline.py [--steps K] trace-0.csv [trace-1.csv ...]
"""
import argparse
import collections
import re
import sys


def label_of(name):
    """A short label: the stage of our kernels, else the kernel's own name without templates."""
    stage = re.search(r"(\w+Stage)\b", name)
    if stage:
        kernel = re.match(r"(?:void )?(?:[\w:]+::)?(\w+)", name)
        return f"{kernel.group(1) if kernel else 'kernel'}<{stage.group(1)}>"
    lam = re.search(r"(\w+)(?:<[^<>]*>)?::\{lambda", name)
    if lam:
        return lam.group(1) + "{lambda}"
    base = re.match(r"(?:void )?([\w:]+)", name)
    text = base.group(1) if base else name
    return text.split("::")[-1][:60]


def load(path):
    """A trace written by Utilities/gpu/cupti_trace.cpp: kind,start_ns,end_ns,stream,name."""
    work, calls = [], []  # (start, end, label, stream); (start, end, name)
    with open(path) as f:
        next(f, None)
        for line in f:
            kind, start, end, stream, name = line.rstrip("\n").split(",", 4)
            start, end = int(start), int(end)
            if kind == "wait":
                calls.append((start, end, re.sub(r"_v\d+$", "", name)))
            else:
                work.append((start, end, label_of(name) if kind == "kernel" else name, int(stream)))
    return sorted(work), calls


def analyse(path, steps):
    work, calls = load(path)
    starts = [w[0] for w in work if w[2].endswith("<PredictStage>")]
    if len(starts) < 2:
        print(f"{path}: fewer than two PredictStage kernels; nothing to cut into steps")
        return
    k = min(steps, len(starts) - 1)
    lo, hi = starts[-k - 1], starts[-1]
    inside = [w for w in work if w[1] > lo and w[0] < hi]
    busy = 0
    gaps = collections.defaultdict(lambda: [0.0, 0])
    cursor, last = lo, "step start"
    for start, end, label, _ in inside:
        start = max(start, lo)
        end = min(end, hi)
        if start > cursor:
            gap = start - cursor
            entry = gaps[(last, label)]
            entry[0] += gap
            entry[1] += 1
        if end > cursor:
            busy += end - max(start, cursor)
            cursor, last = end, label
    if hi > cursor:
        entry = gaps[(last, "next step's PredictStage")]
        entry[0] += hi - cursor
        entry[1] += 1
    span = hi - lo
    per = lambda ns: ns / 1e6 / k
    print(f"== {path}: {k} steps, {per(span):.2f} ms/step, GPU busy {per(busy):.2f}, idle {per(span - busy):.2f}")
    print("  idle gaps, largest first: ms/step, count/step, after -> before")
    for (before, after), (total, count) in sorted(gaps.items(), key=lambda e: -e[1][0])[:14]:
        if per(total) < 0.01:
            break
        print(f"    {per(total):7.3f} {count / k:5.1f}  {before} -> {after}")
    kernels = collections.defaultdict(float)
    for start, end, label, _ in inside:
        kernels[label] += min(end, hi) - max(start, lo)
    print("  busiest work (summed over streams): ms/step")
    for label, total in sorted(kernels.items(), key=lambda e: -e[1])[:14]:
        print(f"    {per(total):7.3f}  {label}")
    waits = collections.defaultdict(float)
    for start, end, name in calls:
        if end > lo and start < hi:
            waits[name] += min(end, hi) - max(start, lo)
    print("  host time in CUDA waits: ms/step")
    for name, total in sorted(waits.items(), key=lambda e: -e[1])[:10]:
        print(f"    {per(total):7.3f}  {name}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=5)
    parser.add_argument("files", nargs="+")
    args = parser.parse_args()
    for path in args.files:
        try:
            analyse(path, args.steps)
        except Exception as error:  # one broken export must not hide the others
            print(f"{path}: {error}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
