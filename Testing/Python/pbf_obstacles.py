"""The Obstacles port: any ParaView geometry becomes a solid the fluid flows around.

A Sphere source and an STL file (a Box written by vtkSTLWriter, read by ParaView's STL reader)
stand in the dam break's way; no particle centre enters either in any frame, while the surge
reaches them. Fluid seeded inside an obstacle is removed with a warning giving the count. Moving
an obstacle by hand puts it there for the whole run; an animated Transform moves it frame by frame
(a paddle pushing the surge back), and so does a reader with time steps (a ball rolling towards the
column). An open surface, an empty dataset, an obstacle outside the tank and
a NaN point are errors naming the input, with the previous output kept; a thickness makes the
open surface a thin shell. A scene file's mesh obstacle (the shipped STL pillar) is read too."""
import math
import os
import sys
import tempfile

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview.simple import (Box, CompositeKeyFrame, Delaunay3D, GetAnimationScene,  # noqa: E402
                             GetAnimationTrack, Plane, ProgrammableSource, Sphere, STLReader,
                             Transform)
from vtkmodules.vtkFiltersSources import vtkCubeSource  # noqa: E402
from vtkmodules.vtkIOGeometry import vtkSTLWriter  # noqa: E402

T.load_plugin(globals())
expect = T.expect

SPACING = 0.04
FRAMES = 24  # 0.8 s at 1/30 s: the surge crosses the tank (x 0..1.6) and climbs the far wall
INTERVAL = 1.0 / 30.0

# A sphere on the floor (gravity is -y) in the surge's path; its facets lie at most r (1 - cos(pi / 24)) inside
# the sphere, so a centre closer than that to the centre is inside the solid.
CENTRE, RADIUS = numpy.array([0.9, 0.0, 0.3]), 0.2
sphere = Sphere(Center=list(CENTRE), Radius=RADIUS, ThetaResolution=24, PhiResolution=24)
INSCRIBED = RADIUS * math.cos(math.pi / 24)

# A box as an STL file, beside the sphere: x 1.2..1.4, y 0..0.3 (on the floor), z 0.05..0.25.
workdir = tempfile.mkdtemp(prefix="pbf_obstacles_")
stl = os.path.join(workdir, "block.stl")
cube = vtkCubeSource()
cube.SetBounds(1.2, 1.4, 0.0, 0.3, 0.05, 0.25)
writer = vtkSTLWriter()
writer.SetInputConnection(cube.GetOutputPort())
writer.SetFileName(stl)
writer.Write()
block = STLReader(FileNames=[stl])
BLOCK_LO, BLOCK_HI = numpy.array([1.2, 0.0, 0.05]), numpy.array([1.4, 0.3, 0.25])

fluid = PositionBasedFluids(Obstacles=[sphere, block], ParticleSpacing=SPACING,  # noqa: F821
                            NumberOfFrames=FRAMES, FrameInterval=INTERVAL)


# A solid is its distance grid's zero set (nodes s/2 apart, trilinear between them), which near
# an edge or across a curved face lies inside the exact shape by a little: a particle centre may
# sit that far inside the exact box or cylinder, no farther. With the solids' shape maps the fluid
# presses closer to their edges than the tangent plane let it (measured 0.002 s inside the STL
# box's edge, 0.005 s inside the pillar's facets); 0.01 s.
GRID = 0.01 * SPACING


def inside_block(points):
    return numpy.all((points > BLOCK_LO + GRID) & (points < BLOCK_HI - GRID), axis=1)


