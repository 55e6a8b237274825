#include "ShapeMap.h"

#include "Kernels.h"
#include "RepeatedWindows.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace pbf
{
namespace
{

// See shapeFactorsAt.
constexpr double kRegularization = 1e-3;
// Moves along the gradient towards a node's surface point.
constexpr int kLooks = 4;
// How far a node's surface point may lie from it, in cells, for its factors to be shared with the
// nodes whose surroundings repeat its own (RepeatedWindows.h); farther ones are integrated alone.
constexpr int kShareableLook = 3;

Vec3d unitOr(const Vec3d& v, const Vec3d& fallback)
{
  const double l = length(v);
  return l > 0 && std::isfinite(l) ? v * (1 / l) : fallback;
}

std::array<float, kShapeValues> flatFactors(const Vec3d& n)
{
  const auto x = static_cast<float>(n.x), y = static_cast<float>(n.y), z = static_cast<float>(n.z);
  return { 1.0f, x, y, z, 1.0f, x, y, z };
}

// Whether the grid's field within h of node (i, j, k) is the plane through it along its gradient:
// every node of the cells that cover the ball, as far as the grid goes, on the plane to a
// ten-thousandth of a cell. The trilinear field between such nodes is that plane exactly, so the
// node's factors are the flat ones without integrating (most nodes of a solid's faces). Beyond
// the grid the field only grows (SignedDistance.h), and a grid cut at the domain reaches h past
// where any particle can be.
bool flatAround(const DistanceGrid& g, int i, int j, int k, double h)
{
  const Vec3d x = g.nodePosition(i, j, k);
  const Vec3d n = unitOr(g.gradient(x), Vec3d{ 0, 0, 0 });
  if (length(n) == 0)
  {
    return false;
  }
  const int reach = static_cast<int>(std::ceil(h / g.cell)) + 1;
  const double d = g.node(i, j, k), tolerance = 1e-4 * g.cell;
  for (int c = std::max(0, k - reach); c <= std::min(g.nz - 1, k + reach); ++c)
  {
    for (int b = std::max(0, j - reach); b <= std::min(g.ny - 1, j + reach); ++b)
    {
      for (int a = std::max(0, i - reach); a <= std::min(g.nx - 1, i + reach); ++a)
      {
        const Vec3d offset{ (a - i) * g.cell, (b - j) * g.cell, (c - k) * g.cell };
        if (std::abs(g.node(a, b, c) - (d + dot(n, offset))) > tolerance)
        {
          return false;
        }
      }
    }
  }
  return true;
}

// y reflected into the box across the walls it lies beyond.
double foldAxis(double v, double lo, double hi)
{
  return v < lo ? 2 * lo - v : (v > hi ? 2 * hi - v : v);
}

Vec3d fold(const Vec3d& y, const Box& box)
{
  return { foldAxis(y.x, box.min.x, box.max.x), foldAxis(y.y, box.min.y, box.max.y),
    foldAxis(y.z, box.min.z, box.max.z) };
}

// Whether the integration from a node at x, with its surface point up to kShareableLook cells
// away, reads the field across a mirror wall: then it depends on where the wall is, not only on
// the node's window.
bool readsAcrossWalls(const Vec3d& x, double reach, const ShapeWalls& walls)
{
  const Box& b = walls.domain;
  return walls.mirror &&
    (x.x - reach < b.min.x || x.x + reach > b.max.x || x.y - reach < b.min.y ||
      x.y + reach > b.max.y || x.z - reach < b.min.z || x.z + reach > b.max.z);
}

// Where a particle found at x goes (collideWithObstacles): inside, to the surface along the
// field's gradient, looked for again where the field bends near an edge; outside, x itself.
Vec3d surfacePoint(const DistanceGrid& grid, const Vec3d& x)
{
  const Vec3d n = unitOr(grid.gradient(x), Vec3d{ 0, 0, 1 });
  double d = grid.at(x);
  Vec3d at = x;
  for (int look = 0; look < kLooks && d < 0; ++look)
  {
    at -= unitOr(grid.gradient(at), n) * d;
    d = grid.at(at);
  }
  return at;
}

// For each near node, the node whose integration it shares: the first whose grid values repeat
// its own over every node its integration reads (the ball of h about its surface point, one
// node beyond for the interpolation); itself where its surface point lies farther than
// kShareableLook cells from it.
std::vector<std::int64_t> representatives(const DistanceGrid& grid,
  const std::vector<std::uint8_t>& near, double h, const ShapeWalls& walls)
{
  const std::int64_t nodes = static_cast<std::int64_t>(near.size());
  std::vector<std::uint8_t> shareable(near.size(), 0);
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t index = 0; index < nodes; ++index)
  {
    const std::size_t n = static_cast<std::size_t>(index);
    if (near[n])
    {
      const GridNode at = gridNode(grid, index);
      const Vec3d x = grid.nodePosition(at.i, at.j, at.k);
      const Vec3d moved = surfacePoint(grid, x) - x;
      const double limit = kShareableLook * grid.cell;
      shareable[n] = std::abs(moved.x) <= limit && std::abs(moved.y) <= limit &&
        std::abs(moved.z) <= limit && !readsAcrossWalls(x, h + limit + grid.cell, walls);
    }
  }
  const int radius = static_cast<int>(std::ceil(h / grid.cell)) + kShareableLook + 1;
  std::vector<std::int64_t> own = repeatedWindows(grid, shareable, radius);
  for (std::int64_t index = 0; index < nodes; ++index)
  {
    if (near[static_cast<std::size_t>(index)] && own[static_cast<std::size_t>(index)] < 0)
    {
      own[static_cast<std::size_t>(index)] = index;
    }
  }
  return own;
}

} // namespace

