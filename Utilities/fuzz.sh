#!/usr/bin/env bash
# Fuzzes the scene parser and the parameter checks for a bounded time (Testing/Fuzz): builds the
# libFuzzer target with clang, AddressSanitizer and UndefinedBehaviorSanitizer into build-fuzz/
# (or $1), replays the seed corpus, then fuzzes for PBF_FUZZ_SECONDS (default 60). Fails on any
# finding and prints the input that caused it (kept in the build folder's fuzz-artifacts/); add
# that file to Testing/Fuzz/corpus/ once fixed, so that every later run replays it.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build-fuzz}
seconds=${PBF_FUZZ_SECONDS:-60}

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DPBF_SOLVER_ONLY=ON -DPBF_ENABLE_CUDA=OFF -DBUILD_TESTING=OFF -DPBF_FUZZ=ON \
  -DCMAKE_DISABLE_FIND_PACKAGE_OpenMP=ON >/dev/null
cmake --build "$build" -j "$(nproc)" --target pbf_fuzz_scene

fuzzer=$build/Testing/Fuzz/pbf_fuzz_scene
seeds=$root/Testing/Fuzz/corpus
corpus=$build/fuzz-corpus        # what this machine's runs have found, kept between runs
artifacts=$build/fuzz-artifacts  # inputs that failed
mkdir -p "$corpus" "$artifacts"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:check_initialization_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}

report() {
  echo "fuzz.sh: FINDING: $1; the failing input:" >&2
  local input
  for input in "$artifacts"/*; do
    [[ -f $input ]] || continue
    echo "--- $input ($(stat -c %s "$input") bytes)" >&2
    od -A d -c "$input" | head -40 >&2
  done
  exit 1
}

# The seeds, and the past findings among them, must all pass.
"$fuzzer" -runs=0 -artifact_prefix="$artifacts/" "$seeds" || report "a seed fails"
"$fuzzer" -max_total_time="$seconds" -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
  -dict="$root/Testing/Fuzz/scene.dict" -artifact_prefix="$artifacts/" -print_final_stats=1 \
  "$corpus" "$seeds" || report "fuzzing for ${seconds} s"
echo "fuzz.sh: ${seconds} s of fuzzing, no finding; $(ls "$corpus" | wc -l) inputs in $corpus"
