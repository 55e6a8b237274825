"""The Surface output (port 3): the fluid's surface as closed triangles with Normals, velocity and
density, from the same frame as the particles (what asks for it: pbf_surface_demand.py).

The dam break at 4 cm: the source's UpdatePipeline alone leaves port 3 empty; a filter on it gives a
surface that has no boundary edge, encloses at least 98 % of the particles
(vtkSelectEnclosedPoints) in every frame asked, carries the frame's time, and changes with the
frame. A bad SurfaceResolution is an error naming it, and the particles stay. An obstacle (a
Sphere source in the dam break's path) clips the surface: no vertex inside it, still closed."""
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import simple  # noqa: E402
from vtkmodules.numpy_interface import dataset_adapter as dsa  # noqa: E402
from vtkmodules.vtkFiltersCore import vtkFeatureEdges  # noqa: E402
from vtkmodules.vtkFiltersModeling import vtkSelectEnclosedPoints  # noqa: E402

T.load_plugin(globals())
expect = T.expect

INTERVAL = 1.0 / 30.0


def count_open_edges(surface):
    """Edges used by one triangle only: 0 for a closed surface."""
    edges = vtkFeatureEdges()
    edges.SetInputData(surface)
    edges.BoundaryEdgesOn()
    edges.FeatureEdgesOff()
    edges.NonManifoldEdgesOff()
    edges.ManifoldEdgesOff()
    edges.Update()
    return edges.GetOutput().GetNumberOfCells()


fluid = PositionBasedFluids(ParticleSpacing=0.04, NumberOfFrames=12,  # noqa: F821
                            FrameInterval=INTERVAL)
algorithm = fluid.GetClientSideObject()

# Nothing downstream of port 3: it stays empty.
fluid.UpdatePipeline(0.0)
expect(algorithm.GetOutputDataObject(3).GetNumberOfCells() == 0,
       "the surface was computed though GenerateSurface is off")
fluid.GenerateSurface = 1
# A filter on port 3, as a user would make one.
downstream = simple.PassArrays(Input=simple.OutputPort(fluid, 3))

previous = None
for f in (0, 6, 12):
    t = f * INTERVAL
    downstream.UpdatePipeline(t)
    surface = algorithm.GetOutputDataObject(3)
    particles = algorithm.GetOutputDataObject(0)
    n = particles.GetNumberOfPoints()
    triangles = surface.GetNumberOfCells()
    expect(triangles > 100, "frame %d: %d triangles" % (f, triangles))
    for name in ("Normals", "velocity", "density"):
        expect(surface.GetPointData().GetArray(name) is not None, "frame %d: no %s" % (f, name))
    info = surface.GetInformation()
    expect(abs(info.Get(surface.DATA_TIME_STEP()) - t) < 1e-12,
           "frame %d: the surface is of time %r" % (f, info.Get(surface.DATA_TIME_STEP())))
    # Closed: no edge used by one triangle only.
    open_edges = count_open_edges(surface)
    expect(open_edges == 0, "frame %d: %d boundary edges" % (f, open_edges))
    # The particles inside it.
    enclosed = vtkSelectEnclosedPoints()
    enclosed.SetInputData(particles)
    enclosed.SetSurfaceData(surface)
    enclosed.Update()
    inside = dsa.WrapDataObject(enclosed.GetOutput()).PointData["SelectedPoints"]
    fraction = float(numpy.count_nonzero(inside)) / n
    expect(fraction >= 0.98, "frame %d: the surface encloses %.2f %% of the particles"
           % (f, 100 * fraction))
    # Interpolated fields: the density within the particles' range.
    density = dsa.WrapDataObject(surface).PointData["density"]
    expect(numpy.all(numpy.isfinite(density)) and density.min() > 0,
           "frame %d: surface density %g..%g" % (f, density.min(), density.max()))
    points = dsa.WrapDataObject(surface).Points
    if previous is not None:
        expect(points.shape != previous.shape or not numpy.array_equal(points, previous),
               "frame %d: the same surface as the frame before" % f)
    previous = numpy.array(points)
    # Made where the run is: a CUDA run's on its GPU, any other on the CPU; and it says so.
    on_gpu = T.field_value(particles, "Backend").startswith("CUDA")
    where = T.field_value(surface, "SurfaceDevice")
    expect((where != "CPU") == on_gpu, "frame %d: SurfaceDevice %r for the backend %r"
           % (f, where, T.field_value(particles, "Backend")))
    print("frame %d: %d particles, surface of %d triangles, no boundary edge, encloses %.2f %%, "
          "%.0f ms" % (f, n, triangles, 100 * fraction,
                       T.field_value(surface, "SurfaceMilliseconds")))

# A bad resolution: an error naming it; the particles are still delivered.
fluid.SurfaceResolution = 0.0
_, text = T.capture_messages(lambda: downstream.UpdatePipeline(6 * INTERVAL))
expect("SurfaceResolution = 0" in text, "no error naming SurfaceResolution: %r" % text)
expect(algorithm.GetOutputDataObject(0).GetNumberOfPoints() > 0, "the particles were lost")
fluid.SurfaceResolution = 0.5

# Anisotropic kernels: another surface of the same frame, still closed and around the particles.
downstream.UpdatePipeline(12 * INTERVAL)
round_points = numpy.array(dsa.WrapDataObject(algorithm.GetOutputDataObject(3)).Points)
fluid.SurfaceAnisotropic = 1
downstream.UpdatePipeline(12 * INTERVAL)
surface = algorithm.GetOutputDataObject(3)
points = numpy.array(dsa.WrapDataObject(surface).Points)
print("anisotropic: %d triangles (round kernels: %d vertices, anisotropic %d), %d open edges"
      % (surface.GetNumberOfCells(), len(round_points), len(points), count_open_edges(surface)))
expect(surface.GetNumberOfCells() > 100 and count_open_edges(surface) == 0,
       "the anisotropic surface is empty or open")
expect(points.shape != round_points.shape or not numpy.array_equal(points, round_points),
       "SurfaceAnisotropic changed nothing")
fluid.SurfaceAnisotropic = 0

# An obstacle clips the surface: the water meets the ball at its face and no surface vertex lies
# inside it (a tenth of a spacing: the ball's field is trilinear on nodes s/2 apart, against
# the Sphere source's polygons), and the surface stays closed.
CENTRE, RADIUS = (0.9, 0.0, 0.3), 0.2
ball = simple.Sphere(Center=list(CENTRE), Radius=RADIUS, ThetaResolution=32, PhiResolution=32)
around = PositionBasedFluids(Obstacles=[ball], ParticleSpacing=0.04, NumberOfFrames=12,  # noqa: F821
                             FrameInterval=INTERVAL, GenerateSurface=1)
around.UpdatePipeline(12 * INTERVAL)
surface = around.GetClientSideObject().GetOutputDataObject(3)
points = dsa.WrapDataObject(surface).Points
inside = numpy.linalg.norm(points - numpy.array(CENTRE), axis=1) - RADIUS
open_edges = count_open_edges(surface)
near = numpy.count_nonzero(numpy.abs(inside) < 0.1 * 0.04)
print("obstacle: %d triangles, deepest vertex %.4f m into the ball, %d vertices on its face, "
      "%d open edges" % (surface.GetNumberOfCells(), -inside.min(), near,
                         open_edges))
expect(inside.min() > -0.1 * 0.04, "a surface vertex %.4f m inside the ball" % -inside.min())
expect(near > 20, "the surface does not meet the ball (%d vertices on its face)" % near)
expect(open_edges == 0, "the clipped surface is open")
T.passed("pbf_surface")
