"""Several liquids in ParaView: a scene file names water and oil, the output carries each
particle's "liquid" (an index into the field data's LiquidNames) and each liquid's density in its
own units; the From Points filter takes a point array "liquid"; an unknown liquid name, a density
of 0 and an index beyond the scene's liquids are errors naming them, the previous output kept."""
import json
import os
import shutil
import sys
import tempfile

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402

T.load_plugin(globals())
expect = T.expect
from paraview.simple import ProgrammableSource  # noqa: E402
from vtkmodules.util import numpy_support  # noqa: E402
from vtkmodules.vtkFiltersCore import vtkFeatureEdges, vtkThreshold  # noqa: E402
from vtkmodules.vtkFiltersGeometry import vtkGeometryFilter  # noqa: E402

folder = tempfile.mkdtemp(prefix="pbf_liquids_")
SCENE = {"name": "water_and_oil", "domain": {"min": [0, 0, 0], "max": [0.4, 0.5, 0.16]},
         "liquids": [{"name": "water", "restDensity": 1000},
                     {"name": "oil", "restDensity": 800}],
         "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.4, 0.16, 0.16], "liquid": "water"},
                   {"type": "box", "min": [0, 0.16, 0], "max": [0.4, 0.32, 0.16],
                    "liquid": "oil"}]}


def scene_file(name, scene):
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        f.write(json.dumps(scene))
    return path


def liquids_of(data):
    ids = numpy_support.vtk_to_numpy(data.GetPointData().GetArray("id"))
    array = data.GetPointData().GetArray("liquid")
    expect(array is not None, "the output has no point array \"liquid\"")
    return numpy_support.vtk_to_numpy(array)[numpy.argsort(ids, kind="stable")].copy()


layers = PositionBasedFluids(SceneFile=scene_file("layers.json", SCENE),  # noqa: F821
                             ParticleSpacing=0.04, NumberOfFrames=30)
first = T.frame(layers, 0.0)
data = T.output_at(layers, 0.0)
liquid = liquids_of(data)
expect(first["n"] == 320, "the layers gave %d particles" % first["n"])
expect(numpy.array_equal(liquid, (first["points"][:, 1] > 0.16).astype(liquid.dtype)),
       "water is not below and oil above")
names = data.GetFieldData().GetAbstractArray("LiquidNames")
expect(names is not None and names.GetNumberOfValues() == 2 and names.GetValue(1) == "oil",
       "LiquidNames %r" % (names and [names.GetValue(i) for i in range(names.GetNumberOfValues())]))
densities = data.GetFieldData().GetArray("LiquidRestDensities")
expect(densities.GetTuple1(0) == 1000 and densities.GetTuple1(1) == 800, "the rest densities")

# Half a second on: the layers stay apart, each liquid near its own rest density.
later = T.frame(layers, 0.5)
liquid = liquids_of(T.output_at(layers, 0.5))
oil = later["density"][liquid == 1]
water = later["density"][liquid == 0]
# The medians: the oil's top layer lacks neighbours above and reads low (the free surface).
print("after 0.5 s: water %.1f, oil %.1f kg/m^3 (medians); oil's lowest particle %.3f m, water's "
      "highest %.3f m" % (numpy.median(water), numpy.median(oil),
                          later["points"][liquid == 1, 1].min(),
                          later["points"][liquid == 0, 1].max()))
expect(abs(numpy.median(water) - 1000) < 20 and abs(numpy.median(oil) - 800) < 16,
       "the median densities %.1f and %.1f are not each liquid's (2 %%)"
       % (numpy.median(water), numpy.median(oil)))
expect(numpy.median(later["points"][liquid == 1, 1]) > numpy.median(later["points"][liquid == 0, 1]),
       "the oil is not above the water")

# The surface: one closed surface per liquid, its points marked by their liquid, the oil's above
# the water's.
layers.GenerateSurface = 1
layers.UpdatePipeline(0.5)
surface = layers.GetClientSideObject().GetOutputDataObject(3)
marks = surface.GetPointData().GetArray("liquid")
expect(marks is not None, "the surface has no point array \"liquid\"")
marks = numpy_support.vtk_to_numpy(marks)
heights = numpy_support.vtk_to_numpy(surface.GetPoints().GetData())[:, 1]
expect(set(numpy.unique(marks)) == {0, 1}, "the surface's liquids %r" % numpy.unique(marks))
expect(heights[marks == 1].max() > heights[marks == 0].max() + 0.08,
       "the oil's surface does not reach above the water's")
