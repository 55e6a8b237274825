// The fluid's surface (Surface/SurfaceExtraction.h): a sphere of fluid at rest gives a closed
// surface within half a spacing of the sphere, facing out; the mesh is the same with and without
// threads; the interpolated fields are the particles'; bad options name the property.
#include "Scene.h"
#include "Solids.h"
#include "Distributed/ThreadCluster.h"
#include "SurfaceCells.h"
#include "SurfaceExtraction.h"
#include "SurfaceShare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <algorithm>
#include <array>
#include <map>
#include <utility>

using namespace pbf;

namespace
{

constexpr double kSpacing = 0.01;
constexpr double kRadius = 20 * kSpacing;
const Vec3d kCentre{ 0.5, 0.5, 0.5 };

// A sphere of 20 spacings' radius on the lattice, every particle moving at (1, 2, 3) m/s with
// the rest density.
struct Sphere
{
  Parameters parameters;
  std::vector<Vec3d> x, v;
  std::vector<double> rho;
};

Sphere fluidSphere()
{
  Sphere s;
  s.parameters.particleSpacing = kSpacing;
  Scene scene;
  scene.domain = { { 0, 0, 0 }, { 1, 1, 1 } };
  scene.spheres.push_back({ kCentre, kRadius, { 1, 2, 3 } });
  s.parameters.domain = scene.domain;
  const ParticleBatch batch = fillScene(scene, s.parameters);
  s.x = batch.position;
  s.v = batch.velocity;
  s.rho.assign(s.x.size(), s.parameters.restDensity);
  return s;
}

SurfaceMesh surfaceOf(const Sphere& s, bool parallel, SurfaceOptions options = {})
{
  return extractSurface<double>(s.x.data(), s.v.data(), s.rho.data(), s.x.size(), s.parameters,
    options, parallel);
}

// Edges not shared by exactly two triangles once in each direction: 0 for a closed,
// consistently oriented surface.
std::size_t openEdges(const SurfaceMesh& mesh)
{
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (const auto& t : mesh.triangles)
  {
    for (int e = 0; e < 3; ++e)
    {
      ++edges[{ t[e], t[(e + 1) % 3] }];
    }
  }
  std::size_t open = 0;
  for (const auto& [edge, count] : edges)
  {
    const auto back = edges.find({ edge.second, edge.first });
    open += (count != 1 || back == edges.end() || back->second != 1) ? 1 : 0;
  }
  return open;
}

// A 0.4 x 0.4 x 0.2 m block of lattice at rest with its top face at z = 0.5 m (a flat free
// surface), every particle at the rest density.
struct FlatBlock
{
  Parameters parameters;
  ParticleBatch particles;
  std::vector<double> rho;
};

FlatBlock flatBlock()
{
  FlatBlock b;
  b.parameters.particleSpacing = kSpacing;
  Scene scene;
  scene.domain = { { 0, 0, 0 }, { 1, 1, 1 } };
  scene.boxes.push_back({ { 0.3, 0.3, 0.3 }, { 0.7, 0.7, 0.5 }, { 0, 0, 0 } });
  b.parameters.domain = scene.domain;
  b.particles = fillScene(scene, b.parameters);
  b.rho.assign(b.particles.position.size(), b.parameters.restDensity);
  return b;
}

} // namespace

