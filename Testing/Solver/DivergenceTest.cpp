// A simulation that blows up is stopped at the step where it happens, with SimulationDiverged
// naming the step, what was found and the likely cause. The scenes really blow up: PBF clamps
// particles into the box, so they pile up on the walls (density many times rho_0) long before
// anything turns NaN.
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

using namespace pbf;

namespace
{

// The dam break at s = 0.05 m (1152 particles) on the serial reference, which is deterministic,
// with the fixed time step, iteration count and light XSPH these blow-ups need: the defaults
// (automatic steps, adaptive iterations) prevent them (AutomaticSteppingHoldsWhatFixedStepsBlowUp).
Parameters coarse()
{
  return test::coarseFixedSteps();
}

// The SimulationDiverged that advancing `steps` throws; fails the test when none is thrown.
SimulationDiverged divergence(Simulation& simulation, std::uint64_t steps)
{
  try
  {
    simulation.advance(steps);
  }
  catch (const SimulationDiverged& error)
  {
    return error;
  }
  ADD_FAILURE() << "no divergence in " << steps << " steps";
  return SimulationDiverged("none", 0, 0, 0, "");
}

// A cube of 8 x 8 x 8 given points at the spacing d, and an empty 1 x 2 x 1 m box to hold it.
ParticleBatch cube(double d)
{
  ParticleBatch points;
  for (int i = 0; i < 8; ++i)
  {
    for (int j = 0; j < 8; ++j)
    {
      for (int k = 0; k < 8; ++k)
      {
        points.position.push_back({ 0.4 + d * i, 0.4 + d * j, 0.4 + d * k });
        points.velocity.push_back({ 0, 0, 0 });
        points.id.push_back(static_cast<std::int64_t>(points.id.size()));
      }
    }
  }
  return points;
}

Scene openBox()
{
  Scene box;
  box.domain = { { 0, 0, 0 }, { 1, 2, 1 } };
  return box;
}

#define EXPECT_MENTIONS(message, text)                                                            \
  EXPECT_NE(std::string(message).find(text), std::string::npos)                                   \
    << "\"" << (message) << "\" lacks " << (text)

} // namespace

