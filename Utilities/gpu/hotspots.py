#!/usr/bin/env python3
"""Where a kernel's instructions go, from ncu's per-SASS-instruction source counters
(`ncu ... --section SourceCounters`, then `ncu -i REPORT --page source --csv --print-source sass`;
gpu/probe.sh writes one such CSV per profiled pass into probe.tgz and calls this on each):

    python3 Utilities/gpu/hotspots.py density.sass.csv [--top 25]

For each kernel in the file: its executed warp instructions, then its costliest straight-line
blocks (consecutive instructions executed equally often) with their length, how often they ran,
their share of the kernel and their first instruction, in address order."""
import argparse
import csv


def kernels(path):
    """Yields (name, rows) for each kernel table; rows are dicts keyed by the CSV's header."""
    name, header, rows = None, None, []
    with open(path, newline="", errors="replace") as f:
        for row in csv.reader(f):
            if not row:
                continue
            if row[0] == "Kernel Name":
                if header is not None:
                    yield name, rows
                name, header, rows = row[1] if len(row) > 1 else "", None, []
            elif row[0] == "Address":
                if header is not None and rows:
                    yield name, rows
                    rows = []
                header = row
            elif header is not None and len(row) == len(header):
                rows.append(dict(zip(header, row)))
    if header is not None and rows:
        yield name, rows


def count(text):
    try:
        return float(text.replace(",", ""))
    except ValueError:
        return 0.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("csv")
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args()
    found = False
    for name, rows in kernels(args.csv):
        executed = [count(r.get("Instructions Executed", "")) for r in rows]
        total = sum(executed)
        if total == 0:
            continue
        found = True
        blocks = []  # [first row, times executed, length]
        for i, n in enumerate(executed):
            if blocks and n == blocks[-1][1] and i == blocks[-1][0] + blocks[-1][2]:
                blocks[-1][2] += 1
            else:
                blocks.append([i, n, 1])
        print(f"\n== {(name or '')[:150]}\n{len(rows)} SASS instructions, {total:,.0f} warp instructions executed")
        costliest = sorted(blocks, key=lambda b: -b[1] * b[2])[: args.top]
        for first, n, length in sorted(costliest):
            r = rows[first]
            print(f"  {r['Address'][-6:]:>6}  {length:4d} instr x {n:12,.0f}  {100 * n * length / total:5.1f} %"
                  f"  threads {r.get('Avg. Threads Executed', '?'):>5}  {r['Source'].strip()[:60]}")
    if not found:
        print(f"{args.csv}: no per-instruction counts (was the SourceCounters section collected?)")


if __name__ == "__main__":
    main()