ShapeWalls shapeWalls(const Parameters& parameters, bool fixedSolid)
{
  return { parameters.mirrorWalls && fixedSolid, parameters.domain };
}

ShapeKernels shapeKernels(const Parameters& parameters)
{
  const double h = parameters.smoothingLength();
  const double dq = parameters.sCorrDeltaQ * h;
  return { h, parameters.sCorrN, Kernels<double>::make(h).poly6(dq * dq) };
}

std::array<float, kShapeValues> shapeFactorsAt(const DistanceGrid& grid, const Vec3d& x,
  const ShapeKernels& k, const ShapeWalls& walls, const ShapeRule& rule)
{
  // Folded into the domain, the field stays a distance bound (folding moves no two points
  // apart), so the rays' march may stride by it.
  const auto phi = [&grid, &walls](const Vec3d& y) {
    return grid.at(walls.mirror ? fold(y, walls.domain) : y);
  };
  const Vec3d n = unitOr(grid.gradient(x), Vec3d{ 0, 0, 1 });
  // Inside, the factors are those of the surface point a particle found at x goes to.
  const Vec3d at = surfacePoint(grid, x);
  const double d = std::max(0.0, grid.at(at));
  const Vec3d outward = unitOr(grid.gradient(at), n);
  if (d >= k.h)
  {
    return flatFactors(outward);
  }
  const ShapeIntegrals half = integrateOverHalfSpace(d, k, rule);
  const ShapeIntegrals solid = integrateOverSolid(at, outward * -1.0, phi, k, rule);
  // Each ratio is taken with a thousandth of the half-space's value at its surface added above
  // and below (along the normal for the vectors): where the half-space's integral fades at
  // d -> h the ratio of two vanishing numbers tends to 1 and the normal instead of rounding, and
  // the table it multiplies is nearly zero there anyway.
  const ShapeIntegrals surface = integrateOverHalfSpace(0.0, k, rule);
  const auto ratio = [](double solidValue, double halfValue, double surfaceValue) {
    const double e = kRegularization * surfaceValue;
    return (solidValue + e) / (halfValue + e);
  };
  // The half-space's vectors lie along its pole (the spiky one into the solid, s_corr's out of
  // it): their components along the outward normal are minus their z.
  const double es = kRegularization * -surface.spiky.z, et = kRegularization * -surface.tensile.z;
  const Vec3d s = (solid.spiky + outward * es) * (1 / (-half.spiky.z + es));
  const Vec3d t = (solid.tensile + outward * et) * (1 / (-half.tensile.z + et));
  return { static_cast<float>(ratio(solid.poly6, half.poly6, surface.poly6)),
    static_cast<float>(s.x), static_cast<float>(s.y), static_cast<float>(s.z),
    static_cast<float>(ratio(solid.spiky2, half.spiky2, surface.spiky2)), static_cast<float>(t.x),
    static_cast<float>(t.y), static_cast<float>(t.z) };
}

std::size_t buildShapeMap(
  DistanceGrid& grid, const ShapeKernels& k, const ShapeWalls& walls, const ShapeRule& rule)
{
  const std::int64_t nodes = static_cast<std::int64_t>(grid.phi.size());
  grid.shape.resize(static_cast<std::size_t>(nodes) * kShapeValues);
  const double inside = -2 * grid.cell, outside = k.h + 2 * grid.cell;
  // Every node's class: on a flat face or far from the solid (the flat factors), or near.
  std::vector<std::uint8_t> near(static_cast<std::size_t>(nodes), 0);
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t index = 0; index < nodes; ++index)
  {
    const std::size_t n = static_cast<std::size_t>(index);
    const GridNode at = gridNode(grid, index);
    near[n] = grid.phi[n] >= inside && grid.phi[n] <= outside &&
      !flatAround(grid, at.i, at.j, at.k, k.h);
    if (!near[n])
    {
      const auto values = flatFactors(unitOr(grid.gradient(
        grid.nodePosition(at.i, at.j, at.k)), Vec3d{ 0, 0, 1 }));
      std::copy(values.begin(), values.end(), grid.shape.begin() + n * kShapeValues);
    }
  }
  const std::vector<std::int64_t> own = representatives(grid, near, k.h, walls);
  std::size_t integrated = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : integrated)
  for (std::int64_t index = 0; index < nodes; ++index)
  {
    const std::size_t n = static_cast<std::size_t>(index);
    if (near[n] && own[n] == index)
    {
      const GridNode at = gridNode(grid, index);
      const auto values = shapeFactorsAt(grid, grid.nodePosition(at.i, at.j, at.k), k, walls, rule);
      std::copy(values.begin(), values.end(), grid.shape.begin() + n * kShapeValues);
      ++integrated;
    }
  }
#pragma omp parallel for schedule(static)
  for (std::int64_t index = 0; index < nodes; ++index)
  {
    const std::size_t n = static_cast<std::size_t>(index);
    if (near[n] && own[n] != index)
    {
      const std::size_t from = static_cast<std::size_t>(own[n]) * kShapeValues;
      std::copy(grid.shape.begin() + from, grid.shape.begin() + from + kShapeValues,
        grid.shape.begin() + n * kShapeValues);
    }
  }
  return integrated;
}

} // namespace pbf