closest_sphere, closest_block, reached = numpy.inf, numpy.inf, 0
kept = {}
for f in range(FRAMES + 1):
    result = T.frame(fluid, f * INTERVAL)
    if f in (7, 16):
        kept[f] = result
    expect(T.finite(result["points"]), "non-finite positions at frame %d" % f)
    d = numpy.linalg.norm(result["points"] - CENTRE, axis=1)
    expect(d.min() >= INSCRIBED, "frame %d: a particle %.4f m from the sphere's centre (inside "
           "below %.4f)" % (f, d.min(), INSCRIBED))
    expect(not inside_block(result["points"]).any(), "frame %d: %d particles inside the STL box"
           % (f, inside_block(result["points"]).sum()))
    closest_sphere = min(closest_sphere, d.min() - RADIUS)
    gap = numpy.maximum(BLOCK_LO - result["points"], result["points"] - BLOCK_HI).max(axis=1)
    closest_block = min(closest_block, gap.min())
    reached = max(reached, int((d < RADIUS + 2 * SPACING).sum()))
# The checks above mean something only if the water meets both solids.
expect(closest_sphere < SPACING, "the surge never came within a spacing of the sphere (%.3f m)"
       % closest_sphere)
expect(closest_block < SPACING, "the surge never came within a spacing of the box (%.3f m)"
       % closest_block)
expect(reached > 20, "only %d particles ever came within 2 spacings of the sphere" % reached)
print("sphere and STL box: closest particle %.4f m / %.4f m from their surfaces, %d particles by "
      "the sphere at once, none inside in %d frames" % (closest_sphere, closest_block, reached,
                                                       FRAMES + 1))

# An unstructured grid is an obstacle through its outer surface: the tetrahedra of Delaunay3D
# over a Box's corners (x 1.0..1.2, y 0..0.3 on the floor, z 0.2..0.4), in the surge's way.
corners = Box(Center=[1.1, 0.15, 0.3], XLength=0.2, YLength=0.3, ZLength=0.2)
hull = Delaunay3D(Input=corners)
hull.UpdatePipeline()
expect(hull.GetDataInformation().GetDataSetTypeAsString() == "vtkUnstructuredGrid",
       "Delaunay3D gave %s" % hull.GetDataInformation().GetDataSetTypeAsString())
solid = PositionBasedFluids(Obstacles=[hull], ParticleSpacing=SPACING,  # noqa: F821
                            NumberOfFrames=FRAMES, FrameInterval=INTERVAL)
HULL_LO, HULL_HI = numpy.array([1.0, 0.0, 0.2]), numpy.array([1.2, 0.3, 0.4])
nearest = numpy.inf
for f in range(0, FRAMES + 1, 4):
    p = T.frame(solid, f * INTERVAL)["points"]
    inside = numpy.all((p > HULL_LO + 1e-5) & (p < HULL_HI - 1e-5), axis=1)
    expect(not inside.any(), "frame %d: %d particles inside the hull" % (f, inside.sum()))
    gap = numpy.maximum(HULL_LO - p, p - HULL_HI).max(axis=1)
    nearest = numpy.minimum(nearest, gap.min())
expect(nearest < SPACING, "the surge never reached the hull (%.3f m)" % nearest)
print("an unstructured grid (Delaunay3D, %d tetrahedra) as an obstacle: closest %.4f m"
      % (hull.GetDataInformation().GetNumberOfCells(), nearest))

# Frames asked again out of order (from checkpoints, the solids rebuilt with the run) are the
# same bits as on the way there.
for f in (16, 7):
    T.expect_identical(T.frame(fluid, f * INTERVAL), kept[f], "frame %d asked again" % f)

# Moving the sphere by hand while a frame is shown puts it there for the whole run (its motion
# as seen so far is replaced): the run starts again and the fluid meets it elsewhere.
before = T.frame(fluid, 12 * INTERVAL)
sphere.Center = [0.9, 0.8, 0.3]  # on the lid instead of the floor: the surge passes beneath it
after = T.frame(fluid, 12 * INTERVAL)
expect(not numpy.array_equal(before["points"], after["points"]),
       "moving the obstacle did not change the run")
lifted = numpy.linalg.norm(T.frame(fluid, 0.0)["points"] - numpy.array([0.9, 0.8, 0.3]), axis=1)
expect(lifted.min() >= INSCRIBED, "frame 0 again: a particle inside the moved sphere")
sphere.Center = list(CENTRE)