TEST(Surface, ASphereOfFluidGivesAClosedSurfaceWithinHalfASpacing)
{
  const Sphere s = fluidSphere();
  ASSERT_GT(s.x.size(), 30000u);
  const SurfaceMesh mesh = surfaceOf(s, true);
  ASSERT_GT(mesh.triangles.size(), 1000u);
  // Within half a spacing of the true sphere: the lattice's sphere holds the volume of a sphere
  // of radius R (to the lattice's rounding), and the level 1/2 lies s/2 beyond a flat lattice's
  // last layer, where that volume ends.
  double nearest = HUGE_VAL, farthest = 0;
  for (const Vec3<float>& p : mesh.points)
  {
    const double r = length(Vec3d::from(p) - kCentre);
    nearest = std::min(nearest, r);
    farthest = std::max(farthest, r);
  }
  std::printf("sphere of %zu particles: %zu triangles, %zu vertices, radius %.5f to %.5f m "
              "(R %.3f m), %zu blocks sampled, %zu kept, %zu bytes at most\n",
    s.x.size(), mesh.triangles.size(), mesh.points.size(), nearest, farthest, kRadius,
    mesh.sampledBlocks, mesh.keptBlocks, mesh.peakBytes);
  EXPECT_GT(nearest, kRadius - 0.5 * kSpacing);
  EXPECT_LT(farthest, kRadius + 0.5 * kSpacing);
  EXPECT_EQ(openEdges(mesh), 0u);
  // Facing out: the normals and the triangles' winding point away from the centre.
  std::size_t inward = 0;
  for (std::size_t i = 0; i < mesh.points.size(); ++i)
  {
    inward += dot(Vec3d::from(mesh.normals[i]), Vec3d::from(mesh.points[i]) - kCentre) <= 0 ? 1 : 0;
  }
  EXPECT_EQ(inward, 0u);
  double signedVolume = 0; // by the divergence theorem, positive for outward winding
  for (const auto& t : mesh.triangles)
  {
    const Vec3d a = Vec3d::from(mesh.points[t[0]]) - kCentre;
    const Vec3d b = Vec3d::from(mesh.points[t[1]]) - kCentre;
    const Vec3d c = Vec3d::from(mesh.points[t[2]]) - kCentre;
    signedVolume += dot(a, cross(b, c)) / 6.0;
  }
  const double sphereVolume = 4.0 / 3.0 * 3.14159265358979 * std::pow(kRadius, 3);
  EXPECT_NEAR(signedVolume / sphereVolume, 1.0, 0.05);
  // Narrow band: only the blocks the level passes through are kept.
  EXPECT_LT(mesh.keptBlocks, mesh.sampledBlocks);
  // The fields are the particles': all move at (1, 2, 3) m/s with rho_0 (rounding of the
  // Shepard average in float, 1e-6 relative).
  for (std::size_t i = 0; i < mesh.points.size(); i += 97)
  {
    EXPECT_NEAR(mesh.velocity[i].x, 1.0f, 1e-5f);
    EXPECT_NEAR(mesh.velocity[i].z, 3.0f, 1e-5f);
    EXPECT_NEAR(mesh.density[i], 1000.0f, 1e-2f);
  }
}

TEST(Surface, ThreadsChangeNoBitAndSmoothingKeepsItClosedAndNear)
{
  const Sphere s = fluidSphere();
  const SurfaceMesh a = surfaceOf(s, false), b = surfaceOf(s, true);
  ASSERT_EQ(a.points.size(), b.points.size());
  ASSERT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(a.points[0])), 0);
  EXPECT_EQ(std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(a.normals[0])), 0);
  SurfaceOptions smooth;
  smooth.smoothing = 5;
  const SurfaceMesh c = surfaceOf(s, true, smooth);
  EXPECT_EQ(c.triangles, a.triangles); // smoothing moves vertices, it does not change the mesh
  double worst = 0;
  for (const Vec3<float>& p : c.points)
  {
    worst = std::max(worst, std::abs(length(Vec3d::from(p) - kCentre) - kRadius));
  }
  EXPECT_LT(worst, 0.5 * kSpacing);
}

TEST(Surface, BadOptionsNameTheProperty)
{
  const Sphere s = fluidSphere();
  auto error = [&](SurfaceOptions o) {
    try
    {
      surfaceOf(s, false, o);
    }
    catch (const InvalidInput& e)
    {
      return std::string(e.what());
    }
    return std::string();
  };
  SurfaceOptions o;
  o.resolution = 0;
  EXPECT_NE(error(o).find("SurfaceResolution = 0"), std::string::npos);
  o = SurfaceOptions{};
  o.isoValue = 1.5;
  EXPECT_NE(error(o).find("SurfaceIsoValue = 1.5"), std::string::npos);
  o = SurfaceOptions{};
  o.smoothing = -1;
  EXPECT_NE(error(o).find("SurfaceSmoothing = -1"), std::string::npos);
  // No particles: an empty surface, not an error.
  EXPECT_TRUE(extractSurface<float>(nullptr, nullptr, nullptr, 0, s.parameters, {}, true)
                .triangles.empty());
}

