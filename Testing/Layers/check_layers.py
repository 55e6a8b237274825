"""The include-order check: every #include "..." in Solver/, Filters/ and Plugin/ that names a
file of this repository must point to the same layer or one below, as the layers table of
Documentation/Architecture.md orders them (its rows "| n | `folder/` ... |", bottom first), and
no two files may include each other (a file and its header count as one unit, so foo.cxx
including bar.h while bar.cxx includes foo.h is a circle too).

    python3 check_layers.py REPOSITORY_ROOT

Prints each violation with the include's line and exits 1 when there is one."""
import os
import re
import sys

SOURCE = re.compile(r"\.(h|hpp|cpp|cxx|cu|cuh)$")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
LAYER_ROW = re.compile(r"^\|\s*(\d+)\s*\|\s*((?:`[^`]+`[ ,]*)+)\|")


def layers(root):
    """Folder prefix -> layer number, from Documentation/Architecture.md."""
    table = {}
    with open(os.path.join(root, "Documentation", "Architecture.md")) as text:
        for line in text:
            row = LAYER_ROW.match(line)
            if row:
                for folder in re.findall(r"`([^`]+)`", row.group(2)):
                    table[folder.rstrip("/") + "/"] = int(row.group(1))
    if not table:
        sys.exit("check_layers: no layers table in Documentation/Architecture.md")
    return table


def sources(root):
    found = []
    for top in ("Solver", "Filters", "Plugin"):
        for folder, _, names in os.walk(os.path.join(root, top)):
            found += [os.path.relpath(os.path.join(folder, n), root) for n in names
                      if SOURCE.search(n)]
    return sorted(found)


def layer_of(path, table):
    matches = [f for f in table if path.startswith(f)]
    return table[max(matches, key=len)] if matches else None


def resolve(include, including, files):
    """The repository file an include names: beside the including file, else the one file whose
    path ends with it (the build's include folders); None for VTK, system or generated headers."""
    beside = os.path.normpath(os.path.join(os.path.dirname(including), include))
    if beside in files:
        return beside
    candidates = [f for f in files if f == include or f.endswith("/" + include)]
    return candidates[0] if len(candidates) == 1 else None


def unit(path):
    return os.path.splitext(path)[0]


def main(root):
    table = layers(root)
    files = set(sources(root))
    problems = []
    unit_edges = {}
    for path in sorted(files):
        mine = layer_of(path, table)
        if mine is None:
            problems.append("%s: in no layer of Documentation/Architecture.md" % path)
            continue
        with open(os.path.join(root, path), errors="replace") as text:
            for number, line in enumerate(text, 1):
                match = INCLUDE.match(line)
                target = match and resolve(match.group(1), path, files)
                if not target:
                    continue
                theirs = layer_of(target, table)
                if theirs is not None and theirs > mine:
                    problems.append("%s:%d includes %s: layer %d includes layer %d above it"
                                    % (path, number, target, mine, theirs))
                if unit(target) != unit(path):
                    unit_edges.setdefault(unit(path), {}).setdefault(unit(target), (path, number))
    for a, targets in sorted(unit_edges.items()):
        for b, (path, number) in sorted(targets.items()):
            if a < b and a in unit_edges.get(b, {}):
                back, back_line = unit_edges[b][a]
                problems.append("%s:%d and %s:%d include each other" % (path, number, back,
                                                                       back_line))
    for problem in problems:
        print("check_layers: " + problem)
    print("check_layers: %d files, %d layers, %d problems" % (len(files), len(set(table.values())),
                                                               len(problems)))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.getcwd()))
