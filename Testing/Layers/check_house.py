"""The house rules' check: sizes and narration, so that the rules hold themselves.

    python3 check_house.py REPOSITORY_ROOT [--ctags PATH]

Rules (the table LIMITS below; Documentation/Architecture.md, "House rules", points here):
- no source file of Solver/, Filters/ or Plugin/ over 700 lines;
- no function there over 100 lines, tools' main included (the functions and their extents come
  from Universal Ctags, which parses C++ and, mapped to it, CUDA);
- no reference document (Documentation/*.md) over 300 lines;
- no narration of the work's history (sessions, issues, review items, earlier calls) in
  Documentation/, Solver/, Filters/ or Plugin/: a document says what is, and git keeps how it
  came to be.

Prints each offender with its size or its line, then one summary line, and exits 1 when there is
an offender."""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys

LIMITS = {"file": 700, "function": 100, "document": 300}
CODE_TOPS = ("Solver", "Filters", "Plugin")
NARRATION_TOPS = ("Documentation", "Solver", "Filters", "Plugin")
SOURCE = re.compile(r"\.(h|hpp|cpp|cxx|cu|cuh)$")
TEXT = re.compile(r"\.(h|hpp|cpp|cxx|cu|cuh|md|xml|in|txt|py|json)$|^CMakeLists\.txt$")
# Phrases that tell the story of the work rather than the product. A ParaView session (a client's
# connection, vtkSMSession) is the product's word, so only the work's determiners count.
NARRATION = re.compile(
    r"\b(?:this|last|next|previous|earlier|later) session\b"
    r"|\bsessions? (?:ago|before)\b"
    r"|\bissue ?#?\d+\b"
    r"|\bthe (?:\w+ )?issue(?:'s)?\b"
    r"|\breview item\b"
    r"|\bclosing note\b"
    r"|\bstop \d+\b"
    r"|\b(?:an earlier|a later|the previous|the last) call\b", re.IGNORECASE)


def walk(root, tops, pattern):
    found = []
    for top in tops:
        for folder, _, names in os.walk(os.path.join(root, top)):
            found += [os.path.relpath(os.path.join(folder, n), root) for n in names
                      if pattern.search(n)]
    return sorted(found)


def line_count(root, path):
    with open(os.path.join(root, path), errors="replace") as text:
        return sum(1 for _ in text)


def functions(root, paths, ctags):
    """(path, first line, name, lines) of every function definition, from Universal Ctags."""
    command = [ctags, "--output-format=json", "--languages=C++", "--langmap=C++:+.cu.cuh",
               "--kinds-C++=f", "--fields=+ne", "-f", "-"] + paths
    listing = subprocess.run(command, cwd=root, check=True, capture_output=True, text=True).stdout
    found = []
    for line in listing.splitlines():
        tag = json.loads(line)
        if tag.get("_type") == "tag" and "end" in tag:
            scope = tag.get("scope", "")
            owner = scope.split("::")[-1]
            name = "%s::%s" % (owner, tag["name"]) if owner and "__anon" not in owner else tag["name"]
            found.append((tag["path"], tag["line"], name, tag["end"] - tag["line"] + 1))
    return found


def narration(root, path):
    hits = []
    with open(os.path.join(root, path), errors="replace") as text:
        for number, line in enumerate(text, 1):
            match = NARRATION.search(line)
            if match:
                hits.append((number, match.group(0)))
    return hits


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("root", nargs="?", default=os.getcwd())
    parser.add_argument("--ctags", default=shutil.which("ctags") or "ctags")
    args = parser.parse_args()
    root = args.root
    problems = []
    sources = walk(root, CODE_TOPS, SOURCE)
    for path in sources:
        lines = line_count(root, path)
        if lines > LIMITS["file"]:
            problems.append("%s: %d lines (file limit %d)" % (path, lines, LIMITS["file"]))
    found = functions(root, sources, args.ctags) if sources else []
    for path, first, name, lines in found:
        if lines > LIMITS["function"]:
            problems.append("%s:%d: function %s: %d lines (function limit %d)"
                            % (path, first, name, lines, LIMITS["function"]))
    documents = [d for d in walk(root, ("Documentation",), re.compile(r"\.md$"))
                 if os.path.dirname(d) == "Documentation"]
    for path in documents:
        lines = line_count(root, path)
        if lines > LIMITS["document"]:
            problems.append("%s: %d lines (document limit %d)"
                            % (path, lines, LIMITS["document"]))
    texts = walk(root, NARRATION_TOPS, TEXT)
    for path in texts:
        for number, phrase in narration(root, path):
            problems.append("%s:%d: narration \"%s\" (say what is; git keeps the history)"
                            % (path, number, phrase))
    for problem in problems:
        print("check_house: " + problem)
    print("check_house: %d source files, %d functions, %d documents, %d texts, %d problems"
          % (len(sources), len(found), len(documents), len(texts), len(problems)))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
