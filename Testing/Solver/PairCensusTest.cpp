// pbf_pair_census's counts (Solver/Tools/PairCensus.h): exact on a lattice, and no structure
// loses a pair within h.
#include "PairCensus.h"

#include <gtest/gtest.h>

#include <random>

using namespace pbf;

namespace
{

// An n^3 cubic lattice of spacing s with its outer sites s/2 inside the domain.
std::vector<Vec3d> lattice(int n, double s)
{
  std::vector<Vec3d> points;
  for (int z = 0; z < n; ++z)
  {
    for (int y = 0; y < n; ++y)
    {
      for (int x = 0; x < n; ++x)
      {
        points.push_back({ (x + 0.5) * s, (y + 0.5) * s, (z + 0.5) * s });
      }
    }
  }
  return points;
}

} // namespace

TEST(PairCensus, CountsTheLatticesPairsWithinHExactly)
{
  // h = 1.9 s: the offsets with |v|^2 < 3.61 are 0 (1), the axes (6), the face diagonals (12) and
  // the body diagonals (8); on a 10^3 lattice an offset v occurs prod_a (10 - |v_a|) times.
  const int n = 10;
  const double s = 0.1, h = 1.9 * s;
  const Box domain{ { 0, 0, 0 }, { n * s, n * s, n * s } };
  const CellSortedParticles sorted =
    sortByCell(lattice(n, s), makeGridGeometry<double>(domain, h));
  const PairCensus c = countPairs(sorted, h, 0.075 * h, {});
  const double pairs = 1000.0 + 6 * 900 + 12 * 810 + 8 * 729;
  // Counts of whole pairs over 1000 particles: exact in double.
  EXPECT_EQ(c.withinH, pairs / 1000.0);
  EXPECT_EQ(c.particles, 1000u);
}

TEST(PairCensus, EveryStructureHoldsEveryPairWithinH)
{
  // A disordered fluid-like cloud: the lattice jittered by up to 0.3 s.
  const int n = 16;
  const double s = 0.05, h = 2 * s;
  std::vector<Vec3d> points = lattice(n, s);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> jitter(-0.3 * s, 0.3 * s);
  for (Vec3d& p : points)
  {
    p += Vec3d{ jitter(random), jitter(random), jitter(random) };
  }
  const Box domain{ { 0, 0, 0 }, { n * s, n * s, n * s } };
  const CellSortedParticles sorted =
    sortByCell(points, makeGridGeometry<double>(domain, h));
  const PairCensus c = countPairs(sorted, h, 0.075 * h, { { 8, 8 }, { 8, 4 }, { 4, 4 } });
  // Each structure visits a superset of the pairs within h, and a warp at least its lanes' work.
  EXPECT_GE(c.cellWalk, c.maskVisits);
  EXPECT_GE(c.maskVisits, c.withinH);
  EXPECT_GE(c.maskSlots, c.maskVisits);
  EXPECT_GE(c.cellWalkSlots, c.cellWalk);
  EXPECT_LT(c.maskOnceSlots, c.maskSlots);
  ASSERT_EQ(c.clusters.size(), 3u);
  for (const ClusterPairCensus& k : c.clusters)
  {
    // A pair within h has boxes closer than h, so its cluster pair is listed: the listed tiles'
    // hits are every pair within h. Relative 1e-12: a ratio of exact counts, multiplied back.
    EXPECT_NEAR(k.hitFraction * k.slotsPerParticle, c.withinH, 1e-12 * c.withinH)
      << k.shape.i << "x" << k.shape.j;
    EXPECT_LE(k.hitFraction, 1.0);
    if (k.shape.i == k.shape.j)
    {
      EXPECT_LT(k.slotsOncePerParticle, k.slotsPerParticle);
      EXPECT_GE(k.slotsOncePerParticle, 0.5 * k.slotsPerParticle);
    }
  }
}
