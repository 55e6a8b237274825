#!/usr/bin/python3
"""The long validation runs on the CPU (Documentation/Validation.md, "CTest and the long runs").

  validate.py run [GROUP...]   run the solver's tools, writing output/validation/*.csv and *.txt
                               (a run whose .txt exists is skipped; --force reruns it)
  validate.py plot             draw the figures (*.png, into output/validation/) and print the
                               tables from output/validation/

Groups: mm (Martin & Moyce at 10/20/40/80 across), mmdt (time-step and s_corr check at 20 across),
mmit (dam-break density error per iteration count at 20 across), tank (hydrostatic tank),
stability (10,000 steps of the dam break with 100 x the confinement, and of every shipped scene).
A run's name (e.g. mm_80) selects that run alone.
Tools come from --build (default build/): pbf_martin_moyce and pbf_validation_run (Solver/Tools).
Needs Debian's python3-numpy and python3-matplotlib. The 80-across run takes about half an hour
on 2 cores; everything else together about as long.
"""
import argparse
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(ROOT, "Testing", "Validation")  # the experiments' records and the tank
# Generated data stays out of the tree: output/ is git-ignored.
RESULTS = os.path.join(ROOT, "output", "validation")
# The table as the project received it (shared/validation/), copied here so tests and CI have it.
EXPERIMENT_CANDIDATES = [
    os.path.join(DATA, "martin_moyce_1952_surge_front_n2.csv"),
    os.path.join(ROOT, "..", "shared", "validation", "martin_moyce_1952_surge_front_n2.csv"),
]
ACROSS = [10, 20, 40, 80]
TANK_ITERATIONS = [1, 2, 4, 8]
ADAPTIVE = ["--iterations", "100", "--tolerance", "0.1"]  # 0.1 %, capped at 100 iterations
SHIPPED = ["dam_break", "double_dam_break", "blob", "stream"]


def experiment_path():
    for p in EXPERIMENT_CANDIDATES:
        if os.path.exists(p):
            return os.path.abspath(p)
    sys.exit("validate.py: martin_moyce_1952_surge_front_n2.csv not found in " +
             ", ".join(EXPERIMENT_CANDIDATES))


def tool(build, name):
    """A tool of Solver/Tools, built into the build tree's Solver/Tools/ (every kind of build)."""
    return os.path.join(build, "Solver", "Tools", name)


def runs(build):
    """(group, name, argv): every run. Outputs go to output/validation/NAME.*"""
    mm = tool(build, "pbf_martin_moyce")
    vr = tool(build, "pbf_validation_run")
    r = lambda name: os.path.join(RESULTS, name)
    out = []

    def dam(group, name, across, extra):
        out.append((group, name, [mm, "--across", str(across), "--experiment", experiment_path(),
                                  "--backend", "openmp", "--front", r(name + "_front.csv"),
                                  "--density", r(name + "_density.csv")] + extra))

    for n in ACROSS:
        dam("mm", "mm_%d" % n, n, [])
    dam("mmdt", "mm_20_dt_half", 20, ["--dt-factor", "0.5"])
    dam("mmdt", "mm_20_k0", 20, ["--scorr-k", "0"])
    dam("mmdt", "mm_20_k0_dt_half", 20, ["--scorr-k", "0", "--dt-factor", "0.5"])
    dam("mmdt", "mm_10_k0", 10, ["--scorr-k", "0"])
    dam("mmdt", "mm_40_k0", 40, ["--scorr-k", "0"])
    for it in [1, 2, 8]:
        dam("mmit", "mm_20_it%d" % it, 20, ["--iterations", str(it)])
    dam("mmit", "mm_20_adaptive", 20, ADAPTIVE)

    tank = os.path.join(DATA, "hydrostatic_tank.json")
    for it in TANK_ITERATIONS + ["adaptive"]:
        solver = ADAPTIVE if it == "adaptive" else ["--iterations", str(it)]
        out.append(("tank", "tank_%s" % (it if it == "adaptive" else "it%d" % it),
                    [vr, "--scene", tank, "--spacing", "0.02", "--steps", "480", "--every", "10",
                     "--backend", "openmp"] + solver))
    out.append(("stability", "stability_dam_break_vorticity1",
                [vr, "--scene", "dam_break", "--spacing", "0.05", "--vorticity", "1.0", "--steps",
                 "10000", "--every", "100", "--backend", "openmp"]))
    # The shipped scenes at the spacing of Testing/Solver's SoakLong (0.05 m).
    for scene in SHIPPED:
        out.append(("stability", "stability_" + scene,
                    [vr, "--scene", scene, "--spacing", "0.05", "--steps", "10000", "--every",
                     "100", "--backend", "openmp"]))
    return out


def run(args):
    os.makedirs(RESULTS, exist_ok=True)
    for group, name, argv in runs(os.path.abspath(args.build)):
        if args.groups and group not in args.groups and name not in args.groups:
            continue
        txt = os.path.join(RESULTS, name + ".txt")
        if os.path.exists(txt) and not args.force:
            print("skip %s (%s exists)" % (name, os.path.relpath(txt)))
            continue
        print("run  %s: %s" % (name, " ".join(os.path.relpath(a, ROOT) if a.startswith("/")
                                             else a for a in argv)), flush=True)
        csv = os.path.join(RESULTS, name + ".csv")
        stdout = open(txt + ".part", "w")
        if os.path.basename(argv[0]) == "pbf_validation_run":
            argv = argv + ["--out", csv]
        status = subprocess.call(["nice", "-n", "10"] + argv, stdout=stdout,
                                 stderr=open(os.path.join(RESULTS, name + ".err"), "w"),
                                 env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
        stdout.write("exit_status,%d\n" % status)
        stdout.close()
        os.replace(txt + ".part", txt)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default=os.path.join(ROOT, "build"))
    parser.add_argument("--force", action="store_true")
    parser.add_argument("command", choices=["run", "plot"])
    parser.add_argument("groups", nargs="*", help="groups or single runs (default: all)")
    args = parser.parse_args()
    if args.command == "run":
        run(args)
    else:
        import plots
        plots.main(RESULTS)
