// The uniform grid finds exactly the particles within h that brute force finds.
#include "CellSort.h"
#include "Grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

using namespace pbf;

TEST(NeighborSearch, GridEqualsBruteForceIncludingCellBordersAndOutsideTheDomain)
{
  const double h = 0.1;
  const Box domain{ { 0, 0, 0 }, { 1.0, 0.55, 0.7 } }; // 0.55 / h leaves a partial last cell
  const GridGeometry<double> geometry = makeGridGeometry<double>(domain, h);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  std::uniform_int_distribution<int> cell(0, 10);
  std::vector<Vec3d> points;
  for (int k = 0; k < 1500; ++k)
  {
    points.push_back({ u(random), u(random) * 0.55, u(random) * 0.7 });
  }
  for (int k = 0; k < 500; ++k)
  {
    // Exactly on cell faces, edges and corners, where floor() decides the cell.
    points.push_back({ cell(random) * h, std::min(cell(random), 5) * h, std::min(cell(random), 7) * h });
  }
  // Far outside the domain: clamped into border cells, and still found by those near them.
  points.push_back({ -5, 0.2, 0.2 });
  points.push_back({ 1.05, -0.02, 0.71 });

  std::vector<CellKey> keys(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    keys[i] = geometry.keyOf(points[i]);
  }
  std::vector<std::uint32_t> offsets(geometry.cellCount() + 1), order, cursor;
  countingSortByCell(keys, offsets, order, cursor);
  std::vector<Vec3d> sorted(points.size());
  std::vector<CellKey> sortedKeys(points.size());
  for (std::size_t k = 0; k < order.size(); ++k)
  {
    sorted[k] = points[order[k]];
    sortedKeys[k] = keys[order[k]];
  }
  ASSERT_TRUE(std::is_sorted(sortedKeys.begin(), sortedKeys.end()));

  const GridView<double> grid{ geometry, offsets.data(), sortedKeys.data() };
  std::size_t pairs = 0;
  for (std::uint32_t i = 0; i < sorted.size(); ++i)
  {
    std::set<std::uint32_t> found, expected;
    forEachNeighbor(grid, i, [&](std::uint32_t j) {
      const Vec3d r = sorted[i] - sorted[j];
      if (dot(r, r) < h * h)
      {
        EXPECT_TRUE(found.insert(j).second) << "neighbour visited twice";
      }
    });
    for (std::uint32_t j = 0; j < sorted.size(); ++j)
    {
      const Vec3d r = sorted[i] - sorted[j];
      if (dot(r, r) < h * h)
      {
        expected.insert(j);
      }
    }
    ASSERT_EQ(found, expected) << "particle at (" << sorted[i].x << ", " << sorted[i].y << ", "
                               << sorted[i].z << ")";
    pairs += found.size();
  }
  EXPECT_GT(pairs, 10 * sorted.size()); // the test saw real neighbourhoods, not empty ones
}

TEST(NeighborSearch, TooManyCellsIsAnErrorNamingTheCount)
{
  const Box huge{ { 0, 0, 0 }, { 1000, 1000, 1000 } };
  try
  {
    makeGridGeometry<float>(huge, 0.01);
    FAIL() << "expected InvalidInput";
  }
  catch (const InvalidInput& error)
  {
    EXPECT_NE(std::string(error.what()).find("grid cells"), std::string::npos) << error.what();
  }
}
