#!/usr/bin/env bash
# Where the neighbour passes spend their instructions, per SASS line: one step of the 1M-particle
# benchmark under ncu's source counters, on the GPU machine in one call of the device tool
# (carry .deps). Builds pbf_bench (sm_90, Release) into $PBF_GPU_BUILD (default
# /tmp/pbf-gpu-build, gpu/run.sh's), profiles the first density pass (it rebuilds every mask),
# the second (it keeps most) and the correction pass after it, then prints each kernel's executed
# warp instructions and its hottest SASS lines. The CSVs go to $OUT (else output/gpu-hotspots).
# PBF_HOTSPOTS_ARGS: other pbf_bench options (for example --precision double).
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=${OUT:-$root/output/gpu-hotspots}
build=${PBF_GPU_BUILD:-/tmp/pbf-gpu-build}
mkdir -p "$out"
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if [[ ! -x $build/Solver/Tools/pbf_bench ]]; then
  cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DPBF_SOLVER_ONLY=ON \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DPBF_JSON_INCLUDE_DIR="$root/.deps/json" \
    -DPBF_GTEST_SOURCE_DIR="$root/.deps/googletest" >"$out/configure.log" 2>&1 &&
    cmake --build "$build" -j "$(nproc)" --target pbf_bench >"$out/build.log" 2>&1 ||
    { tail -30 "$out/build.log"; echo "build FAILED"; exit 1; }
fi
# The filter counts only the matching launches: 1 density pass at construction, then 4 density
# and 4 correction passes a step; 60 warm-up steps in, the first four of the next step.
# shellcheck disable=SC2086
timeout 400 ncu --clock-control none --kernel-name-base demangled -k 'regex:DensityStage|CorrectionStage' --launch-skip 481 \
  --launch-count 4 --section SourceCounters --page source --print-source sass --csv \
  "$build/Solver/Tools/pbf_bench" --backend cuda --particles 1000000 --warmup 60 --steps 1 \
  ${PBF_HOTSPOTS_ARGS:-} >"$out/sass.csv" 2>"$out/ncu.err" || { tail -20 "$out/ncu.err"; echo "ncu FAILED"; }
gzip -kf "$out/sass.csv"
python3 "$root/Utilities/gpu/hotspots.py" "$out/sass.csv"
