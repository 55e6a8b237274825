"""Shared helpers of the plugin's pvpython/pvbatch tests.

The tests run in a builtin session (no separate server), so the VTK object behind a proxy is in
this process: frames are read from it directly, at exactly the time that was asked for.
"""
import os
import sys
import time

import numpy
from paraview import simple
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonCore import vtkLogger, vtkOutputWindow, vtkStringOutputWindow

# Small scenes keep each test to seconds: the dam break at 0.05 m spacing is 8 x 12 x 12 = 1152
# particles, one step about 10 ms on two cores.
QUICK_SPACING = 0.05
QUICK_PARTICLES = 8 * 12 * 12


class TestFailure(AssertionError):
    pass


def _fail_every_rank(kind, value, trace):
    """Under mpiexec, an uncaught exception ends the script on this rank while the other ranks wait
    for it in a collective call, until the test's timeout. Print it, then end this process at once
    with a non-zero code: mpiexec then stops every rank within seconds."""
    sys.__excepthook__(kind, value, trace)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(1)


if int(os.environ.get("OMPI_COMM_WORLD_SIZE", os.environ.get("PMI_SIZE", "1"))) > 1:
    sys.excepthook = _fail_every_rank


def expect(condition, message):
    """An assertion that survives python -O and says what was expected."""
    if not condition:
        raise TestFailure(message)


def cancelled_request(algorithm, request, after=0.01):
    """Runs request() while an observer plays the Cancel button: it sets AbortExecute once the
    algorithm's progress reaches `after`. Returns the result, the progress values the observer saw
    and the seconds the request took."""
    progress = []

    def cancel(caller, event):
        progress.append(caller.GetProgress())
        if 0.0 < caller.GetProgress() < 1.0 and caller.GetProgress() >= after:
            caller.SetAbortExecute(1)

    observer = algorithm.AddObserver("ProgressEvent", cancel)
    start = time.time()
    try:
        result = request()
    finally:
        algorithm.RemoveObserver(observer)
    return result, progress, time.time() - start


def plugin_path():
    """The plugin's shared library: --plugin PATH on the command line, else $PBF_PLUGIN."""
    if "--plugin" in sys.argv:
        return sys.argv[sys.argv.index("--plugin") + 1]
    path = os.environ.get("PBF_PLUGIN")
    expect(path, "no plugin given: pass --plugin PATH or set PBF_PLUGIN")
    return path


def argument(name, default=None):
    if name in sys.argv:
        return sys.argv[sys.argv.index(name) + 1]
    return default


def output_directory():
    """The folder named by --output (default: the working folder), made if missing."""
    path = argument("--output", os.getcwd())
    os.makedirs(path, exist_ok=True)
    return path


def load_plugin(namespace):
    """Loads the plugin in this process and puts its proxy constructors into namespace."""
    path = plugin_path()
    expect(os.path.isfile(path), "plugin not found: %s" % path)
    simple.LoadPlugin(path, remote=False, ns=namespace)
    for constructor in ("PositionBasedFluids", "PositionBasedFluidsFromPoints"):
        expect(constructor in namespace, "LoadPlugin did not define %s()" % constructor)


def capture_messages(action):
    """Runs action() with VTK's output window replaced by a string; returns (result, text).

    pvpython routes Python's print through the output window too, so nothing is printed
    while the capture is on. The logger's copy on stderr is silenced as well: an expected error
    must not look like an unexpected one ("ERR|") in the test's output.
    """
    previous = vtkOutputWindow.GetInstance()
    previous.Register(None)
    capture = vtkStringOutputWindow()
    vtkOutputWindow.SetInstance(capture)
    verbosity = vtkLogger.GetCurrentVerbosityCutoff()
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    try:
        result = action()
    finally:
        vtkLogger.SetStderrVerbosity(verbosity)
        vtkOutputWindow.SetInstance(previous)
        previous.UnRegister(None)
    return result, capture.GetOutput()


def output_at(proxy, time):
    """Updates the proxy at time and returns its VTK output (a live object: copy what you keep)."""
    proxy.UpdatePipeline(time)
    return proxy.GetClientSideObject().GetOutputDataObject(0)


def field_value(data, name):
    array = data.GetFieldData().GetAbstractArray(name)
    expect(array is not None, "field data array %s is missing" % name)
    if array.IsA("vtkStringArray"):
        return array.GetValue(0)
    if array.GetNumberOfComponents() == 1:
        return array.GetTuple1(0)
    return array.GetTuple(0)


