// Bodies the fluid moves (Run/Simulation.h's Body): a box floats at Archimedes' draft, the run is
// the same on Serial and OpenMP and from a checkpoint, and bad bodies are named.
#include "BodyContact.h"
#include "Distributed/ThreadCluster.h"
#include "MassProperties.h"
#include "Scene.h"
#include "SignedDistance.h"
#include "Simulation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

constexpr double kSpacing = 0.04;
constexpr double kHeight = 0.16; // the box's

// Water 0.3 m deep in a 0.6 m tank and a 0.2 x 0.16 x 0.2 m box of `relative` times the water's
// density, let go with its bottom 0.02 m below the surface.
Scene floatingBox(double relative)
{
  Scene scene;
  scene.name = "floating box";
  scene.domain = { { 0, 0, 0 }, { 0.6, 0.6, 0.6 } };
  scene.boxes.push_back({ { 0, 0, 0 }, { 0.6, 0.3, 0.6 }, { 0, 0, 0 } });
  SolidRegion box;
  box.kind = SolidRegion::Kind::Box;
  box.box = { { 0.2, 0.28, 0.2 }, { 0.4, 0.28 + kHeight, 0.4 } };
  box.density = relative * Parameters().restDensity;
  box.name = "box";
  scene.solids.push_back(box);
  return scene;
}

Parameters parameters()
{
  Parameters p;
  p.particleSpacing = kSpacing;
  return p;
}

// The box's draft: from the free surface (half a spacing above the highest particle away from
// the box) down to its bottom.
double draft(const Simulation& simulation)
{
  Snapshot<double> state;
  simulation.stepper().read(state);
  double top = 0;
  for (const Vec3d& q : state.position)
  {
    if (std::abs(q.x - 0.3) > 0.17 || std::abs(q.z - 0.3) > 0.17)
    {
      top = std::max(top, q.y);
    }
  }
  const Body& box = simulation.bodies().at(0);
  return top + 0.5 * kSpacing - (box.state.centre.y - 0.5 * kHeight);
}

std::string errorOf(const Scene& scene, Backend backend = Backend::Serial)
{
  try
  {
    Simulation simulation(scene, parameters(), backend, Precision::Single);
  }
  catch (const InvalidInput& e)
  {
    return e.what();
  }
  return "";
}

} // namespace

// Archimedes: a box of relative density r floats with a draft of r times its height. Fast
// version at 4 spacings of box height: the draft averaged over 1.5-2 s within 5 % of the height
// (measured at 2 s: r = 0.25 +3.2 %, 0.5 -0.9 %, 0.75 +1.4 %), and deeper for a denser box.
TEST(Bodies, BoxesFloatAtArchimedesDraft)
{
  double previous = 0;
  for (double relative : { 0.25, 0.5, 0.75 })
  {
    Simulation simulation(floatingBox(relative), parameters(), Backend::OpenMP, Precision::Single);
    simulation.advanceTo(1.5);
    double sum = 0;
    int samples = 0;
    for (int f = 1; f <= 10; ++f)
    {
      simulation.advanceTo(1.5 + 0.05 * f);
      sum += draft(simulation);
      ++samples;
    }
    const double mean = sum / samples;
    std::printf("relative density %.2f: draft %.4f m, Archimedes %.4f m (%+.1f %% of the height)\n",
      relative, mean, relative * kHeight, 100 * (mean - relative * kHeight) / kHeight);
    EXPECT_NEAR(mean, relative * kHeight, 0.05 * kHeight) << "relative density " << relative;
    EXPECT_GT(mean, previous);
    previous = mean;
  }
}

