#!/usr/bin/env bash
# The test command: install what is missing, build, run every test but the long soak runs.
# GPU tests report SKIPPED on a machine without a CUDA device.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
"$root/Utilities/install-deps.sh"
"$root/Utilities/build.sh" "$build"
cd "$build"
ctest --output-on-failure --timeout 900 -LE long
