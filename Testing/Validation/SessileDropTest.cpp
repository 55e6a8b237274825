// A drop resting on the floor without gravity (Solver/Tools/SessileDrop.h), the fast version of
// the validation page's "Adhesion": a hemisphere of liquid under surface tension on walls of
// several contact angles, the angle its surface settles at read from the cap's volume and
// centroid.
#include "SessileDrop.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

using namespace pbf;
using namespace pbf::validation;

// sigma = 1 N/m, R = 0.05 m at 10 spacings per radius, 3 s (about 4 capillary periods), the
// angle averaged over the last second. Measured (double): 90 -> 90.1, 105 -> 106.0, 120 -> 119.9
// degrees; 80 -> 73.4 (the wetting side settles below the angle set, ValidationInterfaces.md).
// The bounds: the angle moves monotonically with the one set, within 5 degrees of it where the
// surface beads up (theta >= 90), and on the wetting side below 90 and above 60.
TEST(SessileDrop, TheContactAngleFollowsTheAdhesion)
{
  Parameters p;
  p.particleSpacing = 0.005;
  p.surfaceTension = 1.0;
  // 105 (106.0) is in ValidationInterfaces.md's table; CI runs the ends and the neutral angle.
  const std::vector<double> set = { 80, 90, 120 };
  std::vector<double> measured;
  for (double theta : set)
  {
    p.contactAngle = theta;
    const SessileRun run =
      runSessileDrop(p, Backend::OpenMP, Precision::Double, 0.05, 3.0, 1.0, 0.05);
    std::printf("contact angle %.0f: %.1f degrees (spread %.1f, top at %.4f m, %.0f steps)\n",
      theta, run.angle, run.spread, run.height, run.steps);
    // The drop stays on the floor: its top below the domain's ceiling (2 R).
    EXPECT_LT(run.height, 0.09) << theta;
    measured.push_back(run.angle);
  }
  for (std::size_t k = 1; k < set.size(); ++k)
  {
    EXPECT_GT(measured[k], measured[k - 1]) << set[k];
  }
  for (std::size_t k = 1; k < set.size(); ++k)
  {
    EXPECT_NEAR(measured[k], set[k], 5.0) << set[k];
  }
  EXPECT_LT(measured[0], 90.0);
  EXPECT_GT(measured[0], 60.0);
}

// The same drop on a solid slab (an obstacle's distance field) instead of the domain's floor, its
// contact angle the obstacle's: the solid's mirror images continue the surface as the walls' do,
// and its Young's force acts at the line. Measured (double, 3 s): 80 -> 74.4, 120 -> 118.2
// degrees (4 s: 74.2, 118.6, and 90 -> 90.3), as on the wall (73.7, 120.7). Bounds as above; a
// solid whose angle were ignored would hold the drop at 90.3, which fails both.
TEST(SessileDrop, TheContactAngleOnASolidFollowsItsAdhesion)
{
  Parameters p;
  p.particleSpacing = 0.005;
  p.surfaceTension = 1.0;
  std::vector<double> measured;
  for (double theta : { 80.0, 120.0 })
  {
    p.contactAngle = theta;
    const SessileRun run =
      runSessileDrop(p, Backend::OpenMP, Precision::Double, 0.05, 3.0, 1.0, 0.05, true);
    std::printf("on the slab, contact angle %.0f: %.1f degrees (spread %.1f, top at %.4f m)\n",
      theta, run.angle, run.spread, run.height);
    EXPECT_LT(run.height, 0.09) << theta;
    measured.push_back(run.angle);
  }
  EXPECT_LT(measured[0], 90.0);
  EXPECT_GT(measured[0], 60.0);
  EXPECT_NEAR(measured[1], 120.0, 5.0);
}