// The body's state comes from loads summed in a fixed order: OpenMP moves it as Serial does, bit
// for bit, and a run resumed from a checkpoint (the bodies' states and last loads in it) goes on
// as the straight run.
TEST(Bodies, TheSameBitsOnSerialOpenMpAndFromACheckpoint)
{
  Simulation serial(floatingBox(0.5), parameters(), Backend::Serial, Precision::Single);
  Simulation openmp(floatingBox(0.5), parameters(), Backend::OpenMP, Precision::Single);
  // Frame by frame on both (a frame's steps are shortened to land on it).
  serial.advanceTo(0.1);
  const SimulationCheckpoint halfway = serial.checkpoint();
  serial.advanceTo(0.2);
  openmp.advanceTo(0.1);
  openmp.advanceTo(0.2);
  const RigidState a = serial.bodies()[0].state, b = openmp.bodies()[0].state;
  EXPECT_EQ(a.centre.y, b.centre.y);
  EXPECT_EQ(a.velocity.y, b.velocity.y);
  EXPECT_EQ(a.orientation.x, b.orientation.x);
  EXPECT_NE(a.centre.y, 0.28 + 0.5 * kHeight) << "the box did not move";
  Simulation resumed(floatingBox(0.5), parameters(), Backend::Serial, Precision::Single);
  resumed.restore(halfway);
  resumed.advanceTo(0.2);
  const RigidState c = resumed.bodies()[0].state;
  EXPECT_EQ(a.centre.y, c.centre.y);
  EXPECT_EQ(a.velocity.y, c.velocity.y);
  EXPECT_EQ(a.angularMomentum.z, c.angularMomentum.z);
}

TEST(Bodies, BadBodiesAreInvalidInputNamingThem)
{
  Scene shell = floatingBox(0.5);
  shell.solids[0].kind = SolidRegion::Kind::Mesh;
  shell.solids[0].thickness = 0.01;
  shell.solids[0].mesh.points = { { 0.2, 0.3, 0.2 }, { 0.4, 0.3, 0.2 }, { 0.3, 0.3, 0.4 } };
  shell.solids[0].mesh.triangles = { { 0, 1, 2 } };
  EXPECT_NE(errorOf(shell).find("box: a shell (thickness > 0) encloses no solid"), std::string::npos)
    << errorOf(shell);
  Scene moved = floatingBox(0.5);
  moved.solids[0].density = std::nan("");
  EXPECT_NE(errorOf(moved).find("box: density = nan"), std::string::npos) << errorOf(moved);
}

// Two heavy cubes dropped into a shallow pool, one onto the other, and a third onto a fixed cube:
// none passes through another. A cube of side L holds the ball of radius L / 2 about its centre,
// so two cubes that do not overlap have centres at least L apart, however they turn; the contacts
// allow 5 % of L through. A cube that passed through would come within a fraction of L.
TEST(Bodies, BodiesMeetEachOtherAndFixedSolidsWithoutPassingThrough)
{
  Scene scene;
  scene.name = "stack";
  scene.domain = { { 0, 0, 0 }, { 0.8, 0.8, 0.6 } };
  scene.boxes.push_back({ { 0, 0, 0 }, { 0.8, 0.08, 0.6 }, { 0, 0, 0 } });
  const double side = kHeight;
  auto cube = [&](const std::string& name, const Vec3d& lo, double density) {
    SolidRegion b;
    b.kind = SolidRegion::Kind::Box;
    b.box = { lo, lo + Vec3d{ side, side, side } };
    b.density = density;
    b.name = name;
    return b;
  };
  scene.solids.push_back(cube("lower", { 0.1, 0.0, 0.2 }, 2000));
  scene.solids.push_back(cube("upper", { 0.12, 0.3, 0.22 }, 2000));
  scene.solids.push_back(cube("block", { 0.5, 0.0, 0.2 }, 0)); // fixed: no density
  scene.solids.push_back(cube("faller", { 0.52, 0.4, 0.22 }, 1500));
  const Vec3d blockCentre{ 0.58, 0.08, 0.28 };
  Simulation simulation(scene, parameters(), Backend::OpenMP, Precision::Single);
  ASSERT_EQ(simulation.bodies().size(), 3u);
  double closest = 1, closestToBlock = 1;
  for (int frame = 1; frame <= 60; ++frame)
  {
    simulation.advanceTo(frame / 60.0);
    const RigidState& lower = simulation.bodies()[0].state;
    const RigidState& upper = simulation.bodies()[1].state;
    const RigidState& faller = simulation.bodies()[2].state;
    closest = std::min(closest, length(upper.centre - lower.centre));
    closestToBlock = std::min(closestToBlock, length(faller.centre - blockCentre));
  }
  const RigidState& upper = simulation.bodies()[1].state;
  const RigidState& faller = simulation.bodies()[2].state;
  std::printf("closest centres over 1 s: upper-lower %.4f m, faller-block %.4f m (side %.2f m); "
              "upper ends at y = %.3f, faller at %.3f\n",
    closest, closestToBlock, side, upper.centre.y, faller.centre.y);
  EXPECT_GT(closest, 0.95 * side) << "the upper cube went into the lower";
  EXPECT_GT(closestToBlock, 0.95 * side) << "the faller went into the block";
  EXPECT_LT(upper.centre.y, 0.3) << "the upper cube did not fall";
  EXPECT_LT(faller.centre.y, 0.4) << "the faller did not fall";
}

