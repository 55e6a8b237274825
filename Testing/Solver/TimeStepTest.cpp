// The automatic step's speeds (SpeedHistogram.h, Simulation::nextTimeStep): the 99.9th
// percentile of the particles' speeds sets the step, the fastest particle only bounds it, and
// every host backend finds the same percentile.
#include "CpuStepper.h"
#include "Distributed/SubdomainStepper.h"
#include "Distributed/ThreadCluster.h"
#include "SpeedHistogram.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

using namespace pbf;

namespace
{

// The widest bin: speed^2's mantissa from 1 to 9/8.
const double kWidestBin = std::sqrt(9.0 / 8.0);

} // namespace

// Speeds from 1e-3 to 1e3 m/s, 200 a decade: each lies below its bin's top and at or above the
// top of the bin before (1e-15 relative: both tops are square roots rounded once), and no bin
// is wider than sqrt(9/8), 6.1 %.
TEST(SpeedHistogram, EachSpeedLiesInItsBinBelowItsTop)
{
  for (int k = 0; k <= 1200; ++k)
  {
    const double v = std::pow(10.0, -3.0 + k / 200.0);
    const int b = speedBin(v * v);
    ASSERT_GT(b, 0) << v;
    ASSERT_LT(b, kSpeedBins - 1) << v;
    EXPECT_LT(v, speedBinTop(b) * (1 + 1e-15)) << v;
    EXPECT_GE(v * (1 + 1e-15), speedBinTop(b - 1)) << v;
    EXPECT_LE(speedBinTop(b) / speedBinTop(b - 1), kWidestBin * (1 + 1e-15)) << v;
  }
  EXPECT_EQ(speedBin(0.0), 0);
  EXPECT_EQ(speedBin(std::nan("")), 0);
  EXPECT_EQ(speedBin(1e300), kSpeedBins - 1);
}

// 10,000 particles at 1 m/s: with 10 at 8 m/s (a thousandth of 10,010 may be faster) the robust
// speed is the top of 1 m/s's bin; with 11 the percentile falls among the fast ones, whose bin's
// top lies above the fastest: the fastest. Fewer than 1,000 particles: the fastest.
TEST(SpeedHistogram, TheRobustSpeedIsThe999thPercentileRoundedUpAndAtMostTheFastest)
{
  std::vector<std::uint64_t> counts(kSpeedBins, 0);
  counts[static_cast<std::size_t>(speedBin(1.0))] = 10000;
  counts[static_cast<std::size_t>(speedBin(64.0))] = 10;
  const double robust = robustSpeed(counts.data(), 8.0);
  EXPECT_EQ(robust, speedBinTop(speedBin(1.0)));
  EXPECT_GT(robust, 1.0);
  EXPECT_LE(robust, kWidestBin);
  counts[static_cast<std::size_t>(speedBin(64.0))] = 11;
  EXPECT_EQ(robustSpeed(counts.data(), 8.0), 8.0);
  std::vector<std::uint64_t> few(kSpeedBins, 0);
  few[static_cast<std::size_t>(speedBin(1.0))] = 100;
  few[static_cast<std::size_t>(speedBin(64.0))] = 1;
  EXPECT_EQ(robustSpeed(few.data(), 8.0), 8.0);
  const std::vector<std::uint64_t> none(kSpeedBins, 0);
  EXPECT_EQ(robustSpeed(none.data(), 0.0), 0.0);
}

// The falling dam break (4 cm, 30 steps): serial and OpenMP scan the same bits alike; two CPU
// ranks, whose states differ from one rank's by rounding (~1e-13), within a bin (a speed on a
// bin's edge may fall either side).
TEST(SpeedHistogram, TheRobustSpeedIsTheSameOnSerialOpenMpAndTwoRanks)
{
  const test::PresetFluid setup = test::presetFluid("dam_break", 0.04);
  CpuStepper<double> serial(false, setup.parameters, setup.fluid);
  CpuStepper<double> openmp(true, setup.parameters, setup.fluid);
  for (int s = 0; s < 30; ++s)
  {
    serial.step();
    openmp.step();
  }
  const Health a = serial.health();
  EXPECT_EQ(openmp.health().robustSpeed, a.robustSpeed);
  EXPECT_GT(a.robustSpeed, 0.1); // the column is falling (a whole layer as fast as the fastest)
  std::vector<Health> ranks(2);
  distributed::runThreadCluster(2, [&](distributed::Communicator& communicator) {
    distributed::SubdomainStepper<double> stepper(
      communicator, false, setup.parameters, setup.fluid);
    for (int s = 0; s < 30; ++s)
    {
      stepper.step();
    }
    ranks[static_cast<std::size_t>(communicator.rank())] = stepper.health();
  });
  for (const Health& h : ranks)
  {
    EXPECT_EQ(h.robustSpeed, ranks[0].robustSpeed) << "every rank must choose the same step";
    EXPECT_LE(h.robustSpeed, a.robustSpeed * kWidestBin);
    EXPECT_GE(h.robustSpeed * kWidestBin, a.robustSpeed);
  }
}

