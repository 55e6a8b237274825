"""The Surface output against ParaView's own way to a fluid surface (SPH Volume Interpolator, then
Contour), on the same frame and at the same grid cell size, in one pvbatch run:

    pvbatch Utilities/surface_bench.py --plugin PLUGIN [--spacing 0.02] [--frame 12] [--repeat 3]

Prints one row per method: the milliseconds (the median of --repeat runs; the Surface's own
extraction time from its field data SurfaceMilliseconds, the others the wall time of their
update), the triangles, and the ratio. The SPH path interpolates the particles' density with the
cubic kernel of support h (2 spacings) on a Bounded Volume over the fluid's bounds padded by h,
and contours it at rho_0 / 2: the level the colour function's 1/2 stands for."""
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "Testing",
                                "Python"))
import pbf_testing as T  # noqa: E402
from paraview import simple  # noqa: E402

T.load_plugin(globals())
spacing = float(T.argument("--spacing", 0.02))
frame = int(T.argument("--frame", 12))
repeat = int(T.argument("--repeat", 3))
interval = 1.0 / 60.0
t = frame * interval

fluid = PositionBasedFluids(ParticleSpacing=spacing, NumberOfFrames=frame,  # noqa: F821
                            FrameInterval=interval, GenerateSurface=1)
surface_port = simple.PassArrays(Input=simple.OutputPort(fluid, 3))
surface_port.UpdatePipeline(t)
algorithm = fluid.GetClientSideObject()
particles = algorithm.GetOutputDataObject(0)
ours = []
for k in range(repeat):
    # Another smoothing count and back: the same frame's surface computed again.
    fluid.SurfaceSmoothing = 1 if k % 2 == 0 else 0
    surface_port.UpdatePipeline(t)
    ours.append(T.field_value(algorithm.GetOutputDataObject(3), "SurfaceMilliseconds"))
fluid.SurfaceSmoothing = 0
surface_port.UpdatePipeline(t)
our_triangles = algorithm.GetOutputDataObject(3).GetNumberOfCells()

h = 2 * spacing
cell = 0.5 * spacing
lo, hi = list(particles.GetBounds()[0::2]), list(particles.GetBounds()[1::2])
volume = simple.SPHVolumeInterpolator(Input=simple.OutputPort(fluid, 0), Source="Bounded Volume")
volume.Source.Origin = [lo[a] - h for a in range(3)]
volume.Source.Scale = [hi[a] - lo[a] + 2 * h for a in range(3)]
volume.Source.RefinementMode = "Use cell-size"
volume.Source.CellSize = cell
volume.Kernel = "SPHCubicKernel"
volume.Kernel.SpatialStep = spacing
volume.DensityArray = "density"
contour = simple.Contour(Input=volume, ContourBy=["POINTS", "density"], Isosurfaces=[500.0])
sph, contouring = [], []
for k in range(repeat):
    volume.Kernel.SpatialStep = spacing * (1.0 + 1e-9 * (k % 2))  # a change: run it again
    start = time.perf_counter()
    volume.UpdatePipeline(t)
    middle = time.perf_counter()
    contour.UpdatePipeline(t)
    end = time.perf_counter()
    sph.append(1000 * (middle - start))
    contouring.append(1000 * (end - middle))
sph_triangles = contour.GetClientSideObject().GetOutputDataObject(0).GetNumberOfCells()
nodes = volume.GetClientSideObject().GetOutputDataObject(0).GetNumberOfPoints()

ours_ms = statistics.median(ours)
theirs_ms = statistics.median(sph) + statistics.median(contouring)
print("surface of the dam break, spacing %g m, frame %d (t = %.3f s): %d particles, grid cell %g m"
      % (spacing, frame, t, particles.GetNumberOfPoints(), cell))
print("| method | ms (median of %d) | triangles |" % repeat)
print("|---|---:|---:|")
print("| Surface output (SurfaceExtraction, all threads) | %.1f | %d |" % (ours_ms, our_triangles))
print("| SPH Volume Interpolator (%d nodes) + Contour | %.1f + %.1f = %.1f | %d |"
      % (nodes, statistics.median(sph), statistics.median(contouring), theirs_ms, sph_triangles))
print("ratio: %.1f x" % (theirs_ms / ours_ms))