def frame(proxy, time):
    """The particles of the frame answering time, as numpy arrays sorted by particle id."""
    return particles_of(output_at(proxy, time))


def particles_of(data):
    """A frame's particles (a vtkPolyData of this plugin, live or read back from a file) as numpy
    arrays sorted by particle id."""
    n = data.GetNumberOfPoints()
    # Every frame any test looks at has one vertex cell per point, each naming a point that exists
    # (a review's deliberate bug reused the cells of an earlier frame: 189 cells for 27 points).
    verts = data.GetVerts()
    expect(verts is not None and verts.GetNumberOfCells() == n,
           "%s vertex cells for %d points" % (verts.GetNumberOfCells() if verts else None, n))
    expect(data.GetNumberOfCells() == n, "%d cells for %d points" % (data.GetNumberOfCells(), n))
    if n > 0:
        connectivity = numpy_support.vtk_to_numpy(verts.GetConnectivityArray())
        expect(len(connectivity) == n and connectivity.min() >= 0 and connectivity.max() < n,
               "vertex cells name points %d..%d of %d (%d entries)"
               % (connectivity.min(), connectivity.max(), n, len(connectivity)))
    point_data = data.GetPointData()
    ids = numpy_support.vtk_to_numpy(point_data.GetArray("id")).copy()
    order = numpy.argsort(ids, kind="stable")
    result = {
        "n": n,
        "id": ids[order],
        "points": numpy_support.vtk_to_numpy(data.GetPoints().GetData())[order].copy(),
        "points_type": data.GetPoints().GetData().GetClassName(),
        "time": data.GetInformation().Get(data.DATA_TIME_STEP()),
        "step": int(field_value(data, "StepCount")),
        "frame": int(field_value(data, "Frame")),
    }
    for name in ("density", "lambda", "pressure", "velocity"):
        result[name] = numpy_support.vtk_to_numpy(point_data.GetArray(name))[order].copy()
    return result


def expect_identical(a, b, what):
    """Bit-identical frames: same ids, and every array equal element by element."""
    expect(a["n"] == b["n"], "%s: %d particles vs %d" % (what, a["n"], b["n"]))
    expect(numpy.array_equal(a["id"], b["id"]), "%s: the particle ids differ" % what)
    for name in ("points", "velocity", "density", "lambda", "pressure"):
        if not numpy.array_equal(a[name], b[name]):
            worst = numpy.max(numpy.abs(a[name].astype(float) - b[name].astype(float)))
            raise TestFailure("%s: %s differs (max |difference| %g)" % (what, name, worst))


def passed(name):
    sys.stdout.write("%s: passed\n" % name)
    sys.stdout.flush()


def finite(values):
    return bool(numpy.all(numpy.isfinite(values)))



def save_frame(path, result):
    """Writes a frame() result to an .npz file (the child side of the replay tests)."""
    numpy.savez(path, **{k: numpy.asarray(v) for k, v in result.items() if v is not None})


def load_frame(path):
    with numpy.load(path) as data:
        result = {k: data[k] for k in data.files}
    for key in ("n", "step", "frame"):
        result[key] = int(result[key])
    return result


def run_pvbatch(script, *arguments):
    """Runs script in a fresh pvbatch ($PBF_PVBATCH, else pvbatch on the PATH) with the plugin
    path after --plugin; returns its output, failing the test on a non-zero exit or a VTK error."""
    import subprocess
    pvbatch = os.environ.get("PBF_PVBATCH", "pvbatch")
    command = [pvbatch, "--dr", script, "--plugin", plugin_path()] + [str(a) for a in arguments]
    run = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    expect(run.returncode == 0 and "ERR|" not in run.stdout and "ERROR: " not in run.stdout,
           "%s exited with %d:\n%s" % (" ".join(command), run.returncode, run.stdout))
    return run.stdout


def diagnostics(proxy):
    """The diagnostics table (output port 1) as a dict of numpy arrays (strings as lists)."""
    table = proxy.GetClientSideObject().GetOutputDataObject(1)
    columns = {}
    for c in range(table.GetNumberOfColumns()):
        array = table.GetColumn(c)
        if array.IsA("vtkStringArray"):
            columns[array.GetName()] = [array.GetValue(r) for r in range(array.GetNumberOfValues())]
        else:
            columns[array.GetName()] = numpy_support.vtk_to_numpy(array).copy()
    return columns
