// Solids as signed distance fields (Solver/Scene/SignedDistance.h): a triangulated sphere and box
// against their exact fields, the sign independent of orientation, open surfaces refused unless
// given a thickness, and bad input named.
#include "SignedDistance.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

using namespace pbf;
using pbf::test::boxMesh;
using pbf::test::icosphere;

namespace
{

// Largest |field - exact| over points on a lattice through the grid (between its nodes too).
template <class Exact>
double largestError(const DistanceGrid& g, Exact&& exact)
{
  double worst = 0;
  for (double x = g.origin.x; x <= g.origin.x + (g.nx - 1) * g.cell; x += 0.37 * g.cell)
  {
    for (double y = g.origin.y; y <= g.origin.y + (g.ny - 1) * g.cell; y += 0.41 * g.cell)
    {
      for (double z = g.origin.z; z <= g.origin.z + (g.nz - 1) * g.cell; z += 0.43 * g.cell)
      {
        const Vec3d p{ x, y, z };
        worst = std::max(worst, std::abs(g.at(p) - exact(p)));
      }
    }
  }
  return worst;
}

std::string errorOf(const TriangleMesh& mesh, double thickness)
{
  try
  {
    meshDistance(mesh, 0.02, 0.02, thickness, "obstacle \"part.stl\"");
  }
  catch (const InvalidInput& error)
  {
    return error.what();
  }
  return "";
}

} // namespace

TEST(SignedDistance, ATriangulatedSphereMatchesTheExactField)
{
  const Vec3d c{ 0.3, 0.2, 0.1 };
  const double r = 0.1, cell = 0.01;
  const TriangleMesh mesh = icosphere(c, r, 3); // 1,280 triangles, edges of 0.079 rad
  const DistanceGrid g = meshDistance(mesh, cell, 2 * cell, 0.0, "sphere mesh");
  // Facets lie up to r (1 - cos(0.079 / 2)) = 0.08 mm inside the sphere. Trilinear
  // interpolation of |p - c| - r errs by at most cell^2 / (4 rho) at rho = |p - c| (its Hessian
  // is (I - n n^T) / rho): 0.5 mm from r / 2 = 5 cm out. Near the centre, where the field has its
  // kink, the error grows as 1 / rho and nothing reads it (particles are outside the solid), so
  // the comparison covers rho >= r / 2, where the fluid meets the sphere: 1 mm bounds both parts.
  const auto exact = [&](const Vec3d& p) { return length(p - c) - r; };
  const auto awayFromTheCentre = [&](const DistanceGrid& field) {
    return largestError(field, [&](const Vec3d& p) {
      return length(p - c) < 0.5 * r ? field.at(p) : exact(p);
    });
  };
  EXPECT_LT(awayFromTheCentre(g), 1e-3);
  EXPECT_LT(g.at(c), -0.099);
  EXPECT_NEAR(g.at(c + Vec3d{ 0.15, 0, 0 }), 0.05, 1e-3);
  // Away from the grid the field keeps growing: positive far outside.
  EXPECT_NEAR(g.at(c + Vec3d{ 1.0, 0, 0 }), 0.9, 0.01);
  // The gradient is the outward normal near the surface. On a cell face the trilinear gradient
  // is a one-sided difference, whose tangential part is up to cell / (2 rho) = 0.05 here.
  const Vec3d n = g.gradient(c + Vec3d{ 0, 0.105, 0 });
  EXPECT_NEAR(n.y, 1.0, 0.02);
  EXPECT_LT(std::abs(n.x), cell / 0.105);
  EXPECT_LT(std::abs(n.z), cell / 0.105);
  // The exact sphere on the same grid: interpolation error alone.
  const DistanceGrid s = sphereDistance(c, r, cell, 2 * cell);
  ASSERT_EQ(s.phi.size(), g.phi.size());
  EXPECT_LT(awayFromTheCentre(s), 1e-3);
}

