#!/usr/bin/env bash
# The main job: install what is missing, build, and run the default dam break headlessly with
# pvbatch: output/dam_break/dam_break.pvd (one .vtp per frame) and output/dam_break/frames/*.png.
# Extra arguments go to Utilities/dam_break.py (e.g. --frames 30 --spacing 0.03).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBF_BUILD:-$root/build}
out=${PBF_OUTPUT:-$root/output/dam_break}
"$root/Utilities/install-deps.sh"
"$root/Utilities/build.sh" "$build"
plugin="$build/lib/paraview-5.11/plugins/PositionBasedFluids/PositionBasedFluids.so"
# Debian's VTK renders through X only: a private virtual display.
xvfb-run -a -s "-screen 0 1920x1080x24" \
  pvbatch "$root/Utilities/dam_break.py" --plugin "$plugin" --output "$out" "$@"
echo "main: wrote $out/dam_break.pvd and $out/frames/"