# An animated Transform moves an obstacle: a paddle (a Box source, x 0.70..0.78 across the tank)
# is driven by a keyframe track on its Transform's Translate towards the column, 0.3 m along -x
# over the run, and pushes the surge back. Every frame: no particle centre inside the paddle where
# the animation has it; the flow differs from that of a paddle left standing; frames asked again
# out of order are the same bits.
paddle = Box(Center=[0.74, 0.35, 0.3], XLength=0.08, YLength=0.7, ZLength=0.8)
moved = Transform(Input=paddle)
moved.Transform = "Transform"
pushed = PositionBasedFluids(Obstacles=[moved], ParticleSpacing=SPACING,  # noqa: F821
                             NumberOfFrames=FRAMES, FrameInterval=INTERVAL)
standing = PositionBasedFluids(Obstacles=[paddle], ParticleSpacing=SPACING,  # noqa: F821
                               NumberOfFrames=FRAMES, FrameInterval=INTERVAL)
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.StartTime, scene.EndTime = 0.0, FRAMES * INTERVAL
track = GetAnimationTrack("Position", index=0, proxy=moved.Transform)
track.KeyFrames = [CompositeKeyFrame(KeyTime=0.0, KeyValues=[0.0]),
                   CompositeKeyFrame(KeyTime=1.0, KeyValues=[-0.3])]
TRAVEL = 0.3 / (FRAMES * INTERVAL)  # m/s
pushed_frames = {}
deepest, nearest, differs = numpy.inf, numpy.inf, False
for f in range(FRAMES + 1):
    t = f * INTERVAL
    scene.AnimationTime = t
    offset = moved.Transform.Translate[0]
    expect(abs(offset + TRAVEL * t) < 1e-9, "frame %d: the track put the paddle at %g, not %g"
           % (f, offset, -TRAVEL * t))
    result = T.frame(pushed, t)
    pushed_frames[f] = result
    lo = numpy.array([0.70 + offset, 0.0, -0.1])
    hi = numpy.array([0.78 + offset, 0.7, 0.7])
    p = result["points"]
    gap = numpy.maximum(lo - p, p - hi).max(axis=1)  # < 0: inside the paddle's box
    deepest = min(deepest, gap.min())
    nearest = min(nearest, numpy.abs(gap).min())
    differs = differs or not numpy.array_equal(p, T.frame(standing, t)["points"])
