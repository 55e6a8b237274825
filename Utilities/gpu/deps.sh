#!/usr/bin/env bash
# Run HERE, on the build machine: copies into .deps/ (git-ignored, never committed) what the GPU
# machine lacks and cannot download, for the device tool to carry there (carry [".deps"]):
#   .deps/json/nlohmann   Debian's header-only nlohmann-json   -> -DPBF_JSON_INCLUDE_DIR
#   .deps/googletest      Debian's GoogleTest source           -> -DPBF_GTEST_SOURCE_DIR
# Utilities/gpu/run.sh uses both.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
deps=$root/.deps
json=/usr/include/nlohmann
gtest=/usr/src/googletest
[[ -f $json/json.hpp ]] || { echo "gpu-deps: $json/json.hpp missing (apt-get install nlohmann-json3-dev)" >&2; exit 1; }
[[ -f $gtest/CMakeLists.txt ]] || { echo "gpu-deps: $gtest missing (apt-get install googletest)" >&2; exit 1; }
git -C "$root" check-ignore -q .deps/x || { echo "gpu-deps: .deps/ is not git-ignored" >&2; exit 1; }
rm -rf "$deps/json" "$deps/googletest"
mkdir -p "$deps/json"
cp -rL "$json" "$deps/json/nlohmann"
cp -rL "$gtest" "$deps/googletest"
echo "gpu-deps: $(du -sh "$deps" | cut -f1) in $deps"
