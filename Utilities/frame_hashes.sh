#!/usr/bin/env bash
# The frames' fingerprints (pbf_frame_hash) of every shipped scene, single and double, on 1 and 2
# ranks, in two solver modes (the defaults: adaptive projections; and a fixed count of 3 with
# Chebyshev's acceleration, wall friction and XSPH's hyper-viscosity), for each backend named: one
# CSV line per frame, after a line naming the mode. Run it on two builds and diff the outputs to
# show that a change keeps every frame bit for bit:
#   bash Utilities/frame_hashes.sh BUILD_DIR "serial openmp cuda" [pbf_frame_hash options...]
# e.g. --spacing 0.05 for quick CPU runs. The scenes are the presets (the solver's tools do not
# read the mesh of Data/Examples' pillar: the ParaView tests run that scene).
set -uo pipefail

tool=${1:?usage: frame_hashes.sh BUILD_DIR BACKENDS [options]}/Solver/Tools/pbf_frame_hash
backends=${2:-serial openmp}
shift 2 || shift $#
modes=("defaults:" "fixed:--tolerance 0 --iterations 3 --chebyshev 0.8 --friction 0.5 --xsph-hyper 0.1")
status=0
for mode in "${modes[@]}"; do
  echo "mode ${mode%%:*}"
  for scene in dam_break double_dam_break blob stream marin_dam_break; do
    for backend in $backends; do
      for precision in single double; do
        for ranks in 1 2; do
          # shellcheck disable=SC2086
          "$tool" --scene "$scene" --backend "$backend" --precision "$precision" --ranks "$ranks" \
            ${mode#*:} "$@" || { echo "$scene,$backend,$precision,$ranks: FAILED"; status=1; }
        done
      done
    done
  done
done
exit $status