# A centre on the paddle's face is on its surface: 10 um of rounding (float32) allowed.
expect(deepest > -1e-5, "a particle %.5f m inside the moving paddle" % -deepest)
expect(nearest < SPACING, "the surge never came within a spacing of the paddle (%.3f m)" % nearest)
expect(differs, "the animated paddle gave the same frames as a standing one")
for f in (FRAMES // 2, 5):
    scene.AnimationTime = f * INTERVAL
    T.expect_identical(T.frame(pushed, f * INTERVAL), pushed_frames[f],
                       "frame %d of the animated paddle asked again" % f)
print("an animated Transform moved the paddle 0.3 m: closest particle %.4f m from it, none inside "
      "in %d frames" % (nearest, FRAMES + 1))

# A reader with time steps moves an obstacle too: a programmable source that reports times 0..0.8 s
# and puts a ball on the floor at x = 1.2 - 0.5 t. Read at each frame's time, its motion is fitted
# frame by frame; no particle centre enters the ball where it is at that frame.
timed = ProgrammableSource(OutputDataSetType="vtkPolyData", Script="""
from vtkmodules.vtkFiltersSources import vtkSphereSource
info = self.GetOutputInformation(0)
t = info.Get(self.GetExecutive().UPDATE_TIME_STEP()) if info.Has(self.GetExecutive().UPDATE_TIME_STEP()) else 0.0
ball = vtkSphereSource()
ball.SetCenter(1.2 - 0.5 * t, 0.1, 0.3)
ball.SetRadius(0.1)
ball.SetThetaResolution(16)
ball.SetPhiResolution(16)
ball.Update()
self.GetOutput().ShallowCopy(ball.GetOutput())
self.GetOutput().GetInformation().Set(self.GetOutput().DATA_TIME_STEP(), t)
""", ScriptRequestInformation="""
executive = self.GetExecutive()
info = executive.GetOutputInformation(0)
info.Remove(executive.TIME_STEPS())
for k in range(25):
    info.Append(executive.TIME_STEPS(), k / 30.0)
info.Set(executive.TIME_RANGE(), [0.0, 0.8], 2)
""")
rolling = PositionBasedFluids(Obstacles=[timed], ParticleSpacing=SPACING,  # noqa: F821
                              NumberOfFrames=FRAMES, FrameInterval=INTERVAL)
INSCRIBED_BALL = 0.1 * math.cos(math.pi / 16)
closest_ball = numpy.inf
for f in range(0, FRAMES + 1, 2):
    t = f * INTERVAL
    p = T.frame(rolling, t)["points"]
    d = numpy.linalg.norm(p - numpy.array([1.2 - 0.5 * t, 0.1, 0.3]), axis=1)
    expect(d.min() >= INSCRIBED_BALL - 1e-5, "frame %d: a particle %.4f m from the moving ball's "
           "centre (inside below %.4f)" % (f, d.min(), INSCRIBED_BALL))
    closest_ball = numpy.minimum(closest_ball, d.min() - 0.1)  # not min(), as below
expect(closest_ball < SPACING, "the surge never reached the moving ball (%.3f m)" % closest_ball)
print("a reader with time steps moved a ball 0.4 m: closest particle %.4f m from it, none inside"
      % closest_ball)

# A change that is not rigid (the paddle made thicker: the same points, moved apart) samples the
# solid again from the new shape and starts the run again, said once, not at every change.
scene.AnimationTime = 12 * INTERVAL
paddle.XLength = 0.12
thicker, text = T.capture_messages(lambda: T.frame(pushed, 12 * INTERVAL))
expect("Obstacles input 1 changed shape at t = 0.4 s" in text, "no word of the new shape: %r" % text)
expect(not numpy.array_equal(thicker["points"], pushed_frames[12]["points"]),
       "the thicker paddle gave the same frame")
paddle.XLength = 0.10
_, text = T.capture_messages(lambda: T.frame(pushed, 12 * INTERVAL))
expect("changed shape" not in text, "the change of shape was said twice: %r" % text)

# Fluid seeded inside an obstacle is removed before the first step, with the count.
column = Box(Center=[0.2, 0.3, 0.3], XLength=0.2, YLength=0.2, ZLength=0.2)
seeded = PositionBasedFluids(Obstacles=[column], ParticleSpacing=SPACING,  # noqa: F821
                             NumberOfFrames=2)
alone = PositionBasedFluids(ParticleSpacing=SPACING, NumberOfFrames=2)  # noqa: F821
result, text = T.capture_messages(lambda: T.frame(seeded, 0.0))
n_alone = T.frame(alone, 0.0)["n"]
removed = n_alone - result["n"]
expect(removed > 0, "no particle was removed from inside the box (%d and %d)" % (
    n_alone, result["n"]))
expect(("%d initial particles lay inside the obstacles" % removed) in text,
       "the warning does not give the count %d: %r" % (removed, text))
# Lattice sites on the box's faces (0.1 = 0.02 + 2 x 0.04) are on the surface, not inside: 10 um
# (float32 positions round 0.1 up by 1.5 nm) keeps them out of the count.
lo, hi = numpy.array([0.1, 0.2, 0.2]) + 1e-5, numpy.array([0.3, 0.4, 0.4]) - 1e-5
expect(not numpy.all((result["points"] > lo) & (result["points"] < hi), axis=1).any(),
       "particles were left inside the box")

# Bad obstacles: each an error naming the input and the fault, the previous output kept.
plate = Plane(Origin=[0.8, 0.0, 0.1], Point1=[0.8, 0.3, 0.1], Point2=[0.8, 0.0, 0.5])
empty = ProgrammableSource(OutputDataSetType="vtkPolyData", Script="pass")
far = Sphere(Center=[5.0, 5.0, 5.0], Radius=0.2)
# A closed tetrahedron with a NaN corner.
nan = ProgrammableSource(OutputDataSetType="vtkPolyData", Script="""
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray
points = vtkPoints()
for p in ((0.8, 0.1, 0.2), (1.0, 0.1, 0.2), (0.9, 0.3, 0.2), (0.9, 0.1, float("nan"))):
    points.InsertNextPoint(p)
faces = vtkCellArray()
for f in ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)):
    faces.InsertNextCell(3, f)
output.SetPoints(points)
output.SetPolys(faces)
""")
checked = PositionBasedFluids(ParticleSpacing=SPACING, NumberOfFrames=2)  # noqa: F821
good = T.frame(checked, 0.0)
for obstacle, needles in ((plate, ["Obstacles input 1", "not closed", "thickness"]),
                          (empty, ["Obstacles input 1", "empty"]),
                          (far, ["Obstacles input 1", "outside the domain"]),
                          (nan, ["Obstacles input 1", "nan", "must be finite"])):
    checked.Obstacles = [obstacle]
    _, text = T.capture_messages(lambda: T.output_at(checked, 0.0))
    errors = [line for line in text.splitlines() if line.startswith("vtkPBFSimulation")]
    expect(len(errors) == 1, "expected one error for %s, got %r" % (needles, text))
    for needle in needles:
        expect(needle in errors[0], "the error %r does not name %r" % (errors[0], needle))
    T.expect_identical(T.frame(checked, 0.0), good, "the output after the error %s" % needles)

# The open plate with a thickness is a thin shell: accepted, and the fluid stays off it.
checked.Obstacles = [plate]
checked.ObstacleThickness = 1.5 * SPACING
checked.NumberOfFrames = FRAMES
checked.FrameInterval = INTERVAL
HALF = 0.75 * SPACING
nearest = numpy.inf
for f in range(0, FRAMES + 1, 4):
    p = T.frame(checked, f * INTERVAL)["points"]
    # Distance to the sheet x = 0.8, y 0..0.3, z 0.1..0.5; the solid is within HALF of it.
    out = numpy.stack([numpy.abs(p[:, 0] - 0.8),
                       numpy.maximum(numpy.maximum(0.0 - p[:, 1], p[:, 1] - 0.3), 0.0),
                       numpy.maximum(numpy.maximum(0.1 - p[:, 2], p[:, 2] - 0.5), 0.0)], axis=1)
    d = numpy.linalg.norm(out, axis=1)
    expect(d.min() >= HALF - 1e-4, "frame %d: a particle %.4f m from the plate's sheet (the "
           "shell reaches %.4f)" % (f, d.min(), HALF))
    nearest = numpy.minimum(nearest, d.min())  # not min(): ProgrammableSource rebinds it
expect(nearest < HALF + SPACING, "the surge never reached the plate (%.3f m)" % nearest)
print("plate of 0.06 m: closest particle %.4f m from its sheet" % nearest)

# A scene file's mesh obstacle: Data/Examples/dam_break_pillar.json reads pillar.stl (next to it)
# with VTK's STL reader. The pillar's facets lie at most 0.08 (1 - cos(pi / 24)) inside its radius
# (and its grid's surface GRID inside them).
data = os.environ.get("PBF_DATA_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "Data"))
pillar = PositionBasedFluids(SceneFile=os.path.join(data, "Examples", "dam_break_pillar.json"),  # noqa: F821
                             ParticleSpacing=SPACING, NumberOfFrames=FRAMES, FrameInterval=INTERVAL)
closest = numpy.inf
for f in range(0, FRAMES + 1, 2):
    p = T.frame(pillar, f * INTERVAL)["points"]
    below = p[:, 1] < 0.5  # the pillar's top
    r = numpy.hypot(p[below, 0] - 1.0, p[below, 2] - 0.3)
    expect(r.size == 0 or r.min() >= 0.08 * math.cos(math.pi / 24) - GRID,
           "frame %d: a particle %.4f m from the pillar's axis" % (f, r.min()))
    closest = numpy.minimum(closest, r.min() if r.size else numpy.inf)
expect(closest < 0.08 + SPACING, "the surge never reached the pillar (%.3f m)" % closest)
print("pillar.stl from a scene file: closest particle %.4f m from its axis (radius 0.08)" % closest)

# A mesh file edited in place is another run: the same scene file, its STL rewritten further on.
scene = os.path.join(workdir, "scene_block.json")
with open(scene, "w") as out:
    out.write('{"domain": {"min": [0, 0, 0], "max": [1.6, 0.8, 0.6]}, "fluid": [{"type": "box", '
              '"min": [0, 0, 0], "max": [0.4, 0.6, 0.6]}], "obstacles": [{"type": "mesh", '
              '"file": "block.stl"}]}')
edited = PositionBasedFluids(SceneFile=scene, ParticleSpacing=SPACING,  # noqa: F821
                             NumberOfFrames=FRAMES, FrameInterval=INTERVAL)
first = T.frame(edited, 12 * INTERVAL)
cube.SetBounds(0.6, 0.8, 0.0, 0.3, 0.2, 0.4)  # into the surge's way, earlier
writer.Write()
os.utime(stl, (os.path.getatime(stl), os.path.getmtime(stl) + 2))  # a coarse clock: still newer
# Nothing in the pipeline changed (the same path), so the algorithm is marked modified by hand,
# as any property change does; the run then sees the mesh's new size and time and starts again.
edited.GetClientSideObject().Modified()
second = T.frame(edited, 12 * INTERVAL)
expect(not numpy.array_equal(first["points"], second["points"]),
       "rewriting the scene's STL did not change the run")
p = second["points"]
expect(not numpy.all((p > numpy.array([0.6, 0.0, 0.2]) + 1e-5) &
                     (p < numpy.array([0.8, 0.3, 0.4]) - 1e-5), axis=1).any(),
       "particles inside the moved STL block")

# A scene file whose mesh is missing or of an unknown kind: an error naming the obstacle's file.
for name, needle in (("missing.stl", "no such file"), ("pillar.txt", "not an STL, OBJ, PLY or VTP")):
    scene = os.path.join(workdir, "scene_%s.json" % name.replace(".", "_"))
    with open(scene, "w") as out:
        out.write('{"domain": {"min": [0, 0, 0], "max": [1.6, 0.8, 0.6]}, "fluid": [{"type": "box", '
                  '"min": [0, 0, 0], "max": [0.4, 0.6, 0.6]}], "obstacles": [{"type": "mesh", '
                  '"file": "%s"}]}' % name)
    if name.endswith(".txt"):
        with open(os.path.join(workdir, name), "w") as out:
            out.write("not a mesh\n")
    broken = PositionBasedFluids(SceneFile=scene, ParticleSpacing=SPACING)  # noqa: F821
    _, text = T.capture_messages(lambda: T.output_at(broken, 0.0))
    # A new proxy may first say once that it found no GPU; that line is not the error.
    errors = [line for line in text.splitlines()
              if line.startswith("vtkPBFSimulation") and "Backend Auto" not in line]
    expect(len(errors) == 1 and "obstacles[0].file" in errors[0] and name in errors[0] and
           needle in errors[0], "the error for %s: %r" % (name, text))

T.passed("pbf_obstacles")
