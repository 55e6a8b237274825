// The solids' shape maps (Scene/ShapeMap.h) as the stages read them: 1 and the normal on a flat
// face, a cube's mesh the same as the box, the map between its nodes against direct integration,
// and the density a lattice at rest reads around a box's face, edge and corner and cut by a
// sphere, against the tangent plane alone.
#include "CpuStepper.h"
#include "ShapeMap.h"
#include "Solids.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

using namespace pbf;

namespace
{

constexpr double kSpacing = 0.05;
constexpr int kSide = 24; // the tank, in spacings

Parameters tankParameters()
{
  Parameters p;
  p.particleSpacing = kSpacing;
  p.domain = { { 0, 0, 0 }, { kSide * kSpacing, kSide * kSpacing, kSide * kSpacing } };
  return p;
}

// The largest |value| of a column of the table.
double largest(const std::vector<double>& column)
{
  double m = 0;
  for (double v : column)
  {
    m = std::max(m, std::abs(v));
  }
  return m;
}

// The map at x, trilinear between the nodes, as the stages read them.
std::array<double, kShapeValues> mapAt(const DistanceGrid& g, const Vec3d& x)
{
  const DistanceGridView<double> view = g.view<double>(g.phi.data(), g.shapeNodes());
  std::array<double, kShapeValues> values{};
  view.shapeAt(x, values.data());
  return values;
}

// The tank full of lattice at rest around one solid: each particle within h of the solid and
// farther than h from the tank's walls (where its mirrors add images of their own), by how many
// of its coordinates lie beyond the solid's bounds (1 a face, 2 an edge, 3 a corner); the worst
// |rho / rho_0 - 1| of each class.
struct RestDensity
{
  double worst[4] = { 0, 0, 0, 0 };
  int count[4] = { 0, 0, 0, 0 };
};

// A solid's field as a run makes it (solidFields), with its shape map (and without it when the
// run asks for tangent planes).
DistanceGrid mapped(const SolidRegion& solid, const Parameters& p)
{
  Parameters tangent = p;
  tangent.exactBoundaries = false;
  EXPECT_TRUE(solidFields({ solid }, tangent)[0].shape.empty());
  DistanceGrid g = solidFields({ solid }, p)[0];
  EXPECT_EQ(g.shape.size(), g.phi.size() * kShapeValues);
  return g;
}

// The density the stages read at rest, with the shape map (exact) or without it (the tangent
// plane).
RestDensity restDensityAround(const SolidRegion& solid, bool exact)
{
  const Parameters p = tankParameters();
  Scene scene;
  scene.domain = p.domain;
  scene.boxes.push_back({ p.domain.min, p.domain.max, { 0, 0, 0 } });
  DistanceGrid field = mapped(solid, p);
  if (!exact)
  {
    field.shape.clear();
  }
  std::size_t removed = 0;
  const ParticleBatch fluid = outsideSolids(fillScene(scene, p), { field }, {}, removed);
  CpuStepper<double> stepper(false, p, fluid);
  stepper.setObstacles({ field });
  Snapshot<double> state;
  stepper.read(state);
  const double h = p.smoothingLength();
  const Box bounds = solidBounds(solid, "solid");
  RestDensity r;
  for (std::size_t i = 0; i < state.id.size(); ++i)
  {
    const Vec3d x = state.position[i];
    const double wall = std::min({ x.x, x.y, x.z, p.domain.max.x - x.x, p.domain.max.y - x.y,
      p.domain.max.z - x.z });
    if (wall < h || field.at(x) >= h)
    {
      continue;
    }
    const int beyond = (x.x < bounds.min.x || x.x > bounds.max.x) +
      (x.y < bounds.min.y || x.y > bounds.max.y) + (x.z < bounds.min.z || x.z > bounds.max.z);
    r.worst[beyond] =
      std::max(r.worst[beyond], std::abs(state.density[i] / p.restDensity - 1));
    ++r.count[beyond];
  }
  return r;
}

// A cube of 8 x 8 x 8 spacings in the middle of the tank, its faces halfway between lattice
// layers.
SolidRegion cube()
{
  SolidRegion s;
  s.kind = SolidRegion::Kind::Box;
  s.box = { { 8 * kSpacing, 8 * kSpacing, 8 * kSpacing }, { 16 * kSpacing, 16 * kSpacing,
    16 * kSpacing } };
  return s;
}

} // namespace

