#!/usr/bin/env bash
# Scaling of the domain-decomposed solver over MPI ranks on the CPU: builds Solver/ and
# pbf_bench_mpi alone (no ParaView, no CUDA) and runs strong scaling (a fixed particle count over
# 1, 2, 4, ... ranks) and weak scaling (a fixed count per rank), one OpenMP thread per rank.
#
#   bash Utilities/scaling-run.sh [--max-ranks R] [--particles P] [--per-rank Q] [--steps S]
#
# Defaults: R = the number of cores, P = 200000, Q = 100000, S = 20. Works here and on the GPU
# machine (device tool, carry [".deps"] for nlohmann-json and GoogleTest there). Logs and JSON go
# under $OUT (else output/scaling); the tables are printed last.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out=${OUT:-$root/output/scaling}
build=${PBF_SCALING_BUILD:-/tmp/pbf-scaling-build}
cores=$(nproc)
ranks=$cores
particles=200000
per_rank=100000
steps=20
while (($#)); do
  case $1 in
    --max-ranks) ranks=$2; shift 2 ;;
    --particles) particles=$2; shift 2 ;;
    --per-rank) per_rank=$2; shift 2 ;;
    --steps) steps=$2; shift 2 ;;
    *) sed -n '2,12p' "$0"; exit 2 ;;
  esac
done
mkdir -p "$out"
exec > >(tee "$out/scaling.log") 2>&1

deps=()
[[ -d $root/.deps/json ]] && deps+=(-DPBF_JSON_INCLUDE_DIR="$root/.deps/json")
[[ -d $root/.deps/googletest ]] && deps+=(-DPBF_GTEST_SOURCE_DIR="$root/.deps/googletest")
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DPBF_SOLVER_ONLY=ON \
  -DPBF_ENABLE_CUDA=OFF -DBUILD_TESTING=OFF "${deps[@]}" > "$out/configure.log"
cmake --build "$build" --target pbf_bench_mpi -j "$(nproc)" > "$out/build.log"
bench=$(find "$build" -name pbf_bench_mpi -type f -perm -u+x | head -1)
[[ -x $bench ]] || { echo "scaling-run: pbf_bench_mpi was not built (no MPI found?)"; exit 1; }

# OpenMPI: root is refused and ranks beyond the slots too unless allowed; ranks yield when idle so
# that a waiting rank does not take a core from a working one.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_mpi_yield_when_idle=1 OMP_NUM_THREADS=1 OMP_WAIT_POLICY=PASSIVE
echo "machine: $cores cores, $(uname -sr); commit $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
strong=() weak=()
for ((n = 1; n <= ranks; n *= 2)); do
  strong+=("$(mpiexec -n "$n" "$bench" --particles "$particles" --steps "$steps" --warmup 3 \
    --backend serial --json "$out/strong-$n.json" | tail -1)")
  weak+=("$(mpiexec -n "$n" "$bench" --per-rank "$per_rank" --steps "$steps" --warmup 3 \
    --backend serial --json "$out/weak-$n.json" | tail -1)")
done
header="| ranks | backend | precision | particles | ms/step median (p10-p90) | steps/s | ghost ms | migration ms | particles per rank (min-max) | ghosts (max) | finite |"
echo
echo "Strong scaling, $particles particles:"
echo "$header"; printf '%s\n' "${strong[@]}"
echo
echo "Weak scaling, $per_rank particles per rank:"
echo "$header"; printf '%s\n' "${weak[@]}"