namespace
{

// The sphere split at x = 0.5 m (its centre) into two ranks' shares, each given its own
// particles and the other's within the ghost reach: together they are the whole surface,
// vertex for vertex (the same float bits where they meet) and triangle for triangle.
void expectTwoSharesMakeTheWhole(const SurfaceOptions& options)
{
  const Sphere s = fluidSphere();
  const SurfaceMesh whole = surfaceOf(s, true, options);
  const double cut = 0.5, reach = surfaceGhostReach(s.parameters, options);
  std::map<std::array<float, 3>, std::size_t> seen; // vertex -> how many shares made it
  std::size_t triangles = 0, shared = 0;
  std::vector<std::array<std::array<float, 3>, 3>> pieces;
  for (int rank = 0; rank < 2; ++rank)
  {
    SurfaceShare share;
    (rank == 0 ? share.xMax : share.xMin) = cut;
    Sphere part = s;
    part.x.clear();
    part.v.clear();
    part.rho.clear();
    for (std::size_t i = 0; i < s.x.size(); ++i)
    {
      const bool mine = rank == 0 ? s.x[i].x < cut : s.x[i].x >= cut;
      const bool ghost = rank == 0 ? s.x[i].x < cut + reach : s.x[i].x >= cut - reach;
      if (mine || ghost)
      {
        part.x.push_back(s.x[i]);
        part.v.push_back(s.v[i]);
        part.rho.push_back(s.rho[i]);
      }
    }
    // Another order: the rank's ghosts first.
    std::reverse(part.x.begin(), part.x.end());
    std::reverse(part.v.begin(), part.v.end());
    const SurfaceMesh mesh = extractSurface<double>(part.x.data(), part.v.data(), part.rho.data(),
      part.x.size(), part.parameters, options, true, share);
    ASSERT_GT(mesh.triangles.size(), 1000u) << "rank " << rank;
    triangles += mesh.triangles.size();
    for (const Vec3<float>& p : mesh.points)
    {
      shared += ++seen[{ p.x, p.y, p.z }] == 2 ? 1 : 0;
    }
  }
  EXPECT_EQ(triangles, whole.triangles.size());
  EXPECT_EQ(seen.size(), whole.points.size()); // no vertex of the cut made twice in other bits
  for (const Vec3<float>& p : whole.points)
  {
    EXPECT_EQ(seen.count({ p.x, p.y, p.z }), 1u);
  }
  EXPECT_GT(shared, 100u); // the ring where the shares meet
}

} // namespace

TEST(Surface, TwoSharesOfADecomposedRunMeetWithoutACrack)
{
  expectTwoSharesMakeTheWhole(SurfaceOptions{});
  SurfaceOptions anisotropic;
  anisotropic.anisotropic = true;
  expectTwoSharesMakeTheWhole(anisotropic);
}

TEST(Surface, ThreeRanksExchangeTheirBordersAndMakeTheWholeSurface)
{
  // The sphere's particles dealt to three ranks (threads) by slab, each rank's in another order:
  // the shares exchanged through the communicator make the whole surface, triangle for triangle
  // and vertex for vertex.
  const Sphere s = fluidSphere();
  const SurfaceMesh whole = surfaceOf(s, true);
  const double h = s.parameters.smoothingLength();
  distributed::Slabs slabs;
  const int columns = static_cast<int>(std::ceil(1.0 / h));
  slabs.first = { 0, static_cast<int>(0.45 / h), static_cast<int>(0.55 / h), columns };
  std::vector<SurfaceMesh> shares(3);
  distributed::runThreadCluster(3, [&](distributed::Communicator& communicator) {
    const int r = communicator.rank();
    const SurfaceShare mine = slabShare(slabs, r, s.parameters);
    std::vector<Vec3d> x, v;
    std::vector<double> rho;
    for (std::size_t i = s.x.size(); i-- > 0;)
    {
      if (s.x[i].x >= mine.xMin && s.x[i].x < mine.xMax)
      {
        x.push_back(s.x[i]);
        v.push_back(s.v[i]);
        rho.push_back(s.rho[i]);
      }
    }
    shares[static_cast<std::size_t>(r)] = extractSurfaceShare<double>(communicator, slabs,
      x.data(), v.data(), rho.data(), x.size(), s.parameters, SurfaceOptions{}, false);
  });
  std::map<std::array<float, 3>, int> seen;
  std::size_t triangles = 0;
  for (const SurfaceMesh& m : shares)
  {
    triangles += m.triangles.size();
    for (const Vec3<float>& p : m.points)
    {
      ++seen[{ p.x, p.y, p.z }];
    }
  }
  EXPECT_EQ(triangles, whole.triangles.size());
  EXPECT_EQ(seen.size(), whole.points.size());
  for (const Vec3<float>& p : whole.points)
  {
    EXPECT_EQ(seen.count({ p.x, p.y, p.z }), 1u);
  }
}

