// Nodes whose surroundings repeat (Scene/RepeatedWindows.h) and the shape maps that share their
// integration (Scene/ShapeMap.h): every group's nodes hold the same window, its first node is the
// first in index order with that window, the grouping does not depend on the threads, and a long
// box's map, integrated once per cross-section of its edges, equals each node's own integration.
#include "RepeatedWindows.h"
#include "ShapeMap.h"
#include "ShapeMapCache.h"
#include "Solids.h"

#include <gtest/gtest.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace pbf;

namespace
{

// A box's field on a small grid, its edges along x longer than any window.
DistanceGrid boxGrid()
{
  DistanceGrid g;
  g.cell = 0.1;
  g.origin = { -0.35, -0.35, -0.35 };
  g.nx = 24;
  g.ny = 9;
  g.nz = 9;
  g.phi.resize(static_cast<std::size_t>(g.nx) * g.ny * g.nz);
  for (int k = 0; k < g.nz; ++k)
  {
    for (int j = 0; j < g.ny; ++j)
    {
      for (int i = 0; i < g.nx; ++i)
      {
        const Vec3d x = g.nodePosition(i, j, k);
        const Vec3d q{ std::abs(x.x - 1.0) - 0.9, std::abs(x.y) - 0.15, std::abs(x.z) - 0.15 };
        const Vec3d out{ std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0) };
        g.node(i, j, k) = static_cast<float>(
          length(out) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0));
      }
    }
  }
  return g;
}

bool sameWindow(const DistanceGrid& g, std::size_t a, std::size_t b, int radius)
{
  const auto at = [&g](std::size_t n, int di, int dj, int dk) {
    const int i = static_cast<int>(n % g.nx) + di, j = static_cast<int>(n / g.nx % g.ny) + dj,
              k = static_cast<int>(n / g.nx / g.ny) + dk;
    const bool inside = i >= 0 && j >= 0 && k >= 0 && i < g.nx && j < g.ny && k < g.nz;
    return inside ? static_cast<double>(g.node(i, j, k)) : 1e30;
  };
  for (int dk = -radius; dk <= radius; ++dk)
  {
    for (int dj = -radius; dj <= radius; ++dj)
    {
      for (int di = -radius; di <= radius; ++di)
      {
        if (at(a, di, dj, dk) != at(b, di, dj, dk))
        {
          return false;
        }
      }
    }
  }
  return true;
}

} // namespace

// Against a brute-force search: each marked node's first equal window, none earlier.
TEST(RepeatedWindows, EachNodeFindsTheFirstNodeWithItsWindow)
{
  const DistanceGrid g = boxGrid();
  std::vector<std::uint8_t> marked(g.phi.size(), 0);
  for (std::size_t n = 0; n < marked.size(); ++n)
  {
    marked[n] = n % 3 != 1; // some nodes left out
  }
  const int radius = 2;
  const std::vector<std::int64_t> first = repeatedWindows(g, marked, radius);
  ASSERT_EQ(first.size(), g.phi.size());
  std::size_t shared = 0;
  for (std::size_t n = 0; n < marked.size(); ++n)
  {
    if (!marked[n])
    {
      EXPECT_EQ(first[n], -1);
      continue;
    }
    std::int64_t expected = -1;
    for (std::size_t m = 0; m <= n && expected < 0; ++m)
    {
      if (marked[m] && sameWindow(g, m, n, radius))
      {
        expected = static_cast<std::int64_t>(m);
      }
    }
    ASSERT_EQ(first[n], expected) << "node " << n;
    shared += first[n] != static_cast<std::int64_t>(n);
  }
  // The edges along x repeat: most of the box's nodes share.
  std::printf("%zu of %zu marked nodes share another's window\n", shared, marked.size());
  EXPECT_GT(shared, marked.size() / 4);
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<std::int64_t> alone = repeatedWindows(g, marked, radius);
  omp_set_num_threads(threads);
  EXPECT_EQ(alone, first);
#endif
}

