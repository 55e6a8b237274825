"""The house check fails on each kind of offender and names it with its size, and passes a tree
that sits exactly at every limit. Builds throwaway trees in a temporary folder:

    python3 check_house_offenders.py CHECK_HOUSE_PY [--ctags PATH]

Each case is one tree: at the limits (passes); a source file one line over; a function one line
over (a tool's main); a reference document one line over; narration in a header comment, in a
document and in a plugin file. Prints one line per case and exits 1 when one went wrong."""
import argparse
import os
import subprocess
import sys
import tempfile

FILE, FUNCTION, DOCUMENT = 700, 100, 300


def function_lines(name, lines):
    """A C++ function definition of exactly `lines` lines, its first line `int name()`."""
    body = ["  x += %d;" % k for k in range(lines - 5)]
    return ["int %s()" % name, "{", "  int x = 0;"] + body + ["  return x;", "}"]


def source(path_lines):
    """A .cpp of path_lines lines holding small functions, padded with comments."""
    text = function_lines("small", 10)
    return text + ["// padding"] * (path_lines - len(text))


def write(root, path, lines):
    full = os.path.join(root, path)
    os.makedirs(os.path.dirname(full), exist_ok=True)
    with open(full, "w") as out:
        out.write("\n".join(lines) + "\n")


def base_tree(root):
    """A tree at every limit: a file of 700 lines, a main of 100, a document of 300."""
    write(root, "Solver/Physics/AtLimit.cpp", source(FILE))
    main = function_lines("main", FUNCTION)
    write(root, "Solver/Tools/tool.cpp", main + ["// padding"] * 3)
    write(root, "Documentation/Guide.md", ["# Guide"] + ["A line."] * (DOCUMENT - 1))
    write(root, "Filters/vtkThing.cxx", source(40))
    write(root, "Plugin/README.md", ["# Plugin", "Every session of ParaView keeps its proxies."])


CASES = [
    # (name, change to the base tree, text the check must print, or None for a pass)
    ("at the limits", lambda r: None, None),
    ("a file over", lambda r: write(r, "Solver/Physics/AtLimit.cpp", source(FILE + 1)),
     "Solver/Physics/AtLimit.cpp: 701 lines (file limit 700)"),
    ("a function over", lambda r: write(r, "Solver/Tools/tool.cpp", function_lines("main", 101)),
     "Solver/Tools/tool.cpp:1: function main: 101 lines (function limit 100)"),
    ("a document over", lambda r: write(r, "Documentation/Guide.md",
                                        ["# Guide"] + ["A line."] * DOCUMENT),
     "Documentation/Guide.md: 301 lines (document limit 300)"),
    ("narration in code", lambda r: write(r, "Filters/vtkThing.h",
                                          ["// Added in this session for issue 56."]),
     "Filters/vtkThing.h:1: narration \"this session\""),
    ("narration in a document", lambda r: write(r, "Documentation/Notes.md",
                                                ["# Notes", "", "An earlier call gave 2.5 ms."]),
     "Documentation/Notes.md:3: narration \"An earlier call\""),
    ("narration of a review", lambda r: write(r, "Plugin/vtkView.cxx",
                                              ["// Review item D1: one loop."]),
     "Plugin/vtkView.cxx:1: narration \"Review item\""),
]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("check")
    parser.add_argument("--ctags", default=None)
    args = parser.parse_args()
    wrong = 0
    for name, change, expected in CASES:
        with tempfile.TemporaryDirectory() as root:
            base_tree(root)
            change(root)
            command = [sys.executable, args.check, root] + (
                ["--ctags", args.ctags] if args.ctags else [])
            run = subprocess.run(command, capture_output=True, text=True)
            if expected is None:
                good = run.returncode == 0 and "0 problems" in run.stdout
            else:
                good = run.returncode == 1 and expected in run.stdout
            wrong += not good
            print("check_house_offenders: %s: %s (exit %d)%s"
                  % (name, "as expected" if good else "WRONG", run.returncode,
                     "" if good else "\n" + run.stdout + run.stderr))
    print("check_house_offenders: %d cases, %d wrong" % (len(CASES), wrong))
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