TEST(Bodies, ABodyStartingThroughAWallOrInsideAnotherSolidIsNamed)
{
  Scene through = floatingBox(0.5);
  through.solids[0].box.min.y = -0.05;
  EXPECT_NE(errorOf(through).find("box: a body starts 0.05 m through the tank's -y wall"),
    std::string::npos)
    << errorOf(through);
  Scene inside = floatingBox(0.5);
  SolidRegion other = inside.solids[0];
  other.name = "other";
  other.box.min.x += 0.1;
  other.box.max.x += 0.1;
  inside.solids.push_back(other);
  const std::string error = errorOf(inside);
  EXPECT_EQ(error.rfind("box: a body starts ", 0), 0u) << error;
  EXPECT_NE(error.find(" m inside other; move them apart"), std::string::npos) << error;
  // Side by side, touching, is not inside.
  Scene touching = floatingBox(0.5);
  other.box.min.x = touching.solids[0].box.max.x;
  other.box.max.x = other.box.min.x + 0.2;
  touching.solids.push_back(other);
  EXPECT_EQ(errorOf(touching), "");
}

// A scene file says "density" to make an obstacle a body: a number > 0, and not with keyframes.
TEST(Bodies, ASceneFileNamesItsBadBodies)
{
  const std::string head = R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
    "fluid": [{"type": "box", "min": [0, 0, 0], "max": [1, 0.5, 1]}], "obstacles": [)";
  auto errorOfFile = [&](const std::string& obstacle) {
    try
    {
      parseScene(head + obstacle + "]}");
    }
    catch (const InvalidInput& e)
    {
      return std::string(e.what());
    }
    return std::string();
  };
  const Scene scene = parseScene(
    head + R"({"type": "box", "name": "crate", "min": [0.4, 0.4, 0.4], "max": [0.6, 0.6, 0.6], "density": 600})" + "]}");
  EXPECT_EQ(scene.solids.at(0).density, 600);
  EXPECT_EQ(scene.solids.at(0).name, "crate");
  const std::string negative =
    errorOfFile(R"({"type": "sphere", "center": [0.5, 0.5, 0.5], "radius": 0.1, "density": -1})");
  EXPECT_NE(negative.find(".obstacles[0].density"), std::string::npos) << negative;
  EXPECT_NE(negative.find("must be a finite number > 0"), std::string::npos) << negative;
  const std::string both = errorOfFile(R"({"type": "box", "min": [0.4, 0.4, 0.4], "max": [0.6, 0.6, 0.6],
    "density": 500, "motion": {"keyframes": [{"time": 0}]}})");
  EXPECT_NE(both.find("either by the fluid (density) or by its keyframes (motion)"), std::string::npos)
    << both;
}

