#!/usr/bin/env bash
# pbf_bench of this tree against a baseline tree in the same call of the device tool, so that a
# change can be held to "within N % of before" on the same GPU, driver and clocks:
#   git archive <commit> | (mkdir -p .baseline && tar -x -C .baseline)     # here
#   bash Utilities/gpu/compare.sh .baseline                                 # there, carry .deps and .baseline
# Builds pbf_bench of both (sm_90, Release; this tree's build is gpu/run.sh's when it exists),
# then runs 1M single, 1M double and 10M single twice each, alternating baseline and this tree so
# that a drift of the clocks hits both alike, and prints the median ms/step of each and the
# change. JSON under $OUT (else output/gpu-compare). .baseline/ is git-ignored.
# PBF_COMPARE_VARIANTS="skin0.05=--skin 0.05;block96=--block 96": also this tree with
# those extra pbf_bench options, each config once per round, as rows "this tree, LABEL".
# PBF_COMPARE_REFINED="0.005:0.5 0.0025:0.2": also the refined dam break at spacing S to time T
# with the defaults (pbf_bench --refined S --until T --modes defaults), both trees, two rounds:
# ms per step, per frame and per simulated second. PBF_COMPARE_ONLY_REFINED=1: nothing else.
# PBF_COMPARE_HASHES=1: also the frames' fingerprints of both trees (Utilities/frame_hashes.sh:
# CUDA at the scenes' spacing, serial and OpenMP at 5 cm), and whether they are the same.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
baseline=$(cd "${1:?usage: gpu/compare.sh BASELINE_TREE}" && pwd)
out=${OUT:-$root/output/gpu-compare}
mkdir -p "$out"
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)

build() { # build TREE DIR: pbf_bench and pbf_frame_hash of TREE into DIR
  cmake -S "$1" -B "$2" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DPBF_SOLVER_ONLY=ON \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DPBF_JSON_INCLUDE_DIR="$root/.deps/json" \
    -DPBF_GTEST_SOURCE_DIR="$root/.deps/googletest" >"$out/configure-$(basename "$2").log" 2>&1 &&
    cmake --build "$2" -j "$(nproc)" --target pbf_bench pbf_frame_hash >"$out/build-$(basename "$2").log" 2>&1
}
this_build=${PBF_GPU_BUILD:-/tmp/pbf-gpu-build}
[[ -x $this_build/Solver/Tools/pbf_frame_hash ]] || build "$root" "$this_build" || { echo "this tree: build FAILED"; exit 1; }
build "$baseline" /tmp/pbf-gpu-baseline || { tail -20 "$out"/build-pbf-gpu-baseline.log; echo "baseline: build FAILED"; exit 1; }

configs=("64k_f32:--particles 64000 --warmup 20 --steps 100"
  "1M_f32:--particles 1000000 --warmup 20 --steps 100"
  "1M_f64:--precision double --particles 1000000 --warmup 20 --steps 100"
  "10M_f32:--particles 10000000 --warmup 10 --steps 50")
