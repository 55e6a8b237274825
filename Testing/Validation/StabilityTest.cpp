// Vorticity confinement at 100 x the default (1 m/s) in the closed dam-break tank: no blow-up,
// kinetic energy bounded by the potential energy released, and nothing lost, duplicated, outside
// or NaN. Built twice: pbf_validation_tests runs 2,000 steps at s = 0.08 m (label "validation",
// in CI); pbf_validation_long_tests 10,000 steps at s = 0.05 m (label "long"). The shipped scenes'
// 10,000-step conservation soak is Testing/Solver's SoakLong.
#include "Measures.h"

#include "Scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#ifdef PBF_VALIDATION_LONG
#define PBF_STABILITY_SUITE StabilityLong
constexpr std::uint64_t kSteps = 10000;
constexpr double kSpacing = 0.05; // 1,152 particles
#else
#define PBF_STABILITY_SUITE Stability
constexpr std::uint64_t kSteps = 2000;
constexpr double kSpacing = 0.08; // 245 particles
#endif

using namespace pbf;
using namespace pbf::validation;

TEST(PBF_STABILITY_SUITE, StrongVorticityConfinementKeepsEnergyBoundedInAClosedBox)
{
  Parameters p;
  p.particleSpacing = kSpacing;
  p.vorticityEpsilon = 1.0;
  Simulation simulation(presetScene("dam_break"), p, Backend::OpenMP, Precision::Single);
  const double initialPotential = potentialEnergy(simulation);
  double released = 0, maxKinetic = 0, lateKinetic = 0;
  for (std::uint64_t done = 0; done < kSteps; done += 100)
  {
    simulation.advance(100); // the divergence check runs every step: it throws on a blow-up
    const std::string violation = conservationViolation(simulation, simulation.idCount());
    ASSERT_EQ(violation, "") << "step " << simulation.stepCount();
    const Statistics s = simulation.stepper().statistics();
    released = std::max(released, initialPotential - potentialEnergy(simulation));
    maxKinetic = std::max(maxKinetic, s.kineticEnergy);
    // Energy can only come from the fall: confinement that feeds energy in breaks this first.
    // Both sides are sums of a few thousand terms in double: no tolerance needed beyond that.
    ASSERT_LE(s.kineticEnergy, released) << "step " << simulation.stepCount();
    if (done + 100 >= kSteps / 2)
    {
      lateKinetic = std::max(lateKinetic, s.kineticEnergy);
    }
  }
  std::printf("%llu steps at s = %.2f m, confinement 1 m/s: potential released %.3f J, kinetic "
              "max %.3f J, max over the second half %.4f J\n",
    static_cast<unsigned long long>(kSteps), kSpacing, released, maxKinetic, lateKinetic);
  EXPECT_GT(maxKinetic, 0.1 * released); // the flow really moved
  // Bounded and decaying: over the second half of the run the water has settled to a few
  // percent of the peak (measured well under 1 %; 5 % leaves room for a late slosh).
  EXPECT_LT(lateKinetic, 0.05 * maxKinetic);
}