TEST(Surface, AnObstacleClipsTheSurfaceAtItsFace)
{
  // A solid slab through the sphere's lower part (z < 0.45): the fluid ends at the slab's face,
  // so the surface has no vertex inside the solid, and a cap on the face, still closed.
  const Sphere s = fluidSphere();
  SolidRegion slab;
  slab.box = { { 0.1, 0.1, 0.1 }, { 0.9, 0.9, 0.45 } };
  const std::vector<DistanceGrid> fields = solidFields({ slab }, s.parameters);
  SurfaceSolids solids;
  solids.views.push_back(fields[0].view<double>(fields[0].phi.data(), nullptr));
  const SurfaceMesh clipped = extractSurface<double>(s.x.data(), s.v.data(), s.rho.data(),
    s.x.size(), s.parameters, {}, true, {}, solids);
  const SurfaceMesh whole = surfaceOf(s, true);
  auto depth = [&](const Vec3<float>& p) { return fields[0].at(Vec3d::from(p)); };
  double deepestWhole = HUGE_VAL, deepest = HUGE_VAL;
  for (const Vec3<float>& p : whole.points)
  {
    deepestWhole = std::min(deepestWhole, depth(p));
  }
  std::size_t cap = 0, capFacingIn = 0;
  for (std::size_t i = 0; i < clipped.points.size(); ++i)
  {
    const double d = depth(clipped.points[i]);
    deepest = std::min(deepest, d);
    if (d < 0.01 * kSpacing)
    {
      ++cap;
      capFacingIn += clipped.normals[i].z < -0.99f ? 1 : 0;
    }
  }
  std::printf("clipped: %zu triangles (whole %zu), deepest vertex %.3g m into the solid (whole "
              "%.3g m), %zu cap vertices, %zu facing into the solid\n",
    clipped.triangles.size(), whole.triangles.size(), -deepest, -deepestWhole, cap, capFacingIn);
  // Without clipping the sphere's lower part lies 15 spacings inside the slab.
  EXPECT_LT(deepestWhole, -14 * kSpacing);
  // With it, no vertex inside: at a crossing the clipped colour is at most iso + d / cell, so d
  // >= 0 there, up to the solid field's float nodes (1e-7 m here); a hundredth of a spacing.
  EXPECT_GT(deepest, -0.01 * kSpacing);
  EXPECT_EQ(openEdges(clipped), 0u);
  // The cap: a disk of radius sqrt(0.2^2 - 0.05^2) = 0.19 m on the face, its normals the solid's
  // inward one (-z: out of the fluid), but for its rim, where the sphere's own surface meets the
  // face and the colour's gradient gives the normal (30 of 18,511 vertices when written).
  EXPECT_GT(cap, 1000u);
  EXPECT_GT(capFacingIn, cap * 99 / 100);
}

