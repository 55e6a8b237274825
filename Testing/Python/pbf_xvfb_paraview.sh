#!/bin/sh
# The client that smTestDriver starts for the GUI test: ParaView under a private X server,
# because Debian's VTK renders through X only (no EGL, no OSMesa). xvfb-run -a picks a free
# display, so GUI tests may run next to others. PBF_XVFB_RUN and PBF_PARAVIEW name the programs.
exec "${PBF_XVFB_RUN:-xvfb-run}" -a -s "-screen 0 1280x1024x24" "${PBF_PARAVIEW:-paraview}" "$@"
