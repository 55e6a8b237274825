#include "ShapeMap.h"

#include "Kernels.h"

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

} // namespace

ShapeKernels shapeKernels(const Parameters& parameters)
{
  const double h = parameters.smoothingLength();
  const double dq = parameters.sCorrDeltaQ * h;
  return { h, parameters.sCorrN, Kernels<double>::make(h).poly6(dq * dq) };
}

std::array<float, kShapeValues> shapeFactorsAt(
  const DistanceGrid& grid, const Vec3d& x, const ShapeKernels& k, const ShapeRule& rule)
{
  const auto phi = [&grid](const Vec3d& y) { return grid.at(y); };
  const Vec3d n = unitOr(grid.gradient(x), Vec3d{ 0, 0, 1 });
  double d = grid.at(x);
  Vec3d at = x;
  // Inside: a particle found here goes to the surface along the field's gradient
  // (collideWithObstacles); the factors are those of its surface point, looked for again where
  // the field bends near an edge.
  for (int look = 0; look < kLooks && d < 0; ++look)
  {
    at -= unitOr(grid.gradient(at), n) * d;
    d = grid.at(at);
  }
  d = std::max(0.0, d);
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

std::size_t buildShapeMap(DistanceGrid& grid, const ShapeKernels& k, const ShapeRule& rule)
{
  const std::int64_t nodes = static_cast<std::int64_t>(grid.phi.size());
  grid.shape.resize(static_cast<std::size_t>(nodes) * kShapeValues);
  const double inside = -2 * grid.cell, outside = k.h + 2 * grid.cell;
  std::size_t integrated = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : integrated)
  for (std::int64_t index = 0; index < nodes; ++index)
  {
    const double phi = grid.phi[static_cast<std::size_t>(index)];
    const std::int64_t plane = static_cast<std::int64_t>(grid.nx) * grid.ny;
    const Vec3d x = grid.nodePosition(static_cast<int>(index % grid.nx),
      static_cast<int>((index % plane) / grid.nx), static_cast<int>(index / plane));
    const bool near = phi >= inside && phi <= outside &&
      !flatAround(grid, static_cast<int>(index % grid.nx),
        static_cast<int>((index % plane) / grid.nx), static_cast<int>(index / plane), k.h);
    const std::array<float, kShapeValues> values = near
      ? shapeFactorsAt(grid, x, k, rule)
      : flatFactors(unitOr(grid.gradient(x), Vec3d{ 0, 0, 1 }));
    for (int v = 0; v < kShapeValues; ++v)
    {
      grid.shape[static_cast<std::size_t>(index) * kShapeValues + v] = values[v];
    }
    integrated += near ? 1 : 0;
  }
  return integrated;
}

} // namespace pbf