// A body's "degreesOfFreedom" and "release" (a guide and a hold): read into the solid, and
// refused naming the key and the value for an obstacle that is no body, an unknown or repeated
// freedom, or a release that is not a time.
TEST(Bodies, ASceneFileGuidesAndHoldsItsBodies)
{
  const std::string head = R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
    "fluid": [{"type": "box", "min": [0, 0, 0], "max": [1, 0.5, 1]}], "obstacles": [)";
  const std::string sphere = R"({"type": "sphere", "center": [0.5, 0.6, 0.5], "radius": 0.1, )";
  auto errorOfFile = [&](const std::string& keys) {
    try
    {
      parseScene(head + sphere + keys + "}]}");
    }
    catch (const InvalidInput& e)
    {
      return std::string(e.what());
    }
    return std::string();
  };
  const Scene guided = parseScene(
    head + sphere + R"("density": 500, "degreesOfFreedom": ["y"], "release": 0.5})" + "]}");
  const SolidRegion& s = guided.solids.at(0);
  EXPECT_EQ(s.freeAxes, (std::array<bool, 3>{ false, true, false }));
  EXPECT_FALSE(s.turns);
  EXPECT_EQ(s.release, 0.5);
  const SolidRegion free = parseScene(head + sphere + R"("density": 500})" + "]}").solids.at(0);
  EXPECT_EQ(free.freeAxes, (std::array<bool, 3>{ true, true, true }));
  EXPECT_TRUE(free.turns);
  EXPECT_EQ(free.release, 0.0);
  const struct
  {
    const char* keys;
    const char* expected;
  } bad[] = {
    { R"("degreesOfFreedom": ["y"])", ".obstacles[0].degreesOfFreedom" },
    { R"("release": 1)", "applies to a body the fluid moves" },
    { R"("density": 500, "degreesOfFreedom": ["w"])", "must be a list of distinct" },
    { R"("density": 500, "degreesOfFreedom": ["x", "x"])", "[\"x\",\"x\"]" },
    { R"("density": 500, "degreesOfFreedom": "y")", "must be a list of distinct" },
    { R"("density": 500, "release": -1)", ".obstacles[0].release" },
    { R"("density": 500, "release": -1)", "must be a finite time >= 0" },
  };
  for (const auto& b : bad)
  {
    const std::string error = errorOfFile(b.keys);
    EXPECT_NE(error.find(b.expected), std::string::npos) << b.keys << ": " << error;
  }
}

// A box three times as dense as the water sinks and comes to rest on the tank's floor: its
// bottom within a spacing of the floor (a squeezed layer of water stays under it: 6 mm at 4 cm)
// and never through it, and it stays put over the last 0.5 s within 2 mm (measured 0.8 mm). Its
// velocity chatters from step to step (explicit coupling: +-0.09 m/s measured) while it stays.
TEST(Bodies, ADenseBoxSinksToTheFloorAndRestsThere)
{
  Simulation simulation(floatingBox(3.0), parameters(), Backend::OpenMP, Precision::Single);
  double lowest = 1, settledLow = 1, settledHigh = 0;
  for (int f = 1; f <= 30; ++f)
  {
    simulation.advanceTo(0.05 * f);
    const double bottom = simulation.bodies()[0].state.centre.y - 0.5 * kHeight;
    lowest = std::min(lowest, bottom);
    if (f > 20)
    {
      settledLow = std::min(settledLow, bottom);
      settledHigh = std::max(settledHigh, bottom);
    }
  }
  std::printf("bottom %.5f-%.5f m over 1-1.5 s, lowest %.5f m\n", settledLow, settledHigh, lowest);
  EXPECT_GE(lowest, -1e-6);
  EXPECT_LT(settledHigh, kSpacing);
  EXPECT_LT(settledHigh - settledLow, 0.002);
}

