#!/usr/bin/env bash
# Configures and builds the plugin, the solver, its tools and the tests into build/ (or $1).
# The CUDA backend is built when nvcc is found (it is on this project's machines); a machine with
# no GPU then falls back to the CPU at run time.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DBUILD_SHARED_LIBS=ON -DBUILD_TESTING=ON
cmake --build "$build" -j "$(nproc)"
