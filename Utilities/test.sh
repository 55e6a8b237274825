#!/usr/bin/env bash
# The test command: install what is missing, build, run every test but the long soak runs, then
# the solver tests again under AddressSanitizer and UndefinedBehaviorSanitizer (sanitize.sh) and
# a minute of fuzzing (fuzz.sh). GPU tests report SKIPPED on a machine without a CUDA device.
# Every stage runs even when an earlier one failed; the exit status is non-zero if any failed.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
"$root/Utilities/install-deps.sh"
"$root/Utilities/build.sh" "$build"

failed=()
stage() {
  local name=$1 start=$SECONDS
  shift
  echo "test.sh: == $name"
  if "$@"; then
    echo "test.sh: == $name passed in $((SECONDS - start)) s"
  else
    echo "test.sh: == $name FAILED (exit $?) after $((SECONDS - start)) s"
    failed+=("$name")
  fi
}
# As many tests at once as there are cores: the MPI and GUI tests claim two (PROCESSORS) and
# render under private X servers, so none shares a display or oversubscribes the ranks.
tests() (cd "$build" && ctest --output-on-failure --timeout 900 -j "$(nproc)" -LE long)

stage "tests (ctest -LE long)" tests
stage "sanitizers (Utilities/sanitize.sh)" "$root/Utilities/sanitize.sh" "$build-sanitize"
stage "fuzzing (Utilities/fuzz.sh)" "$root/Utilities/fuzz.sh" "$build-fuzz"
if ((${#failed[@]})); then
  printf 'test.sh: FAILED: %s\n' "${failed[@]}"
  exit 1
fi
echo "test.sh: all stages passed"