# PBF_COMPARE_CONFIGS="NAME:pbf_bench options;...": more runs of both trees, e.g.
# "1M_tension:--particles 1000000 --liquids 2 --surface-tension 0.07 --warmup 20 --steps 100".
IFS=';' read -r -a extra_configs <<<"${PBF_COMPARE_CONFIGS:-}"
configs+=("${extra_configs[@]}")
[[ ${PBF_COMPARE_ONLY_REFINED:-0} == 1 ]] && configs=()
IFS=';' read -r -a variants <<<"${PBF_COMPARE_VARIANTS:-}"
refined=(${PBF_COMPARE_REFINED:-})
binary_of() { # binary_of baseline|this: that tree's pbf_bench
  [[ $1 == this ]] && echo "$this_build/Solver/Tools/pbf_bench" || echo /tmp/pbf-gpu-baseline/Solver/Tools/pbf_bench
}
# bench_one TREE LABEL ROUND ARGS...: one kernel benchmark, its JSON as LABEL-ROUND.json
bench_one() {
  local tree=$1 label=$2 round=$3
  shift 3
  timeout 60 "$(binary_of "$tree")" --backend cuda "$@" --json "$out/$label-$round.json" \
    --label "$label" >/dev/null 2>&1 || echo "$label round $round: FAILED"
}
for round in 1 2; do
  for config in "${configs[@]}"; do
    name=${config%%:*}
    # shellcheck disable=SC2086
    {
      bench_one baseline "$name-baseline" "$round" ${config#*:}
      bench_one this "$name-this" "$round" ${config#*:}
      for variant in "${variants[@]}"; do
        bench_one this "$name-${variant%%=*}" "$round" ${config#*:} ${variant#*=}
      done
    }
  done
  for run in "${refined[@]}"; do
    for tree in baseline this; do
      timeout 240 "$(binary_of "$tree")" --backend cuda --refined "${run%%:*}" --until "${run#*:}" \
        --modes defaults >"$out/refined-${run%%:*}-$tree-$round.txt" 2>&1 ||
        echo "refined $run $tree round $round: FAILED"
    done
  done
done
if ((${#refined[@]})); then
  echo "refined dam break, defaults (pbf_bench --refined): spacing, mode, particles, frames, steps/frame,"
  echo "iterations/step, ms/step, ms/frame, s per simulated s, worst mean %, worst max %, vmax, status"
  for file in "$out"/refined-*.txt; do
    echo "$(basename "$file" .txt): $(grep -E '^[0-9.]+ +defaults' "$file")"
  done
fi

if [[ ${PBF_COMPARE_HASHES:-0} == 1 ]]; then
  for tree in baseline this; do
    dir=$this_build
    [[ $tree == baseline ]] && dir=/tmp/pbf-gpu-baseline
    { bash "$root/Utilities/frame_hashes.sh" "$dir" cuda
      bash "$root/Utilities/frame_hashes.sh" "$dir" "serial openmp" --spacing 0.05; } >"$out/hashes-$tree.csv" 2>&1
  done
  echo "frame hashes: $(grep -c ',all,' "$out/hashes-this.csv") runs, $(grep -c FAILED "$out/hashes-this.csv") failed;" \
    "$(diff -q "$out/hashes-baseline.csv" "$out/hashes-this.csv" >/dev/null && echo "every frame the same as the baseline's" || echo "DIFFERENT from the baseline:")"
  diff "$out/hashes-baseline.csv" "$out/hashes-this.csv" | head -20
fi

names=("${configs[@]%%:*}")
PBF_COMPARE_NAMES="${names[*]}" python3 - "$out" "${variants[@]%%=*}" <<'PY'
import glob, json, os, statistics, sys
out = sys.argv[1]
print("| run | baseline ms/step | this tree ms/step | change |")
print("|---|---:|---:|---:|")
for name in os.environ.get("PBF_COMPARE_NAMES", "").split():
    def median(tree):
        values = [json.load(open(p))["runs"][0]["median_ms"]
                  for p in sorted(glob.glob(os.path.join(out, f"{name}-{tree}-*.json")))]
        return statistics.median(values) if values else float("nan")
    a, b = median("baseline"), median("this")
    if a != a and b != b:
        continue  # not run (PBF_COMPARE_ONLY_REFINED)
    print(f"| {name} | {a:.3f} | {b:.3f} | {100 * (b / a - 1):+.1f} % |")
    def builds(tree):
        values = [json.load(open(p))["runs"][0].get("mask_builds_per_step", float("nan"))
                  for p in sorted(glob.glob(os.path.join(out, f"{name}-{tree}-*.json")))]
        return statistics.median(values) if values else float("nan")
    print(f"|   mask builds per particle-step: baseline {builds('baseline'):.2f}, this {builds('this'):.2f} | | | |")
    for variant in sys.argv[2:]:
        c = median(variant)
        print(f"| {name}, this tree, {variant} ({builds(variant):.2f} builds) | {a:.3f} | {c:.3f} | {100 * (c / a - 1):+.1f} % |")
PY