TEST(ShapeMap, AFlatFaceReadsOneAndItsNormal)
{
  const Parameters p = tankParameters();
  const DistanceGrid g = mapped(cube(), p);
  ASSERT_EQ(g.shape.size(), g.phi.size() * kShapeValues);
  DistanceGrid again = g;
  const auto start = std::chrono::steady_clock::now();
  const std::size_t integrated = buildShapeMap(again, shapeKernels(p));
  const double seconds =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("the cube's map: %zu nodes, %zu integrated, %.2f s\n", g.phi.size(), integrated,
    seconds);
#ifdef _OPENMP
  // The same map whatever the threads: one thread against the default team.
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  buildShapeMap(again, shapeKernels(p));
  omp_set_num_threads(threads);
#endif
  EXPECT_EQ(again.shape, g.shape);
  const double h = p.smoothingLength();
  // Points within h of the top face, farther than h from its edges: the half-space itself.
  double worst = 0;
  int points = 0;
  for (double d = 0.0; d < h; d += 0.13 * kSpacing)
  {
    for (double u = 8 * kSpacing + h; u <= 16 * kSpacing - h; u += 0.37 * kSpacing)
    {
      const std::array<double, kShapeValues> v = mapAt(g, { u, 16 * kSpacing + d, 0.61 });
      const double expected[kShapeValues] = { 1, 0, 1, 0, 1, 0, 1, 0 };
      for (int k = 0; k < kShapeValues; ++k)
      {
        worst = std::max(worst, std::abs(v[k] - expected[k]));
      }
      ++points;
    }
  }
  ASSERT_GT(points, 50);
  // Both integrals by the same rule over the same half-space (ShapeIntegralsTest: 1e-9); what
  // remains is the factors' storage in float (6e-8 each, a few of them summed by the trilinear
  // weights).
  std::printf("on the face: largest difference from 1 and the normal %.2e\n", worst);
  EXPECT_LT(worst, 1e-6);
}

TEST(ShapeMap, BetweenItsNodesTheMapFollowsTheIntegrals)
{
  const Parameters p = tankParameters();
  const ShapeKernels k = shapeKernels(p);
  const BoundaryTableData tableData = makeBoundaryTable(p);
  const std::vector<double> packed = tableData.packed<double>();
  const BoundaryTable<double> table = tableData.view(packed.data());
  SolidRegion ball;
  ball.kind = SolidRegion::Kind::Sphere;
  ball.center = { 0.6, 0.6, 0.6 };
  ball.radius = 0.2;
  for (const SolidRegion& solid : { cube(), ball })
  {
    const DistanceGrid g = mapped(solid, p);
    double worst = 0;
    int points = 0;
    // A line across the corner (or the ball's side), off the nodes.
    for (double t = -0.3; t < 0.3; t += 0.0173)
    {
      const Vec3d x = solid.kind == SolidRegion::Kind::Box
        ? Vec3d{ 0.8 + 0.07, 0.8 + 0.03 + t * 0.1, 0.8 + t }
        : Vec3d{ 0.6 + t, 0.6 + 0.21, 0.6 + 0.013 };
      const double d = g.at(x);
      if (d < 0 || d >= p.smoothingLength())
      {
        continue;
      }
      const std::array<double, kShapeValues> v = mapAt(g, x);
      const std::array<float, kShapeValues> direct = shapeFactorsAt(g, x, k);
      // What the stages read is the table times the factors: each difference weighed by the
      // table at x's distance over the table's largest value.
      // (The spiky column is negative: magnitudes.)
      const BoundarySample<double> b = sampleBoundary(table, d);
      const double spiky = std::abs(b.spiky) / largest(tableData.spiky),
                   tensile = std::abs(b.tensile) / largest(tableData.tensile);
      const double weight[kShapeValues] = { std::abs(b.poly6) / largest(tableData.poly6), spiky,
        spiky, spiky, std::abs(b.spiky2) / largest(tableData.spiky2), tensile, tensile,
        tensile };
      for (int c = 0; c < kShapeValues; ++c)
      {
        worst = std::max(worst, std::abs(v[c] - direct[c]) * weight[c]);
      }
      ++points;
    }
    ASSERT_GT(points, 10);
    std::printf("largest difference from direct integration: %.4f of the table's largest value "
                "over %d points\n",
      worst, points);
    // Trilinear between nodes s / 2 apart, of factors that change by up to 1 over h = 2 s
    // (measured 0.01-0.04 of the factor itself close to the ball).
    EXPECT_LT(worst, 0.05);
  }
}

