#!/usr/bin/env python3
"""Per-kernel summary of `ncu --page source --print-source sass --csv` (gpu/hotspots.sh): the
executed warp instructions of each profiled kernel, and its hottest SASS lines with their share."""
import csv
import sys


def tables(path):
    """Yields (title, header, rows) for each kernel's table in the CSV."""
    title, header, rows = "", None, []
    with open(path, newline="", errors="replace") as f:
        for row in csv.reader(f):
            if not row:
                continue
            if any(cell.strip() == "Source" for cell in row) and any("Address" in c for c in row):
                if header is not None:
                    yield title, header, rows
                header, rows = [c.strip() for c in row], []
            elif header is not None and len(row) == len(header):
                rows.append(row)
            else:
                if header is not None:
                    yield title, header, rows
                    header, rows = None, []
                title = " ".join(row)[:160]
    if header is not None:
        yield title, header, rows


def number(text):
    try:
        return float(text.replace(",", ""))
    except ValueError:
        return 0.0


def main(path, top=45):
    found = False
    for title, header, rows in tables(path):
        columns = [i for i, c in enumerate(header) if c.startswith("Instructions Executed")]
        if not columns:
            continue
        found = True
        executed, source = columns[0], header.index("Source")
        address = next(i for i, c in enumerate(header) if "Address" in c)
        total = sum(number(r[executed]) for r in rows)
        print(f"\n== {title}\n{len(rows)} SASS lines, {total:,.0f} warp instructions executed")
        hottest = sorted(rows, key=lambda r: -number(r[executed]))[:top]
        for r in sorted(hottest, key=lambda r: int(r[address], 16) if r[address].startswith("0x") else 0):
            n = number(r[executed])
            print(f"{r[address]:>8} {n:14,.0f} {100 * n / total:5.1f} %  {r[source].strip()[:90]}")
    if not found:
        print("no instruction counts found; the file begins:")
        with open(path, errors="replace") as f:
            for _, line in zip(range(12), f):
                print(line.rstrip()[:200])


if __name__ == "__main__":
    main(sys.argv[1])
