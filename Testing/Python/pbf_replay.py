"""Child of the state and trace tests, run in a fresh pvbatch: rebuilds a pipeline from a saved
state (--state FILE.pvsm) or a Python trace (--trace FILE.py), then writes the particles of the
source named --name at --time to --output (an .npz of pbf_testing.frame()).

    pvbatch pbf_replay.py --plugin SO (--state PVSM | --trace PY) --name NAME --time T --output NPZ
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import simple  # noqa: E402

# The state and the trace name the plugin's proxies, which exist once it is loaded. Without ns,
# LoadPlugin adds the constructors to paraview.simple itself, where a trace's
# "from paraview.simple import *" finds them (as when a user runs: pvbatch, LoadPlugin, trace).
simple.LoadPlugin(T.plugin_path(), remote=False)
state = T.argument("--state")
trace = T.argument("--trace")
if state:
    simple.LoadState(state)
else:
    with open(trace) as script:
        # A trace is a script for paraview.simple; it runs as pvbatch would run it.
        exec(compile(script.read(), trace, "exec"), {"__name__": "__main__"})
source = simple.FindSource(T.argument("--name"))
T.expect(source is not None, "no source named %s after replay" % T.argument("--name"))
T.save_frame(T.argument("--output"), T.frame(source, float(T.argument("--time"))))
print("pbf_replay: wrote %s" % T.argument("--output"))
