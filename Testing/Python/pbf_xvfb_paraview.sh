#!/bin/sh
# The client that smTestDriver starts for the GUI test: ParaView under a private Xvfb (see
# pbf_xvfb.py for why not xvfb-run -a). PBF_PYTHON and PBF_PARAVIEW name the programs.
PBF_XVFB_PASSTHROUGH=1 exec "${PBF_PYTHON:-python3}" "$(dirname "$0")/pbf_xvfb.py" \
  "${PBF_PARAVIEW:-paraview}" "$@"