for liquid_index in (0, 1):
    part = vtkThreshold()
    part.SetInputData(surface)
    part.SetInputArrayToProcess(0, 0, 0, 0, "liquid")
    part.SetLowerThreshold(liquid_index)
    part.SetUpperThreshold(liquid_index)
    part.Update()
    closed = vtkGeometryFilter()
    closed.SetInputConnection(part.GetOutputPort())
    edges = vtkFeatureEdges()
    edges.SetInputConnection(closed.GetOutputPort())
    edges.BoundaryEdgesOn()
    edges.FeatureEdgesOff()
    edges.NonManifoldEdgesOff()
    edges.ManifoldEdgesOff()
    edges.Update()
    expect(part.GetOutput().GetNumberOfCells() > 100 and edges.GetOutput().GetNumberOfCells() == 0,
           "liquid %d's surface: %d triangles, %d open edges" % (
               liquid_index, part.GetOutput().GetNumberOfCells(),
               edges.GetOutput().GetNumberOfCells()))
layers.GenerateSurface = 0

# From Points: the input's point array "liquid" gives each point its liquid.
LATTICE = """
import numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.util import numpy_support
g = (numpy.arange(8) + 0.5) * 0.04
x = numpy.array(numpy.meshgrid(g[:10], g[:6], g[:4], indexing="ij")).reshape(3, -1).T.copy()
points = vtkPoints()
points.SetData(numpy_support.numpy_to_vtk(x, deep=True))
output.SetPoints(points)
l = numpy_support.numpy_to_vtk(%s, deep=True)
l.SetName("liquid")
output.GetPointData().AddArray(l)
"""
cloud = ProgrammableSource(OutputDataSetType="vtkPolyData",
                           Script=LATTICE % "(x[:, 1] > 0.12).astype(numpy.int32)")
fluid = PositionBasedFluidsFromPoints(Input=cloud, ParticleSpacing=0.04,  # noqa: F821
                                      SceneFile=layers.SceneFile)
given = T.frame(fluid, 0.0)
given_liquid = liquids_of(T.output_at(fluid, 0.0))
expect(numpy.array_equal(given_liquid, (given["points"][:, 1] > 0.12).astype(given_liquid.dtype)),
       "the input's liquid array was not each particle's liquid")

# Bad liquids: each an error naming it; the previous output stays.
BAD = [
    ("an unknown liquid name", dict(SCENE, fluid=[dict(SCENE["fluid"][0], liquid="mercury")]),
     [".fluid[0].liquid", "mercury", "unknown liquid", "water, oil"]),
    ("a density of 0", dict(SCENE, liquids=[SCENE["liquids"][0], {"name": "oil", "restDensity": 0}]),
     [".liquids[1].restDensity = 0", "must be > 0"]),
]
for k, (what, scene, needles) in enumerate(BAD):
    layers.SceneFile = scene_file("bad%d.json" % k, scene)
    _, text = T.capture_messages(lambda: T.output_at(layers, 0.5))
    errors = [line for line in text.splitlines() if line.startswith("vtkPBFSimulation")]
    expect(len(errors) == 1, "%s: expected one vtkPBFSimulation error, got %r" % (what, text))
    for needle in needles:
        expect(needle in errors[0], "%s: the error %r does not name %r" % (what, errors[0], needle))
    T.expect_identical(T.frame(layers, 0.5), later, "%s: the output after the error" % what)
cloud.Script = LATTICE % "numpy.full(len(x), 2, dtype=numpy.int32)"
_, text = T.capture_messages(lambda: T.output_at(fluid, 0.0))
errors = [line for line in text.splitlines() if line.startswith("vtkPBFSimulation")]
expect(len(errors) == 1 and "liquid of particle 0 = 2" in errors[0] and "2 liquids" in errors[0],
       "an index beyond the scene's liquids gave %r" % text)
T.expect_identical(T.frame(fluid, 0.0), given, "the From Points output after the error")

shutil.rmtree(folder)
T.passed("pbf_liquids")