namespace
{

constexpr double kSpraySpacing = 0.05;

// The scene's fluid and one spray particle above it at (0.25, 0.8, 0.25), moving at `spray` m/s
// along x (set in the state: an initial speed would raise v_scene), in an automatic-step serial
// simulation whose divergence scan (which the next step's size reads) has run.
Simulation withSprayParticle(const Scene& scene, double spray)
{
  test::PresetFluid fluid = test::sceneFluid(scene, kSpraySpacing);
  fluid.fluid.position.push_back({ 0.25, 0.8, 0.25 });
  fluid.fluid.velocity.push_back({ 0, 0, 0 });
  fluid.fluid.id.push_back(static_cast<std::int64_t>(fluid.fluid.id.size()));
  Parameters p = fluid.parameters;
  p.timeStepping = TimeStepping::Automatic;
  Simulation simulation(scene, p, Backend::Serial, Precision::Double, fluid.fluid);
  Snapshot<double> state;
  simulation.stepper().read(state);
  for (std::size_t i = 0; i < state.id.size(); ++i)
  {
    if (state.id[i] == static_cast<std::int64_t>(state.id.size()) - 1)
    {
      state.velocity[i] = { spray, 0, 0 };
    }
  }
  simulation.stepper().load(state);
  simulation.checkDivergence();
  return simulation;
}

} // namespace

// A block of 10 x 10 x 10 particles at rest and one spray particle above it at 8 m/s: the step
// is no longer cflNumber s / 8 m/s, which one particle of 1,001 set, but the largest step, below
// the scene's (cflNumber s / v_scene, v_scene the fall across the box, 4.4 m/s); at 60 m/s the
// spray particle is bounded by kFastestStepSpacings: it moves a spacing in the step.
TEST(TimeStep, OneSprayParticleNoLongerSetsTheStepButTheFastestIsBounded)
{
  constexpr double s = kSpraySpacing;
  const Scene scene = test::restingBlock(10, s);
  for (double spray : { 8.0, 60.0 })
  {
    const Simulation simulation = withSprayParticle(scene, spray);
    const Parameters& p = simulation.parameters();
    const double sceneSpeed = simulation.divergenceLimits().sceneSpeed;
    ASSERT_LT(sceneSpeed, spray) << "the scene's fall speed would hide the spray particle";
    const double expected = std::min({ p.timeStep, p.cflNumber * s / sceneSpeed,
      Simulation::kFastestStepSpacings * s / spray, p.cflNumber * std::sqrt(s / length(p.gravity)) });
    EXPECT_DOUBLE_EQ(simulation.nextTimeStep(), expected) << spray << " m/s";
    EXPECT_GT(simulation.nextTimeStep(), 1.5 * p.cflNumber * s / spray) << spray << " m/s";
  }
}

// The same block with a sphere in a corner of the box, away from the fluid: with a solid in the
// scene the spray particle at 8 m/s sets the step again, cflNumber s / 8 m/s (a prediction
// collides only where it lands, so no particle may cross a thin solid in one step).
TEST(TimeStep, WithSolidsTheFastestMovesAtMostTheCflNumber)
{
  constexpr double s = kSpraySpacing, spray = 8.0;
  Scene scene = test::restingBlock(10, s);
  SolidRegion ball;
  ball.kind = SolidRegion::Kind::Sphere;
  ball.center = { 0.45, 0.95, 0.45 };
  ball.radius = 0.04;
  scene.solids.push_back(ball);
  const Simulation simulation = withSprayParticle(scene, spray);
  EXPECT_DOUBLE_EQ(simulation.nextTimeStep(), simulation.parameters().cflNumber * s / spray);
}