TEST(ShapeMap, ACubesMeshHasTheBoxsMap)
{
  const Parameters p = tankParameters();
  SolidRegion mesh;
  mesh.kind = SolidRegion::Kind::Mesh;
  const Box b = cube().box;
  for (int c = 0; c < 8; ++c)
  {
    mesh.mesh.points.push_back({ c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y,
      c & 4 ? b.max.z : b.min.z });
  }
  mesh.mesh.triangles = { { 0, 2, 1 }, { 1, 2, 3 }, { 4, 5, 6 }, { 5, 7, 6 }, { 0, 1, 4 },
    { 1, 5, 4 }, { 2, 6, 3 }, { 3, 6, 7 }, { 0, 4, 2 }, { 2, 4, 6 }, { 1, 3, 5 }, { 3, 7, 5 } };
  const DistanceGrid fromMesh = mapped(mesh, p);
  const DistanceGrid fromBox = mapped(cube(), p);
  const double h = p.smoothingLength();
  double worst = 0;
  int points = 0;
  for (double t = 0; t < 1.2; t += 0.0231)
  {
    const Vec3d x{ 0.8 + 0.3 * h * std::sin(7 * t), 0.4 + t * 0.35,
      0.8 + 0.5 * h * std::cos(5 * t) };
    if (fromBox.at(x) >= h)
    {
      continue;
    }
    ++points;
    const std::array<double, kShapeValues> a = mapAt(fromMesh, x), e = mapAt(fromBox, x);
    for (int c = 0; c < kShapeValues; ++c)
    {
      worst = std::max(worst, std::abs(a[c] - e[c]));
    }
  }
  // The two fields agree to rounding within h + 2 nodes of the surface (SignedDistanceTest), so
  // their maps agree to the crossings' tolerance, on factors of order 1.
  ASSERT_GT(points, 10);
  std::printf("mesh against box: largest difference %.2e over %d points\n", worst, points);
  EXPECT_LT(worst, 1e-5);
}

TEST(ShapeMap, TheLatticeAtRestAroundABoxReadsRestDensity)
{
  const RestDensity exact = restDensityAround(cube(), true);
  const RestDensity tangent = restDensityAround(cube(), false);
  const char* names[4] = { "", "face", "edge", "corner" };
  double worstExact = 0, worstTangent = 0;
  for (int c = 1; c <= 3; ++c)
  {
    std::printf("%-6s %4d particles: worst |rho/rho_0 - 1| %.4f (tangent plane %.4f)\n", names[c],
      exact.count[c], exact.worst[c], tangent.worst[c]);
    ASSERT_GT(exact.count[c], 0);
    worstExact = std::max(worstExact, exact.worst[c]);
    worstTangent = std::max(worstTangent, tangent.worst[c]);
  }
  // Over a face by an edge the tangent plane counts the whole half-space (+5.8 %); the factors
  // take the edge away (measured 1.25 %; over the edge itself 1.8 %, where the tangent plane's
  // layering happens to fall on the lattice's, 0.9 %). The target is 1 %: the
  // continuous factors scale the table's layering near the particle with the solid's share,
  // which a lattice does not quite do.
  EXPECT_LT(worstExact, 0.02);
  EXPECT_GT(worstTangent, 0.05);
  EXPECT_LT(exact.worst[1], 0.5 * tangent.worst[1]);
}

