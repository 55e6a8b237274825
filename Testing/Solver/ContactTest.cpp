// Where the collision reads a solid (DistanceGridView::contact): the grids' node normals are the
// exact field's gradient, and a particle just inside a convex edge or corner, which the trilinear
// field reads as outside, is put on the nearest face, standing or turned.
#include "SignedDistance.h"
#include "SolidMotion.h"
#include "SolidTerms.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace pbf;
using pbf::test::boxMesh;

namespace
{

constexpr double kCell = 0.02;
// The grid holds phi and the normals as floats: a node value of up to two cells (0.04 m) is
// rounded by up to 2.4e-9 m, and the plane through it with it.
constexpr double kStored = 5e-9;
// Every face half a cell between two node planes (the grid starts 1.5 cells below the box and
// the box spans whole cells), where the trilinear field rounds an edge the most.
const Box kBox{ { 0.1, 0.0, 0.2 }, { 0.5, 0.3, 0.4 } };

// The exact signed distance to kBox and the axis (0, 1, 2) of its nearest face from inside, -1
// where two faces are nearly as near (the normal there is either).
double boxDistanceAt(const Vec3d& p, int* face = nullptr)
{
  const Vec3d c = (kBox.min + kBox.max) * 0.5, half = (kBox.max - kBox.min) * 0.5;
  const double q[3] = { std::abs(p.x - c.x) - half.x, std::abs(p.y - c.y) - half.y,
    std::abs(p.z - c.z) - half.z };
  const Vec3d out{ std::max(q[0], 0.0), std::max(q[1], 0.0), std::max(q[2], 0.0) };
  const int a = int(std::max_element(q, q + 3) - q);
  if (face)
  {
    const double second = std::max(q[(a + 1) % 3], q[(a + 2) % 3]);
    *face = q[a] - second > 1e-9 ? a : -1;
  }
  return length(out) + std::min(q[a], 0.0);
}

// Points inside kBox within `depth` of its surface, on a lattice that is no multiple of the cell.
std::vector<Vec3d> shellPoints(double depth)
{
  std::vector<Vec3d> points;
  const double step = 0.13 * kCell;
  for (double x = kBox.min.x + 0.5 * step; x < kBox.max.x; x += step)
  {
    for (double y = kBox.min.y + 0.5 * step; y < kBox.max.y; y += step)
    {
      for (double z = kBox.min.z + 0.5 * step; z < kBox.max.z; z += step)
      {
        const double d = boxDistanceAt({ x, y, z });
        if (d < 0 && d > -depth)
        {
          points.push_back({ x, y, z });
        }
      }
    }
  }
  return points;
}

// collideWithObstacles against the one solid `view`.
Vec3d collide(const Vec3d& q, const DistanceGridView<double>& view)
{
  FluidView<double> f{};
  f.obstacles = &view;
  f.obstacleCount = 1;
  return collideWithObstacles(q, f);
}

} // namespace

TEST(Contact, ANodesNormalIsTheExactFieldsGradient)
{
  // The box's analytic normals and the triangulated box's (from each node's nearest point) are
  // the same unit vectors, to float rounding (1e-6), wherever the nearest face is one face.
  const DistanceGrid exact = boxDistance(kBox, kCell, 1.5 * kCell);
  const DistanceGrid mesh = meshDistance(boxMesh(kBox), kCell, 1.5 * kCell, 0.0, "box mesh");
  ASSERT_EQ(exact.normal.size(), 3 * exact.phi.size());
  ASSERT_EQ(mesh.normal.size(), 3 * mesh.phi.size());
  std::size_t compared = 0;
  for (int k = 0; k < exact.nz; ++k)
  {
    for (int j = 0; j < exact.ny; ++j)
    {
      for (int i = 0; i < exact.nx; ++i)
      {
        const std::size_t n = exact.index(i, j, k);
        const Vec3d e{ exact.normal[3 * n], exact.normal[3 * n + 1], exact.normal[3 * n + 2] };
        const Vec3d m{ mesh.normal[3 * n], mesh.normal[3 * n + 1], mesh.normal[3 * n + 2] };
        EXPECT_NEAR(length(e), 1.0, 1e-6) << "node " << i << " " << j << " " << k;
        EXPECT_NEAR(length(m), 1.0, 1e-6) << "node " << i << " " << j << " " << k;
        int face = 0;
        boxDistanceAt(exact.nodePosition(i, j, k), &face);
        if (face >= 0)
        {
          EXPECT_LT(length(e - m), 1e-6) << "node " << i << " " << j << " " << k;
          ++compared;
        }
      }
    }
  }
  EXPECT_GT(compared, exact.phi.size() / 2);
}

