// A drop without gravity (Solver/Tools/Droplet.h), the fast version of the validation page's
// "Surface tension": a block 1.3 times as long as it is wide pulls itself round and oscillates in
// Rayleigh's l = 2 mode, at 10 spacings per radius (the page has 15 too).
#include "Droplet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace pbf;
using namespace pbf::validation;

// sigma = 1 N/m, R = 0.1 m, rho = 1000: Rayleigh's period 2.221 s. Measured (double, OpenMP):
// 2.733 s at the automatic step (at most 1/240 s) and 2.702 s at steps of at most 2 ms, +23 % and
// +22 % (+19 % at 15 spacings per radius: the period converges from above). The bound is the
// measurement's margin, not the 15 %, which this model does not meet yet
// (Documentation/Validation.md); the two steps agree within 5 %, as the issue asks.
TEST(Droplet, ADropOscillatesNearRayleighsPeriodAtAnyStep)
{
  Parameters p;
  p.particleSpacing = 0.01;
  p.surfaceTension = 1.0;
  const double radius = 0.1, aspect = 1.3, until = 5.0;
  const double theory = rayleighPeriod(radius, p.restDensity, p.surfaceTension);
  const DropletRun coarse =
    runDroplet(p, Backend::OpenMP, Precision::Double, radius, aspect, until, theory / 40);
  p.timeStep = 0.002;
  const DropletRun fine =
    runDroplet(p, Backend::OpenMP, Precision::Double, radius, aspect, until, theory / 40);
  std::printf("periods %.4f s (%d crossings, %.0f steps) and %.4f s (%d, %.0f steps) against "
              "Rayleigh's %.4f s: %+.1f %% and %+.1f %%\n",
    coarse.period, coarse.crossings, coarse.steps, fine.period, fine.crossings, fine.steps, theory,
    100 * (coarse.period / theory - 1), 100 * (fine.period / theory - 1));
  ASSERT_GE(coarse.crossings, 3) << "the drop did not oscillate";
  ASSERT_GE(fine.crossings, 3) << "the drop did not oscillate";
  EXPECT_GT(fine.steps, 1.9 * coarse.steps) << "the smaller step was not taken";
  EXPECT_NEAR(coarse.period, theory, 0.3 * theory);
  EXPECT_NEAR(fine.period, coarse.period, 0.05 * coarse.period);
}