TEST(Surface, SymmetricEigenReconstructsTheMatrix)
{
  // Matrices of several shapes (a diagonal, a degenerate pair, a full one, a flat one): V D V^T
  // gives the matrix back and V is orthonormal, to 1e-12 of the largest entry (double rounding
  // over a few Jacobi sweeps).
  const double cases[][6] = { { 3, 0, 0, 1, 0, 2 }, { 2, 1, 0, 2, 0, 5 }, { 4, 1.5, -0.7, 3, 0.2, 1 },
    { 1e-6, 2e-7, 0, 1e-6, 0, 1e-9 }, { 1, 1, 1, 1, 1, 1 } };
  for (const auto& a : cases)
  {
    double values[3], v[9];
    surface::symmetricEigen(a, values, v);
    double scale = 0;
    for (double e : a)
    {
      scale = std::max(scale, std::abs(e));
    }
    const int at[3][3] = { { 0, 1, 2 }, { 1, 3, 4 }, { 2, 4, 5 } };
    for (int r = 0; r < 3; ++r)
    {
      for (int c = 0; c < 3; ++c)
      {
        double back = 0, orthonormal = 0;
        for (int k = 0; k < 3; ++k)
        {
          back += v[3 * r + k] * values[k] * v[3 * c + k];
          orthonormal += v[3 * k + r] * v[3 * k + c];
        }
        EXPECT_NEAR(back, a[at[r][c]], 1e-12 * scale);
        EXPECT_NEAR(orthonormal, r == c ? 1.0 : 0.0, 1e-12);
      }
    }
  }
}

TEST(Surface, AnisotropicKernelsFlattenTheWaterAndKeepTheSphere)
{
  // A block of fluid at rest: its top face, a flat free surface, is flatter with anisotropic
  // kernels (the kernels of its last layer are squeezed along the normal); the sphere stays
  // within half a spacing of the true one and closed; threads change no bit.
  const FlatBlock flat = flatBlock();
  const Parameters& p = flat.parameters;
  const ParticleBatch& block = flat.particles;
  const std::vector<double>& rho = flat.rho;
  SurfaceOptions round, stretched;
  stretched.anisotropic = true;
  // The top face's height, over the vertices above the block's middle: its spread, the surface's
  // bumps at the lattice's scale.
  auto topBumps = [&](const SurfaceOptions& options, double& mean) {
    const SurfaceMesh mesh = extractSurface<double>(block.position.data(), block.velocity.data(),
      rho.data(), block.position.size(), p, options, true);
    EXPECT_EQ(openEdges(mesh), 0u);
    double low = HUGE_VAL, high = -HUGE_VAL, sum = 0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < mesh.points.size(); ++i)
    {
      const Vec3<float>& q = mesh.points[i];
      if (q.z > 0.45 && q.x > 0.4 && q.x < 0.6 && q.y > 0.4 && q.y < 0.6)
      {
        low = std::min(low, static_cast<double>(q.z));
        high = std::max(high, static_cast<double>(q.z));
        sum += q.z;
        ++count;
      }
    }
    mean = sum / static_cast<double>(count);
    return high - low;
  };
  double roundMean = 0, stretchedMean = 0;
  const double roundBumps = topBumps(round, roundMean);
  const double stretchedBumps = topBumps(stretched, stretchedMean);
  std::printf("top face: round kernels %.3g m of bumps at %.4f m, anisotropic %.3g m at %.4f m\n",
    roundBumps, roundMean, stretchedBumps, stretchedMean);
  EXPECT_LT(stretchedBumps, 0.5 * roundBumps);
  // Still where the water ends: within a tenth of a spacing of the last layer's s/2 beyond.
  EXPECT_NEAR(stretchedMean, 0.5, 0.1 * kSpacing);

  const Sphere s = fluidSphere();
  const SurfaceMesh a = surfaceOf(s, true, stretched), b = surfaceOf(s, false, stretched);
  EXPECT_EQ(openEdges(a), 0u);
  double nearest = HUGE_VAL, farthest = 0;
  for (const Vec3<float>& q : a.points)
  {
    const double r = length(Vec3d::from(q) - kCentre);
    nearest = std::min(nearest, r);
    farthest = std::max(farthest, r);
  }
  std::printf("anisotropic sphere: %zu triangles, radius %.5f to %.5f m\n", a.triangles.size(),
    nearest, farthest);
  EXPECT_GT(nearest, kRadius - 0.5 * kSpacing);
  EXPECT_LT(farthest, kRadius + 0.5 * kSpacing);
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(a.points[0])), 0);
  EXPECT_EQ(a.triangles, b.triangles);
}

