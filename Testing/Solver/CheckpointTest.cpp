// Checkpoints restore a simulation exactly, and the adaptive iteration mode meets its tolerance.
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

using namespace pbf;

namespace
{

Parameters coarse()
{
  Parameters p;
  p.particleSpacing = 0.04;
  return p;
}

template <class Real>
bool sameBits(const Simulation& a, const Simulation& b)
{
  Snapshot<Real> x, y;
  a.stepper().read(x);
  b.stepper().read(y);
  const std::size_t n = x.id.size();
  return x.id == y.id &&
    std::memcmp(x.position.data(), y.position.data(), n * sizeof(x.position[0])) == 0 &&
    std::memcmp(x.velocity.data(), y.velocity.data(), n * sizeof(x.velocity[0])) == 0 &&
    std::memcmp(x.density.data(), y.density.data(), n * sizeof(x.density[0])) == 0 &&
    std::memcmp(x.lambda.data(), y.lambda.data(), n * sizeof(x.lambda[0])) == 0 &&
    std::memcmp(x.pressure.data(), y.pressure.data(), n * sizeof(x.pressure[0])) == 0;
}

} // namespace

TEST(Checkpoint, RestoredRunIsBitIdenticalToAStraightRun)
{
  for (const char* scene : { "dam_break", "stream" }) // stream: emitter counters are state too
  {
    Simulation straight(presetScene(scene), coarse(), Backend::OpenMP, Precision::Single);
    straight.advance(50);

    Simulation resumed(presetScene(scene), coarse(), Backend::OpenMP, Precision::Single);
    resumed.advance(20);
    const SimulationCheckpoint at20 = resumed.checkpoint();
    EXPECT_GT(at20.bytes(), 0u);
    resumed.advance(17); // wander off, then come back
    resumed.restore(at20);
    EXPECT_EQ(resumed.stepCount(), 20u);
    resumed.advance(30);
    EXPECT_TRUE(sameBits<float>(straight, resumed)) << scene;
  }
}

TEST(Checkpoint, DoublePrecisionCheckpointIntoAFreshSimulation)
{
  Simulation straight(presetScene("blob"), coarse(), Backend::Serial, Precision::Double);
  straight.advance(40);
  Simulation source(presetScene("blob"), coarse(), Backend::Serial, Precision::Double);
  source.advance(25);
  Simulation fresh(presetScene("blob"), coarse(), Backend::Serial, Precision::Double);
  fresh.restore(source.checkpoint());
  fresh.advance(15);
  EXPECT_TRUE(sameBits<double>(straight, fresh));
}

TEST(Checkpoint, PrecisionMismatchIsAnError)
{
  Simulation single(presetScene("dam_break"), coarse(), Backend::Serial, Precision::Single);
  Simulation twice(presetScene("dam_break"), coarse(), Backend::Serial, Precision::Double);
  EXPECT_THROW(twice.restore(single.checkpoint()), InvalidInput);
}

TEST(AdaptiveIterations, StopsAtTheToleranceAndUsesFewerIterationsWhenCalm)
{
  Parameters p = coarse();
  p.particleSpacing = 0.02;
  p.solverIterations = 50;           // the cap
  p.densityErrorTolerance = 0.1;     // percent
  Simulation simulation(test::restingBlock(12, p.particleSpacing), p, Backend::OpenMP,
    Precision::Single);
  long total = 0;
  for (int k = 0; k < 100; ++k)
  {
    const AdvanceReport report = simulation.advance(1);
    ASSERT_LE(report.densityError, 0.001) << "step " << k; // met, not capped
    total += report.iterations;
  }
  // A resting block needs a few projections per step, not the cap.
  EXPECT_LT(total, 100 * 10);
  EXPECT_LE(simulation.stepper().statistics().averageDensityError, 0.001 + 1e-6);
}

TEST(AdaptiveIterations, FixedModeAppliesExactlyTheCount)
{
  Parameters p = coarse();
  p.solverIterations = 3;
  p.densityErrorTolerance = 0;
  Simulation simulation(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
  const AdvanceReport report = simulation.advance(5);
  EXPECT_EQ(report.iterations, 15);
  EXPECT_TRUE(std::isnan(report.densityError));
}

TEST(AdaptiveIterations, OpenMPIsBitIdenticalToSerial)
{
  Parameters p = coarse();
  p.solverIterations = 20;
  p.densityErrorTolerance = 0.05;
  Simulation a(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
  Simulation b(presetScene("dam_break"), p, Backend::OpenMP, Precision::Single);
  const AdvanceReport ra = a.advance(40);
  const AdvanceReport rb = b.advance(40);
  EXPECT_EQ(ra.iterations, rb.iterations);
  EXPECT_TRUE(sameBits<float>(a, b));
}