TEST(Contact, AParticleJustInsideAConvexEdgeGoesToTheNearestFace)
{
  // Points up to 0.45 of a cell inside the box, on two grids: the faces mid-cell, where the
  // trilinear field reads some of them as outside near the edges and corners (the failure the
  // normals remove, counted so that the test shows it) and the collision without normals leaves
  // those inside; and the faces on node planes, as solidFields lays a box mesh out (h is 4 cells),
  // where the nodes on the faces take their normals from phi's differences (their nearest points
  // are off by rounding, in any direction). With the normals every point moves to its nearest
  // face: the exact distance afterwards is 0 and the move is the depth, both to kStored.
  for (double margin : { 1.5 * kCell, 2.0 * kCell })
  {
    const DistanceGrid grid = meshDistance(boxMesh(kBox), kCell, margin, 0.0, "box mesh");
    const DistanceGridView<double> withNormals =
      grid.view<double>(grid.phi.data(), nullptr, grid.normalNodes());
    const DistanceGridView<double> withoutNormals = grid.view<double>(grid.phi.data(), nullptr);
    const std::vector<Vec3d> points = shellPoints(0.45 * kCell);
    ASSERT_GT(points.size(), 10000u);
    std::size_t readOutside = 0, leftInside = 0;
    double deepest = 0, worstMove = 0;
    for (const Vec3d& p : points)
    {
      const double depth = -boxDistanceAt(p);
      readOutside += grid.at(p) >= 0 ? 1 : 0;
      leftInside += boxDistanceAt(collide(p, withoutNormals)) < -1e-6 ? 1 : 0;
      const Vec3d q = collide(p, withNormals);
      deepest = std::min(deepest, boxDistanceAt(q));
      worstMove = std::max(worstMove, std::abs(length(q - p) - depth));
    }
    std::printf("margin %.1f cells: %zu points within 0.45 cells inside: %zu read outside by the "
                "trilinear field, %zu left inside without normals; with them the deepest %.3g m, "
                "the move off by %.3g m\n",
      margin / kCell, points.size(), readOutside, leftInside, deepest, worstMove);
    if (margin == 1.5 * kCell)
    {
      EXPECT_GT(readOutside, 100u);
      EXPECT_GT(leftInside, 100u);
    }
    EXPECT_GT(deepest, -kStored) << "margin " << margin;
    EXPECT_LT(worstMove, kStored) << "margin " << margin;
  }
}

TEST(Contact, ATurnedSolidsEdgeHoldsAsAStandingOnes)
{
  // The same box turned 30 degrees about z and moved: the planes are read in the grid's frame, so
  // every point goes to the same face as on the standing box (kStored, as above).
  const DistanceGrid grid = meshDistance(boxMesh(kBox), kCell, 1.5 * kCell, 0.0, "box mesh");
  SolidPose pose;
  pose.moving = true;
  const double angle = 30.0 * (3.14159265358979323846 / 180.0);
  const double c = std::cos(angle), s = std::sin(angle);
  pose.rotation = { c, -s, 0, s, c, 0, 0, 0, 1 };
  pose.translation = { 0.3, -0.1, 0.05 };
  const DistanceGridView<double> turned =
    placed(grid.view<double>(grid.phi.data(), nullptr, grid.normalNodes()), pose);
  double deepest = 0, worstMove = 0;
  for (const Vec3d& p : shellPoints(0.45 * kCell))
  {
    const Vec3d q = pose.toLocal(collide(pose.toWorld(p), turned));
    deepest = std::min(deepest, boxDistanceAt(q));
    worstMove = std::max(worstMove, std::abs(length(q - p) + boxDistanceAt(p)));
  }
  EXPECT_GT(deepest, -kStored);
  EXPECT_LT(worstMove, kStored);
}

TEST(Contact, AConcaveEdgeKeepsTheTrilinearReading)
{
  // The box as a shell 4 cells thick: inside its cavity every edge and corner is concave, where
  // the nodes' planes lie above the field and the trilinear field is the lower reading, so the
  // collision is the one without normals, to the bit, for points of the cavity within half a cell
  // of the shell and points of the shell within 0.45 cells of the cavity. (The trilinear field
  // reads low there: it pushes some cavity points a little off a concave edge, never into it.)
  const double half = 2 * kCell;
  const DistanceGrid grid = meshDistance(boxMesh(kBox), kCell, 1.5 * kCell, 2 * half, "shell");
  const DistanceGridView<double> withNormals =
    grid.view<double>(grid.phi.data(), nullptr, grid.normalNodes());
  const DistanceGridView<double> withoutNormals = grid.view<double>(grid.phi.data(), nullptr);
  auto shellDistance = [&](const Vec3d& p) { return std::abs(boxDistanceAt(p)) - half; };
  std::size_t near = 0, differ = 0;
  const double step = 0.13 * kCell;
  for (double x = kBox.min.x + 0.5 * step; x < kBox.max.x; x += step)
  {
    for (double y = kBox.min.y + 0.5 * step; y < kBox.max.y; y += step)
    {
      for (double z = kBox.min.z + 0.5 * step; z < kBox.max.z; z += step)
      {
        const Vec3d p{ x, y, z };
        const double d = shellDistance(p);
        if (boxDistanceAt(p) < 0 && d > -0.45 * kCell && d < 0.5 * kCell)
        {
          ++near;
          const Vec3d a = collide(p, withNormals), b = collide(p, withoutNormals);
          differ += (a.x == b.x && a.y == b.y && a.z == b.z) ? 0 : 1;
        }
      }
    }
  }
  std::printf("%zu points near the cavity's walls, %zu moved otherwise with normals\n", near, differ);
  EXPECT_GT(near, 10000u);
  EXPECT_EQ(differ, 0u);
}