// On decomposed ranks every rank moves the body by the same loads (reduced over the ranks in
// rank order), so each rank's body is the same to the bit; against one rank, in double, within
// 1e-9 m after 0.2 s (the fluid's own decomposed bound).
TEST(Bodies, RanksMoveTheBodyAlikeAndAsOneRankDoes)
{
  Simulation one(floatingBox(0.5), parameters(), Backend::Serial, Precision::Double);
  one.advanceTo(0.1);
  one.advanceTo(0.2);
  std::vector<RigidState> ranks(2);
  distributed::runThreadCluster(2, [&](distributed::Communicator& communicator) {
    Simulation simulation(
      floatingBox(0.5), parameters(), Backend::Serial, Precision::Double, &communicator);
    simulation.advanceTo(0.1);
    simulation.advanceTo(0.2);
    ranks[static_cast<std::size_t>(communicator.rank())] = simulation.bodies()[0].state;
  });
  EXPECT_EQ(ranks[0].centre.y, ranks[1].centre.y);
  EXPECT_EQ(ranks[0].angularMomentum.x, ranks[1].angularMomentum.x);
  EXPECT_NEAR(ranks[0].centre.y, one.bodies()[0].state.centre.y, 1e-9);
  EXPECT_NEAR(ranks[0].centre.x, one.bodies()[0].state.centre.x, 1e-9);
  EXPECT_NE(one.bodies()[0].state.centre.y, 0.28 + 0.5 * kHeight) << "the box did not move";
}

namespace
{

// A box body at rest where the scene puts it, or (density 0) a fixed box, as Simulation's
// contactSide places each: the hull and field sampled in the scene's frame, the pose the body's.
struct ContactBox
{
  SolidRegion solid;
  MassProperties mass;
  ContactHull hull;
  DistanceGrid grid;
  RigidState state;

  ContactBox(const Box& box, double density)
  {
    solid.kind = SolidRegion::Kind::Box;
    solid.box = box;
    solid.density = density;
    if (density > 0)
    {
      mass = boxMassProperties(box, density, "box");
      state = restingState(mass);
    }
    hull = surfaceHull(solid, kSpacing);
    // Nodes 1 cm apart: the contacts below are 5 mm deep and at least 1.9 cm from the nearest
    // side, where the distance is linear over every cell they read, so the trilinear field is
    // the box's distance to the float rounding of its nodes and its normal the face's.
    grid = boxDistance(box, 0.01, 0.05);
  }

  ContactSide side()
  {
    ContactSide s;
    s.hull = &hull;
    const Box& b = solid.box;
    s.reach = 0.5 * length(b.max - b.min);
    s.centre = (b.min + b.max) * 0.5;
    const DistanceGridView<double> view = grid.view<double>(grid.phi.data(), nullptr);
    s.field = view;
    if (solid.density > 0)
    {
      s.body = &state;
      s.mass = &mass;
      s.pose = poseOf(state, mass);
      s.centre = state.centre;
      s.field = placed(view, s.pose);
    }
    return s;
  }
};

} // namespace