// A long box at s = 5 cm standing against the tank's -x wall: its map, integrated once per
// repeated window (and node by node where the integration reads across the mirror wall), against
// each node's own integration, over every node within h outside it. Tolerance 1e-6: the same integral at a node
// whole cells away, whose trilinear weights round differently (1e-16 of the coordinates) and
// whose crossings are found to 1e-9 h; stored in float (6e-8 of factors of order 1). (Inside, a
// node on an edge's bisector goes to one face or the other by a rounding of the field's
// gradient, differently at each node when integrated on its own: the shared map takes one
// choice along the whole edge.)
TEST(RepeatedWindows, ALongBoxsMapEqualsEachNodesOwnIntegration)
{
  Parameters p;
  p.particleSpacing = 0.05;
  p.domain = { { 0, 0, 0 }, { 3, 1, 1 } };
  SolidRegion bar;
  bar.kind = SolidRegion::Kind::Box;
  bar.box = { { 0.0, 0.4, 0.4 }, { 2.7, 0.6, 0.65 } };
  DistanceGrid g = solidFields({ bar }, p)[0];
  const ShapeKernels k = shapeKernels(p);
  const ShapeWalls walls = shapeWalls(p, true);
  g.shape.clear();
  const std::size_t integrated = buildShapeMap(g, k, walls);
  double worst = 0;
  std::size_t near = 0, band = 0;
  for (std::size_t n = 0; n < g.phi.size(); ++n)
  {
    const double phi = g.phi[n];
    band += phi >= -2 * g.cell && phi < k.h;
    if (phi < 0 || phi >= k.h)
    {
      continue;
    }
    const Vec3d x = g.nodePosition(static_cast<int>(n % g.nx), static_cast<int>(n / g.nx % g.ny),
      static_cast<int>(n / g.nx / g.ny));
    const std::array<float, kShapeValues> own = shapeFactorsAt(g, x, k, walls);
    for (int v = 0; v < kShapeValues; ++v)
    {
      worst = std::max(worst, std::abs(double(own[v]) - g.shape[n * kShapeValues + v]));
    }
    ++near;
  }
  std::printf("%zu nodes, %zu within h, %zu integrated; %zu checked, largest difference %.2e\n",
    g.phi.size(), band, integrated, near, worst);
  ASSERT_GT(near, 500u);
  EXPECT_LT(worst, 1e-6);
  // The bar's edges are 48 spacings long: all but their last 16 or so nodes at each end share
  // (measured: 10,111 of the 25,054 nodes within h integrated).
  EXPECT_LT(integrated * 2, band);
}

// The cache: the same solid again gets the same map without integrating it; the solid moved by
// a sixth of a spacing, or the same solid under another s_corr exponent, is integrated anew.
TEST(RepeatedWindows, TheCacheGivesASolidItsMapAgain)
{
  Parameters p;
  p.particleSpacing = 0.05;
  p.domain = { { 0, 0, 0 }, { 1, 1, 1 } };
  SolidRegion cube;
  cube.kind = SolidRegion::Kind::Box;
  cube.box = { { 0.3, 0.3, 0.3 }, { 0.6, 0.6, 0.6 } };
  const DistanceGrid first = solidFields({ cube }, p)[0];
  const std::size_t before = shapeMapsBuilt();
  const DistanceGrid again = solidFields({ cube }, p)[0];
  EXPECT_EQ(shapeMapsBuilt(), before) << "the same solid was integrated again";
  EXPECT_EQ(again.shape, first.shape);
  DistanceGrid built = first;
  built.shape.clear();
  buildShapeMap(built, shapeKernels(p), shapeWalls(p, true));
  EXPECT_EQ(built.shape, first.shape);

  Parameters other = p;
  other.sCorrN = 3;
  const DistanceGrid otherKernels = solidFields({ cube }, other)[0];
  EXPECT_EQ(shapeMapsBuilt(), before + 1) << "another s_corr exponent took the cached map";
  EXPECT_NE(otherKernels.shape, first.shape);

  cube.box.min.x += p.particleSpacing / 6;
  cube.box.max.x += p.particleSpacing / 6;
  const DistanceGrid moved = solidFields({ cube }, p)[0];
  EXPECT_EQ(shapeMapsBuilt(), before + 2) << "the moved solid took the cached map";
  DistanceGrid movedBuilt = moved;
  movedBuilt.shape.clear();
  buildShapeMap(movedBuilt, shapeKernels(p), shapeWalls(p, true));
  EXPECT_EQ(moved.shape, movedBuilt.shape);
  EXPECT_NE(moved.shape, first.shape);
}
