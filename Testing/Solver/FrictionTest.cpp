// Wall friction (Parameters::wallFriction): a layer of fluid sliding along the floor keeps its
// speed on free-slip walls and is held back by no-slip ones, whether the floor is the domain's
// (a mirror wall) or a solid obstacle; friction is the same on every host backend; out-of-range
// values are refused naming the field.
#include "Scene.h"
#include "Simulation.h"
#include "Stepper.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace pbf;

namespace
{

// A layer 0.1 m deep sliding along +x at 1 m/s over a floor 1.8 m long, at s = 0.025 m: either
// the domain's floor or a box solid 0.1 m thick with the domain's floor under it.
Scene slidingLayer(bool solidFloor)
{
  const std::string floor = solidFloor ? "0.1" : "0.0";
  const std::string top = solidFloor ? "0.2" : "0.1";
  return parseScene(R"({
    "domain": { "min": [0, 0, 0], "max": [1.8, 0.5, 0.1] },
    "fluid": [ { "type": "box", "min": [0, )" + floor + R"(, 0], "max": [0.5, )" + top +
    R"(, 0.1], "velocity": [1, 0, 0] } ])" +
    (solidFloor ? R"(, "obstacles": [ { "type": "box", "min": [-1, -1, -1], "max": [3, 0.1, 1] } ])"
                : "") +
    "}");
}

// The mean x velocity after 0.25 s (the layer's front is still 0.5 m from the far wall).
double meanSlidingSpeed(bool solidFloor, double friction, Backend backend = Backend::Serial)
{
  Parameters p;
  p.particleSpacing = 0.025;
  p.wallFriction = friction;
  Simulation simulation(slidingLayer(solidFloor), p, backend, Precision::Double);
  simulation.advanceTo(0.25);
  Snapshot<double> state;
  simulation.stepper().read(state);
  double sum = 0;
  for (const Vec3d& v : state.velocity)
  {
    sum += v.x;
  }
  return sum / static_cast<double>(state.velocity.size());
}

} // namespace

TEST(WallFriction, FreeSlipLetsALayerSlideAndNoSlipHoldsItBack)
{
  for (bool solidFloor : { false, true })
  {
    SCOPED_TRACE(solidFloor ? "on a solid floor" : "on the domain's floor");
    const double free = meanSlidingSpeed(solidFloor, 0.0);
    const double half = meanSlidingSpeed(solidFloor, 0.5);
    const double stuck = meanSlidingSpeed(solidFloor, 1.0);
    std::printf("%s: mean speed after 0.25 s: friction 0 %.4f, 0.5 %.4f, 1 %.4f m/s\n",
      solidFloor ? "solid floor" : "domain floor", free, half, stuck);
    // Free-slip: nothing along x acts on the layer but the side walls' pressure as it spreads
    // (it keeps flowing into the empty part of the tank), so it keeps most of its 1 m/s.
    EXPECT_GT(free, 0.9);
    // Friction removes speed, more the more friction: the bound is the measured effect's scale
    // (a tenth of the free-slip speed at phi = 1), so a friction that did nothing would fail.
    EXPECT_LT(half, free - 0.02);
    EXPECT_LT(stuck, half - 0.02);
    EXPECT_LT(stuck, 0.9 * free);
  }
}

TEST(WallFriction, SerialAndOpenMPAreBitIdenticalWithFriction)
{
  // The same stages in the same order on both host backends (Equations.h), friction included.
  const double serial = meanSlidingSpeed(true, 1.0, Backend::Serial);
  const double openmp = meanSlidingSpeed(true, 1.0, Backend::OpenMP);
  EXPECT_EQ(serial, openmp);
}

TEST(WallFriction, OutOfRangeIsRefusedNamingTheField)
{
  for (double bad : { -0.1, 1.5, std::nan("") })
  {
    Parameters p;
    p.wallFriction = bad;
    try
    {
      p.validate();
      ADD_FAILURE() << "wallFriction = " << bad << " accepted";
    }
    catch (const InvalidInput& error)
    {
      EXPECT_NE(std::string(error.what()).find("wallFriction"), std::string::npos) << error.what();
    }
  }
}