TEST(SignedDistance, TheSignDoesNotDependOnTheOrientation)
{
  TriangleMesh mesh = icosphere({ 0, 0, 0 }, 0.1, 2);
  const DistanceGrid outward = meshDistance(mesh, 0.02, 0.02, 0.0, "sphere");
  for (auto& t : mesh.triangles)
  {
    std::swap(t[1], t[2]);
  }
  const DistanceGrid inward = meshDistance(mesh, 0.02, 0.02, 0.0, "sphere");
  EXPECT_EQ(outward.phi, inward.phi); // the same bits: distances are unsigned, |w| decides
}

TEST(SignedDistance, ATriangulatedBoxMatchesTheExactField)
{
  const Box b{ { 0.1, 0.0, 0.2 }, { 0.5, 0.3, 0.4 } };
  const double cell = 0.025;
  const DistanceGrid mesh = meshDistance(boxMesh(b), cell, cell, 0.0, "box mesh");
  const DistanceGrid exact = boxDistance(b, cell, cell);
  ASSERT_EQ(mesh.phi.size(), exact.phi.size());
  // At the nodes the two are the same distance computed two ways: float rounding only.
  double worst = 0;
  for (std::size_t k = 0; k < mesh.phi.size(); ++k)
  {
    worst = std::max(worst, double(std::abs(mesh.phi[k] - exact.phi[k])));
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(exact.at({ 0.3, 0.15, 0.3 }), -0.099); // 0.1 m from the nearest faces (z)
  EXPECT_GT(exact.at({ 0.3, 0.15, 0.45 }), 0.049);
}

TEST(SignedDistance, AnOpenSurfaceIsRefusedUnlessItHasAThickness)
{
  TriangleMesh plate = boxMesh({ { 0, 0, 0 }, { 0.2, 0.2, 0.01 } });
  plate.triangles.pop_back(); // a hole in the +z face
  const std::string error = errorOf(plate, 0.0);
  EXPECT_NE(error.find("obstacle \"part.stl\""), std::string::npos) << error;
  EXPECT_NE(error.find("not closed"), std::string::npos) << error;
  EXPECT_NE(error.find("thickness"), std::string::npos) << error;

  // A single square as a thin shell of 3 cm: inside within 1.5 cm of it, outside beyond.
  TriangleMesh sheet;
  sheet.points = { { 0, 0, 0 }, { 0.2, 0, 0 }, { 0.2, 0.2, 0 }, { 0, 0.2, 0 } };
  sheet.triangles = { { 0, 1, 2 }, { 0, 2, 3 } };
  const DistanceGrid g = meshDistance(sheet, 0.005, 0.01, 0.03, "sheet");
  EXPECT_NEAR(g.at({ 0.1, 0.1, 0.0 }), -0.015, 1e-6);
  EXPECT_NEAR(g.at({ 0.1, 0.1, 0.01 }), -0.005, 1e-6);
  EXPECT_NEAR(g.at({ 0.1, 0.1, -0.025 }), 0.01, 1e-6);
}

TEST(SignedDistance, BadInputIsNamed)
{
  const TriangleMesh sphere = icosphere({ 0, 0, 0 }, 0.1, 1);
  EXPECT_NE(errorOf(TriangleMesh{}, 0.0).find("no triangles"), std::string::npos);
  TriangleMesh nan = sphere;
  nan.points[3].y = std::nan("");
  EXPECT_NE(errorOf(nan, 0.0).find("point 3 = (0"), std::string::npos) << errorOf(nan, 0.0);
  TriangleMesh out = sphere;
  out.triangles[5][1] = 999;
  EXPECT_NE(errorOf(out, 0.0).find("triangle 5 names point 999"), std::string::npos);
  EXPECT_THROW(meshDistance(sphere, 0.0, 0.0, 0.0, "s"), InvalidInput);
  EXPECT_THROW(meshDistance(sphere, 1e-6, 0.0, 0.0, "s"), InvalidInput); // 2e5^3 nodes
  EXPECT_THROW(sphereDistance({ 0, 0, 0 }, -1.0, 0.01, 0.0), InvalidInput);
  EXPECT_THROW(boxDistance({ { 0, 0, 0 }, { 0, 1, 1 } }, 0.01, 0.0), InvalidInput);
}

TEST(SignedDistance, TheBandIsExactAndTheEstimateBeyondItKeepsTheSign)
{
  const Vec3d c{ 0.0, 0.0, 0.0 };
  const double r = 0.2, cell = 0.01, band = 0.03;
  const TriangleMesh mesh = icosphere(c, r, 3);
  const DistanceGrid exact = meshDistance(mesh, cell, 0.1, 0.0, "sphere");
  const DistanceGrid banded = meshDistance(mesh, cell, 0.1, 0.0, "sphere", band);
  ASSERT_EQ(exact.phi.size(), banded.phi.size());
  std::size_t inBand = 0, beyond = 0;
  double worstRatio = 0;
  for (std::size_t n = 0; n < exact.phi.size(); ++n)
  {
    const double e = exact.phi[n], b = banded.phi[n];
    ASSERT_EQ(e < 0, b < 0) << "node " << n << ": " << e << " against " << b;
    if (std::abs(e) <= band)
    {
      // The nearest triangle is among those that visit the node: the same minimum, bit for bit.
      ASSERT_EQ(e, b) << "node " << n;
      ++inBand;
    }
    else
    {
      // Beyond the band the chamfer distance is an upper bound, at least the band, and within
      // its known error (Borgefors' <1, sqrt 2, sqrt 3> transform: under 13 % of the distance
      // travelled beyond the band; 15 % here with the facets' own distance).
      EXPECT_GE(std::abs(b), band * (1 - 1e-6));
      EXPECT_GE(std::abs(b), std::abs(e) * (1 - 1e-6));
      worstRatio = std::max(worstRatio, std::abs(b) / std::abs(e));
      ++beyond;
    }
  }
  EXPECT_GT(inBand, 10000u);
  EXPECT_GT(beyond, 10000u);
  EXPECT_LT(worstRatio, 1.15);
}

TEST(SignedDistance, RaysThroughEdgesAndCornersCountOneCrossing)
{
  // Two unit cubes in one mesh with every corner on a node: the rows of nodes run exactly along
  // edges and through corners of the triangles, which the sign must count once.
  TriangleMesh twoBoxes = boxMesh({ { 0, 0, 0 }, { 1, 1, 1 } });
  const TriangleMesh second = boxMesh({ { 2, 0, 0 }, { 3, 1, 1 } });
  for (const auto& t : second.triangles)
  {
    twoBoxes.triangles.push_back({ t[0] + 8, t[1] + 8, t[2] + 8 });
  }
  twoBoxes.points.insert(twoBoxes.points.end(), second.points.begin(), second.points.end());
  const DistanceGrid g = meshDistance(twoBoxes, 0.25, 0.5, 0.0, "two boxes", 0.5);
  const DistanceGrid a = boxDistance({ { 0, 0, 0 }, { 1, 1, 1 } }, 0.25, 0.5);
  int checked = 0;
  for (int k = 0; k < g.nz; ++k)
  {
    for (int j = 0; j < g.ny; ++j)
    {
      for (int i = 0; i < g.nx; ++i)
      {
        const Vec3d p = g.nodePosition(i, j, k);
        const auto strictly = [&](double lo, double hi, double v) { return v > lo && v < hi; };
        const bool inside = strictly(0, 1, p.y) && strictly(0, 1, p.z) &&
          (strictly(0, 1, p.x) || strictly(2, 3, p.x));
        const bool onSurface = std::abs(g.node(i, j, k)) < 1e-9;
        if (!onSurface)
        {
          EXPECT_EQ(g.node(i, j, k) < 0, inside) << "node " << p.x << ", " << p.y << ", " << p.z;
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 500);
  // Beside the first box, the two fields agree (the second box is farther than the first).
  EXPECT_NEAR(g.at({ 0.5, 0.5, 0.5 }), a.at({ 0.5, 0.5, 0.5 }), 1e-6);
  EXPECT_NEAR(g.at({ -0.25, 0.5, 0.5 }), 0.25, 1e-6);
}

TEST(SignedDistance, AMeshFieldCanCoverOnlyTheRegionTheFluidReaches)
{
  // A sphere of 0.5 m whose centre is outside the region: the clipped grid is the part inside
  // it (plus the margin), with the values of the whole grid at the same points, the sign counted
  // over every triangle (the rays start outside the clipped grid).
  const TriangleMesh mesh = icosphere({ 0.0, 0.0, 0.0 }, 0.5, 3);
  const double cell = 0.02, band = 0.06;
  const Box region{ { 0.2, -0.2, -0.2 }, { 1.0, 0.2, 0.2 } };
  const DistanceGrid whole = meshDistance(mesh, cell, 0.04, 0.0, "big sphere", band);
  const DistanceGrid part = meshDistance(mesh, cell, 0.04, 0.0, "big sphere", band, &region);
  EXPECT_LT(part.phi.size() * 4, whole.phi.size()); // a quarter of the nodes or fewer
  EXPECT_NEAR(part.origin.x, 0.2 - 0.04, 1e-12);
  double worst = 0;
  int inside = 0, checked = 0;
  for (double x = 0.2; x <= 0.5; x += 0.013)
  {
    for (double y = -0.2; y <= 0.2; y += 0.017)
    {
      for (double z = -0.2; z <= 0.2; z += 0.019)
      {
        const Vec3d p{ x, y, z };
        const double a = whole.at(p), b = part.at(p);
        ASSERT_EQ(a < 0, b < 0) << x << ", " << y << ", " << z;
        if (std::abs(a) < band - 2 * cell)
        {
          worst = std::max(worst, std::abs(a - b));
          ++checked;
        }
        inside += b < 0 ? 1 : 0;
      }
    }
  }
  // Within the band both hold exact distances at their nodes, which lie elsewhere: the two
  // trilinear interpolations of |p| - r differ by at most twice cell^2 / (4 r) = 4e-4 m.
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(checked, 100);
  EXPECT_GT(inside, 100);
  const Box away{ { 2.0, 2.0, 2.0 }, { 3.0, 3.0, 3.0 } };
  EXPECT_THROW(meshDistance(mesh, cell, 0.04, 0.0, "big sphere", band, &away), InvalidInput);
}

TEST(SignedDistance, SolidsTouchingAlongAnEdgeAreClosed)
{
  // Two unit cubes that share the edge x = 1, y = 1 (its two points merged): four triangles meet
  // there, as on the outer surface of a tetrahedral mesh (Delaunay3D). Closed all the same.
  TriangleMesh m = boxMesh({ { 0, 0, 0 }, { 1, 1, 1 } });
  const TriangleMesh other = boxMesh({ { 1, 1, 0 }, { 2, 2, 1 } });
  std::vector<std::uint32_t> index(8);
  for (std::uint32_t k = 0; k < 8; ++k)
  {
    // other's corners (1, 1, 0) and (1, 1, 1) are m's corners 3 and 7.
    const Vec3d& p = other.points[k];
    if (p.x == 1 && p.y == 1)
    {
      index[k] = p.z == 0 ? 3u : 7u;
      continue;
    }
    index[k] = static_cast<std::uint32_t>(m.points.size());
    m.points.push_back(p);
  }
  for (const auto& t : other.triangles)
  {
    m.triangles.push_back({ index[t[0]], index[t[1]], index[t[2]] });
  }
  const DistanceGrid g = meshDistance(m, 0.1, 0.2, 0.0, "two cubes on an edge", 0.3);
  EXPECT_LT(g.at({ 0.5, 0.5, 0.5 }), -0.45);
  EXPECT_LT(g.at({ 1.5, 1.5, 0.5 }), -0.45);
  EXPECT_NEAR(g.at({ 1.5, 0.5, 0.5 }), 0.5, 1e-6); // the empty quarters: outside
  EXPECT_NEAR(g.at({ 0.5, 1.5, 0.5 }), 0.5, 1e-6);
  // An odd count is still refused: one triangle fewer leaves an edge with one.
  m.triangles.pop_back();
  EXPECT_THROW(meshDistance(m, 0.1, 0.2, 0.0, "two cubes on an edge", 0.3), InvalidInput);
}