TEST(ShapeMap, TheLatticeCutByASphereIsNoRestState)
{
  SolidRegion ball;
  ball.kind = SolidRegion::Kind::Sphere;
  ball.center = { 0.6, 0.6, 0.6 };
  ball.radius = 0.2;
  const RestDensity exact = restDensityAround(ball, true);
  const RestDensity tangent = restDensityAround(ball, false);
  double worstExact = 0, worstTangent = 0;
  int count = 0;
  for (int c = 0; c <= 3; ++c)
  {
    worstExact = std::max(worstExact, exact.worst[c]);
    worstTangent = std::max(worstTangent, tangent.worst[c]);
    count += exact.count[c];
  }
  std::printf("sphere %d particles: worst |rho/rho_0 - 1| %.4f (tangent plane %.4f)\n", count,
    worstExact, worstTangent);
  ASSERT_GT(count, 100);
  // A cubic lattice cut by a ball leaves particles a hundredth of a spacing from its surface,
  // whose mirror image in the surface nearly coincides with them: +20 % and more under any mirror
  // model, until the fluid relaxes. The factors take away what the ball does not fill (measured
  // 21.8 % against 32.6 %).
  EXPECT_LT(worstExact, worstTangent - 0.05);
}

TEST(ShapeMap, ASolidNoNodeLiesInsideIsNamed)
{
  const Parameters p = tankParameters();
  SolidRegion grain;
  grain.kind = SolidRegion::Kind::Sphere;
  grain.center = { 0.6 + 0.25 * kSpacing, 0.6 + 0.25 * kSpacing, 0.6 + 0.25 * kSpacing };
  grain.radius = 0.05 * kSpacing;
  grain.name = "grain";
  try
  {
    solidFields({ grain }, p);
    FAIL() << "a sphere of radius s / 20 between the nodes was accepted";
  }
  catch (const InvalidInput& e)
  {
    EXPECT_NE(std::string(e.what()).find("grain: thinner than its grid resolves"),
      std::string::npos)
      << e.what();
  }
}

// A box standing on the tank's floor: with mirror walls the world below the floor is the image
// of the one above, the box's included, so its side faces continue down through the floor and a
// point by the foot of a face reads the flat factors (to the integration's 1e-6); without mirror
// walls the box ends at the floor, an edge that takes part of the half-space away (the poly6
// factor well below 1).
TEST(ShapeMap, ABoxOnTheFloorContinuesInItsImage)
{
  Parameters p = tankParameters();
  // A floor away from y = 0 and a box 3 spacings tall (its top farther than h from the foot), so
  // that a reflection about the origin, which lands above the box, does not pass for one about
  // the wall.
  p.domain.min.y = -0.25;
  SolidRegion standing = cube();
  standing.box.min.y = p.domain.min.y;
  standing.box.max.y = p.domain.min.y + 3 * kSpacing;
  const Vec3d foot{ standing.box.max.x + 0.5 * kSpacing, p.domain.min.y + 0.3 * kSpacing, 0.6 };
  const DistanceGrid mirrored = mapped(standing, p);
  const std::array<double, kShapeValues> flat = mapAt(mirrored, foot);
  p.mirrorWalls = false;
  const DistanceGrid open = mapped(standing, p);
  const std::array<double, kShapeValues> edge = mapAt(open, foot);
  std::printf("by the foot of a face: poly6 factor %.6f with mirror walls, %.4f without\n",
    flat[0], edge[0]);
  const double expected[kShapeValues] = { 1, 1, 0, 0, 1, 1, 0, 0 };
  for (int v = 0; v < kShapeValues; ++v)
  {
    EXPECT_NEAR(flat[v], expected[v], 1e-6) << "factor " << v;
  }
  EXPECT_LT(edge[0], 0.9);
}