TEST(Divergence, HugeGravityIsCaughtAtTheFirstStepAndBlamesTheTimeStep)
{
  // g = 1e4 m/s^2 moves a particle 3.5 spacings per step: the column is crushed into the floor
  // (13 x rho_0) in the first step. The tiny relaxation is named too.
  Parameters p = coarse();
  p.gravity = { 0, -1e4, 0 };
  p.relaxation = 1e-6;
  Simulation simulation(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
  const SimulationDiverged error = divergence(simulation, 100);
  EXPECT_EQ(error.step(), 1u);
  EXPECT_EQ(error.lastGoodStep(), 0u);
  EXPECT_MENTIONS(error.what(), "simulation diverged at step 1 (t = 0.00417 s");
  EXPECT_MENTIONS(error.what(), "x restDensity");
  EXPECT_MENTIONS(error.cause(), "the time step dt = 0.00417 s is too large");
  EXPECT_MENTIONS(error.cause(), "gravity alone moves a particle 3.47 spacings per step");
  EXPECT_MENTIONS(error.cause(), "relaxation epsilon = 1e-06 is too small");
}

TEST(Divergence, HugeTimeStepIsCaughtAtTheStepItHappens)
{
  // dt = 0.05 s, 12 x the default: at step 2 the fastest particle already crosses 0.9 h per
  // step, at step 3 the fluid piles up on the floor at 3.1 x rho_0 (and later at 800 x).
  Parameters p = coarse();
  p.timeStep = 0.05;
  Simulation simulation(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
  const SimulationDiverged error = divergence(simulation, 60);
  EXPECT_EQ(error.step(), 3u);
  EXPECT_EQ(error.lastGoodStep(), 2u);
  EXPECT_DOUBLE_EQ(error.time(), 0.15);
  EXPECT_EQ(simulation.stepCount(), 3u); // advance() stopped there
  EXPECT_MENTIONS(error.cause(), "the time step dt = 0.05 s is too large");
  EXPECT_MENTIONS(error.cause(), "lower timeStep");

  // The same 0.15 s at the default step is fine.
  Simulation calm(presetScene("dam_break"), coarse(), Backend::Serial, Precision::Single);
  EXPECT_NO_THROW(calm.advance(36));
}

TEST(Divergence, AutomaticSteppingHoldsWhatFixedStepsBlowUp)
{
  // The blow-ups above with the defaults of automatic stepping and adaptive iterations: 0.05 s
  // and 1/60 s are then only the largest step, and one iteration only the cap. Each must get
  // through a second of the dam break with the front at a physical speed (at most 3 sqrt(g H) =
  // 7.3 m/s for the 0.6 m column) and no particle over 1.2 rho_0.
  for (double largest : { 0.05, 1.0 / 60.0 })
  {
    Parameters p;
    p.particleSpacing = 0.05;
    p.timeStep = largest;
    Simulation simulation(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
    AdvanceReport report;
    for (int frame = 1; frame <= 60; ++frame)
    {
      ASSERT_NO_THROW(report.add(simulation.advanceTo(frame / 60.0))) << largest << " " << frame;
      const Statistics s = simulation.stepper().statistics();
      ASSERT_LE(s.maxSpeed, 7.3) << largest << " at frame " << frame;
      ASSERT_LE(s.maxDensityError, 0.2) << largest << " at frame " << frame;
    }
    EXPECT_EQ(simulation.time(), 1.0); // landed on the frame exactly
    // The CFL step, not the largest one, set the pace: 0.4 s / 4.5 m/s is about 4.4 ms.
    EXPECT_LT(report.maxTimeStep, 0.0046) << largest;
  }
}

TEST(Divergence, OneIterationAtALargeStepBlamesTheIterations)
{
  // One substep per 60 Hz frame with one iteration: over 3 x rho_0 at step 8. Either alone is
  // fine. The step is not blamed: the fastest particle crossed less than h per step before.
  Parameters p = coarse();
  p.timeStep = 1.0 / 60.0;
  p.solverIterations = 1;
  Simulation simulation(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
  const SimulationDiverged error = divergence(simulation, 60);
  EXPECT_EQ(error.step(), 8u);
  EXPECT_MENTIONS(error.cause(), "too few solver iterations (solverIterations = 1)");
  for (int iterations : { 1, 4 })
  {
    Parameters fine = coarse();
    fine.solverIterations = iterations;
    fine.timeStep = iterations == 1 ? coarse().timeStep : 1.0 / 60.0;
    Simulation ok(presetScene("dam_break"), fine, Backend::Serial, Precision::Single);
    EXPECT_NO_THROW(ok.advance(static_cast<std::uint64_t>(0.5 / fine.timeStep))) << iterations;
  }
}

TEST(Divergence, UnilateralOffIsNamedFirst)
{
  // Without the clamp of C_i at 0 the free surface pulls itself together: particles fly across
  // the box at 83 m/s by step 184, beyond 20 x the scene's 4 m/s.
  Parameters p = coarse();
  p.unilateral = false;
  Simulation simulation(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
  const SimulationDiverged error = divergence(simulation, 300);
  EXPECT_EQ(error.step(), 184u);
  EXPECT_MENTIONS(error.what(), "the fastest particle moves at");
  EXPECT_EQ(error.cause().rfind("Unilateral is off", 0), 0u) << error.cause();
}

TEST(Divergence, NonFiniteStateIsCaughtAtTheNextStepNamingAParticle)
{
  // NaN cannot be reached through valid input; a checkpoint can carry it in.
  Simulation simulation(presetScene("dam_break"), coarse(), Backend::Serial, Precision::Single);
  simulation.advance(10);
  SimulationCheckpoint checkpoint = simulation.checkpoint();
  auto& state = std::get<Snapshot<float>>(checkpoint.state);
  state.velocity[100].y = std::numeric_limits<float>::quiet_NaN();
  const std::int64_t id = state.id[100];
  simulation.restore(checkpoint);
  const SimulationDiverged error = divergence(simulation, 5);
  EXPECT_EQ(error.step(), 11u);
  EXPECT_EQ(error.lastGoodStep(), 10u);
  EXPECT_MENTIONS(error.what(), "with a non-finite position or velocity");
  EXPECT_MENTIONS(error.what(), "particle id " + std::to_string(id));
}

TEST(Divergence, TheIntervalChoosesTheGranularity)
{
  Parameters p = coarse();
  p.timeStep = 0.05;
  // Every 4th step: the blow-up of step 3 is found at step 4, counted from step 0 whatever the
  // advance() calls.
  Simulation everyFourth(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
  everyFourth.setDivergenceCheckInterval(4);
  everyFourth.advance(1);
  everyFourth.advance(2);
  const SimulationDiverged error = divergence(everyFourth, 10);
  EXPECT_EQ(error.step(), 4u);
  EXPECT_EQ(error.lastGoodStep(), 0u);
  // Off: the run goes on, and an explicit check still finds it.
  Simulation off(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
  off.setDivergenceCheckInterval(0);
  EXPECT_NO_THROW(off.advance(10));
  EXPECT_THROW(off.checkDivergence(), SimulationDiverged);
}

TEST(Divergence, LimitsFollowTheScene)
{
  // Dam break: a fall across the 0.8 m height from rest, sqrt(2 g 0.8) = 3.96 m/s; density 3 x.
  Simulation dam(presetScene("dam_break"), coarse(), Backend::Serial, Precision::Single);
  EXPECT_NEAR(dam.divergenceLimits().sceneSpeed, std::sqrt(2 * 9.81 * 0.8), 1e-12);
  EXPECT_NEAR(dam.divergenceLimits().maxSpeed, 20 * std::sqrt(2 * 9.81 * 0.8), 1e-9);
  EXPECT_NEAR(dam.divergenceLimits().maxDensityError, 2.0, 1e-5);
  // Given points at 0.8 s start near 2 x rho_0: the limit follows them, and the cube bursting
  // apart at 16 m/s in zero gravity (the limit is 2 h / dt = 48 m/s) is no divergence.
  Parameters p = coarse();
  p.gravity = { 0, 0, 0 };
  Simulation bursting(openBox(), p, Backend::Serial, Precision::Single, cube(0.8 * p.particleSpacing));
  EXPECT_GT(bursting.divergenceLimits().maxDensityError, 4.0);
  EXPECT_NO_THROW(bursting.advance(100));
}

TEST(Divergence, PointsFarDenserThanTheLatticeAreRefusedNamingTheirPacking)
{
  // At half the spacing (8 x rho_0) the first correction flung particles out at 83 m/s, and the
  // divergence check blamed the time step. Now the cause is named before any step: 8 points per
  // cell of the spacing, and the spacing they fit.
  Parameters p = coarse();
  p.gravity = { 0, 0, 0 };
  try
  {
    Simulation dense(openBox(), p, Backend::Serial, Precision::Single, cube(0.5 * p.particleSpacing));
    FAIL() << "points at half the spacing were accepted";
  }
  catch (const InvalidInput& error)
  {
    EXPECT_MENTIONS(error.what(), "512 points in 64 occupied cells");
    EXPECT_MENTIONS(error.what(), "8 per cell");
    EXPECT_MENTIONS(error.what(), "Set particleSpacing to about 0.025 m");
  }
  // Points at 0.8 s (2 per cell) are a fluid the solver relaxes: accepted (LimitsFollowTheScene).
  EXPECT_NO_THROW(Simulation(openBox(), p, Backend::Serial, Precision::Single,
    cube(0.8 * p.particleSpacing)));
}

TEST(Divergence, PointsOnAMirrorWallAreRefusedNamingThePoint)
{
  // An input lattice starting on the floor: the floor's image doubles the bottom layer. Named
  // with the first such point and the domain's scene; half a spacing up, the same points run.
  Parameters p = coarse();
  ParticleBatch onFloor = cube(p.particleSpacing);
  for (Vec3d& x : onFloor.position)
  {
    x.y -= 0.4; // the cube's bottom layer at y = 0
  }
  try
  {
    Simulation simulation(openBox(), p, Backend::Serial, Precision::Single, onFloor);
    FAIL() << "points on the floor were accepted";
  }
  catch (const InvalidInput& error)
  {
    EXPECT_MENTIONS(error.what(), "64 points lie within a quarter of particleSpacing");
    EXPECT_MENTIONS(error.what(), "point 0 = (0.4, 0, 0.4)");
    EXPECT_MENTIONS(error.what(), "Move the points half a spacing inside");
  }
  for (Vec3d& x : onFloor.position)
  {
    x.y += 0.5 * p.particleSpacing;
  }
  Simulation lifted(openBox(), p, Backend::Serial, Precision::Single, onFloor);
  EXPECT_NO_THROW(lifted.advance(10));
  // Without mirror walls a point on a wall is an ordinary particle.
  p.mirrorWalls = false;
  for (Vec3d& x : onFloor.position)
  {
    x.y -= 0.5 * p.particleSpacing;
  }
  EXPECT_NO_THROW(Simulation(openBox(), p, Backend::Serial, Precision::Single, onFloor));
}