// Where the colour function of a half-space of fluid crosses iso, above its face, in units of
// h: phi(z) = integral over z' > z of poly6's marginal along one axis,
// (315 / 256) (1 - u^2)^4 for |u| < 1, so phi(0) = 1/2; solved by bisection.
double halfSpaceLevel(double iso)
{
  auto tail = [](double u) {
    // The integral of (1 - t^2)^4 from u to 1, term by term: 1 - 4t^2 + 6t^4 - 4t^6 + t^8.
    auto primitive = [](double t) {
      return t - 4 * std::pow(t, 3) / 3 + 6 * std::pow(t, 5) / 5 - 4 * std::pow(t, 7) / 7 +
        std::pow(t, 9) / 9;
    };
    return 315.0 / 256.0 * (primitive(1.0) - primitive(u));
  };
  double low = -1, high = 1; // tail falls from 1 to 0
  for (int i = 0; i < 60; ++i)
  {
    const double mid = 0.5 * (low + high);
    (tail(mid) > iso ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

TEST(Surface, TheIsoValueMovesAFlatSurfaceByTheHalfSpacesLevel)
{
  // A block of fluid at rest; its top face's mean height, over the vertices above its middle,
  // at the default iso value and at two others. The lattice's face is s/2 above its last layer
  // (where phi = 1/2 for the continuum); another level moves the surface by the continuum's
  // h * halfSpaceLevel(iso). The lattice's discreteness moves the mean by at most 0.03 s at
  // these levels (measured -0.011, -0.028, +0.016 s); 0.05 s is the tolerance, and a level read
  // 0.05 off (0.45 for 0.5: 0.04 h = 0.08 s) cannot pass.
  const FlatBlock flat = flatBlock();
  const Parameters& p = flat.parameters;
  const ParticleBatch& block = flat.particles;
  const std::vector<double>& rho = flat.rho;
  double lastLayer = 0;
  for (const Vec3d& x : block.position)
  {
    lastLayer = std::max(lastLayer, x.z);
  }
  const double face = lastLayer + 0.5 * kSpacing;
  const double h = p.smoothingLength();
  // The default (SurfaceIsoValue's documented 0.5) and two others.
  for (const double iso : { 0.5, 0.25, 0.75 })
  {
    SurfaceOptions options;
    if (iso != 0.5)
    {
      options.isoValue = iso;
    }
    const SurfaceMesh mesh = extractSurface<double>(block.position.data(),
      block.velocity.data(), rho.data(), block.position.size(), p, options, true);
    double sum = 0;
    std::size_t count = 0;
    for (const Vec3<float>& q : mesh.points)
    {
      if (q.z > face - h && q.x > 0.4 && q.x < 0.6 && q.y > 0.4 && q.y < 0.6)
      {
        sum += q.z;
        ++count;
      }
    }
    ASSERT_GT(count, 100u) << "iso " << iso;
    const double mean = sum / static_cast<double>(count);
    const double expected = face + h * halfSpaceLevel(iso);
    std::printf("iso %.2f: top face at %.5f m, the half-space's level %.5f m (%+.3f s)\n", iso,
      mean, expected, (mean - expected) / kSpacing);
    EXPECT_NEAR(mean, expected, 0.05 * kSpacing) << "iso " << iso;
  }
}

TEST(Surface, CubeRootIsWithinAnUlpOrTwo)
{
  // The anisotropic kernels' cube root (IEEE operations only, the same bits on the GPU) against
  // the library's, to 4e-16 relative (two ulps) over 60 decades.
  for (double x = 1e-30; x < 1e30; x *= 3.7)
  {
    EXPECT_NEAR(surface::cubeRoot(x), std::cbrt(x), 4e-16 * std::cbrt(x)) << x;
  }
  EXPECT_EQ(surface::cubeRoot(8.0), 2.0);
  EXPECT_EQ(surface::cubeRoot(0.125), 0.5);
}
