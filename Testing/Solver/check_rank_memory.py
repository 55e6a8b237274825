"""Each rank of a decomposed run costs host memory in proportion to its own slab.

pbf_bench_mpi (serial backend, one step) on 1, 2 and 4 ranks reports every rank's peak host
memory: the construction (counting the fluid, generating its slab, the first evaluation) and the
step. Above the process's own baseline (the same ranks with a fluid of 2,000 particles: the
libraries, MPI's buffers), each rank of 2 and 4 must hold at most 1.3 times its slab's share of
one rank's: (peak_r - base_R) <= 1.3 (peak_1 - base_1) n_r / N. A rank that held the whole
fluid, or a batch of it in double beside its own arrays, exceeds that several times over.

Measured on the development machine at 2M particles: 1.02 on 2 ranks, 1.04-1.09 on 4 (the
ghosts, 7.5 % of a rank's particles on 4 ranks, and the capacity planned for the migration; each
rank's grid is the window of its own columns).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile


def run(mpiexec, bench, ranks, particles, folder):
    out = os.path.join(folder, f"memory_{ranks}_{particles}.json")
    command = [mpiexec, "-n", str(ranks), bench, "--backend", "serial", "--particles",
               str(particles), "--warmup", "0", "--steps", "1", "--json", out]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    with open(out) as f:
        return json.load(f)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--mpiexec", required=True)
    parser.add_argument("--bench", required=True)
    parser.add_argument("--particles", type=int, default=2000000)
    args = parser.parse_args()
    bound = 1.3
    problems = []
    with tempfile.TemporaryDirectory() as folder:
        base = {r: max(run(args.mpiexec, args.bench, r, 2000, folder)["peak_host_mb_per_rank"])
                for r in (1, 2, 4)}
        one = run(args.mpiexec, args.bench, 1, args.particles, folder)
        whole = one["peak_host_mb_per_rank"][0] - base[1]
        total = one["particles"]
        print(f"1 rank: {total} particles, peak {one['peak_host_mb_per_rank'][0]:.1f} MB, "
              f"{whole:.1f} MB above the baseline of {base[1]:.1f} MB")
        for ranks in (2, 4):
            many = run(args.mpiexec, args.bench, ranks, args.particles, folder)
            if many["particles"] != total:
                problems.append(f"{ranks} ranks simulated {many['particles']} particles, one rank {total}")
            for r, (peak, count) in enumerate(zip(many["peak_host_mb_per_rank"],
                                                  many["particles_per_rank"])):
                share = whole * count / total
                ratio = (peak - base[ranks]) / share
                print(f"{ranks} ranks, rank {r}: {count} particles, peak {peak:.1f} MB, "
                      f"{peak - base[ranks]:.1f} MB above the baseline of {base[ranks]:.1f} MB, "
                      f"{ratio:.2f} x its share ({share:.1f} MB)")
                if not ratio <= bound:
                    problems.append(f"{ranks} ranks, rank {r}: {ratio:.2f} x its share (bound {bound})")
    for p in problems:
        print("PROBLEM:", p)
    print(f"check_rank_memory: {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
