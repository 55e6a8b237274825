"""ParaView's GUI client (run by smTestDriver) connected to a pvserver of 2 MPI ranks,
all under one private Xvfb (the server ranks render too): it creates the source, plays a short
animation, and the particles it renders, colored by rank, come from both ranks, each particle once.
The server loads the plugin too (--plugins reaches both)."""
import os

import numpy
from paraview import servermanager, simple
from vtkmodules.util import numpy_support


def expect(condition, message):
    if not condition:
        raise RuntimeError("pbf_client_server: " + message)


expect(hasattr(simple, "PositionBasedFluids"),
       "the plugin's source is not available: was it loaded with --plugins?")
ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
expect(ranks == 2, "the server runs %d ranks, expected 2" % ranks)

source = simple.PositionBasedFluids(ParticleSpacing=0.04, NumberOfFrames=8)
view = simple.GetActiveViewOrCreate("RenderView")
view.ViewSize = [640, 360]
simple.Show(source, view)
scene = simple.GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.Play()
keeper = simple.GetTimeKeeper()
expect(keeper.Time == list(keeper.TimestepValues)[-1], "Play stopped at t = %g" % keeper.Time)

# What the view renders: the representation's data, from every rank; color it by rank.
owners = simple.ProcessIdScalars(Input=source)
simple.Hide(source, view)
shown = simple.Show(owners, view)
simple.ColorBy(shown, ("POINTS", "ProcessId"))
simple.Render(view)
output_dir = os.environ.get("PBF_GUI_OUTPUT", os.getcwd())
os.makedirs(output_dir, exist_ok=True)
simple.SaveScreenshot(os.path.join(output_dir, "pbf_client_server.png"), view,
                      ImageResolution=[640, 360])
data = servermanager.Fetch(owners)
process = numpy_support.vtk_to_numpy(data.GetPointData().GetArray("ProcessId"))
ids = numpy_support.vtk_to_numpy(data.GetPointData().GetArray("id"))
expect(set(process.tolist()) == {0, 1}, "particles came from ranks %s" % sorted(set(process.tolist())))
expect(len(numpy.unique(ids)) == len(ids) == data.GetNumberOfPoints(),
       "%d particles, %d distinct ids" % (data.GetNumberOfPoints(), len(numpy.unique(ids))))
info = source.GetDataInformation()
expect(info.GetNumberOfPoints() == len(ids), "the server counts %d particles, %d fetched"
       % (info.GetNumberOfPoints(), len(ids)))
print("pbf_client_server: %d particles, %d on rank 0 and %d on rank 1, frame %d of 8"
      % (len(ids), numpy.sum(process == 0), numpy.sum(process == 1), 8))