// Two bodies 5 mm into each other, the upper (4 kg) falling at 1 m/s onto the lower (12 kg, free,
// at rest): they are moved apart by the depth, shared by the inverse masses (the light one moves
// 3/4 of it, the heavy one 1/4), and the impulses that stop the approach change the velocities
// in the same 3:1, keeping the momentum: an inelastic contact, so both end at the common
// velocity -1/4 m/s. Tolerances: the depth comes from a field of float nodes (1e-8 m of rounding
// at 0.1 m, bound 1e-7); the shares and the momentum are sums of pushes and impulses each given
// to both bodies in the ratio, so only double rounding (1e-12) remains; the common velocity is
// what 8 sweeps of projected Gauss-Seidel over the face's contacts reach (1e-4 m/s measured,
// bound 1e-3 m/s, a thousandth of the impact speed; an impulse never taken back parts them at
// 0.66 m/s).
TEST(Bodies, ContactSharesTheSeparationAndImpulsesByInverseMass)
{
  const double depth = 0.005;
  // The upper's footprint 0.12 m square off the lower's samples (every 2 cm), at 4 kg.
  ContactBox lower({ { 0, 0, 0 }, { 0.2, 0.1, 0.2 } }, 3000);
  ContactBox upper({ { 0.041, 0.1 - depth, 0.041 }, { 0.161, 0.2 - depth, 0.161 } },
    4.0 / (0.12 * 0.1 * 0.12));
  ASSERT_NEAR(lower.mass.mass, 3 * upper.mass.mass, 1e-12);
  upper.state.velocity = { 0, -1, 0 };
  const Vec3d upperStart = upper.state.centre, lowerStart = lower.state.centre;
  const Vec3d momentum = upper.state.velocity * upper.mass.mass;
  ContactSide a = upper.side(), b = lower.side();
  ASSERT_TRUE(separate(a, b));
  const Vec3d movedUpper = upper.state.centre - upperStart;
  const Vec3d movedLower = lower.state.centre - lowerStart;
  std::printf("upper moved %.9f m, lower %.9f m; velocities %.9f, %.9f m/s\n", movedUpper.y,
    movedLower.y, upper.state.velocity.y, lower.state.velocity.y);
  EXPECT_NEAR(movedUpper.y - movedLower.y, depth, 1e-7) << "apart by the whole depth";
  EXPECT_NEAR(movedUpper.y, -3 * movedLower.y, 1e-12) << "the light body takes 3/4 of it";
  EXPECT_NEAR(movedUpper.y, 0.75 * depth, 1e-7);
  // The velocity changes: 3:1, the momentum kept, the approach stopped.
  const Vec3d dvUpper = upper.state.velocity - Vec3d{ 0, -1, 0 };
  const Vec3d dvLower = lower.state.velocity;
  EXPECT_NEAR(dvUpper.y, -3 * dvLower.y, 1e-12);
  const Vec3d after = upper.state.velocity * upper.mass.mass + lower.state.velocity * lower.mass.mass;
  EXPECT_NEAR(after.x, momentum.x, 1e-12);
  EXPECT_NEAR(after.y, momentum.y, 1e-12);
  EXPECT_NEAR(after.z, momentum.z, 1e-12);
  EXPECT_NEAR(upper.state.velocity.y, -0.25, 1e-3) << "inelastic: the common velocity";
  EXPECT_NEAR(lower.state.velocity.y, -0.25, 1e-3) << "inelastic: the common velocity";
}

// A body 5 mm into a fixed solid (no density) is pushed off it by the whole depth, the fixed one
// having no share, and stopped there (inelastic: it does not leave the solid). Tolerances as
// above: the float nodes' rounding, and the sweeps' residual for the velocity (an impulse never
// taken back sends it off at 0.68 m/s).
TEST(Bodies, ABodyIsPushedOffAFixedSolidByTheWholeDepth)
{
  const double depth = 0.005;
  ContactBox body({ { 0.041, 0.1 - depth, 0.041 }, { 0.161, 0.2 - depth, 0.161 } }, 2500);
  ContactBox fixed({ { 0, 0, 0 }, { 0.2, 0.1, 0.2 } }, 0);
  body.state.velocity = { 0, -1, 0 };
  const Vec3d start = body.state.centre;
  ContactSide a = body.side(), b = fixed.side();
  ASSERT_EQ(b.body, nullptr);
  ASSERT_TRUE(separate(a, b));
  const Vec3d moved = body.state.centre - start;
  std::printf("moved %.9f m, velocity %.9f m/s\n", moved.y, body.state.velocity.y);
  EXPECT_NEAR(moved.y, depth, 1e-7);
  EXPECT_NEAR(moved.x, 0, 1e-7);
  EXPECT_NEAR(body.state.velocity.y, 0.0, 1e-3) << "inelastic: stopped, not bounced";
}
