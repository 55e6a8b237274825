#include "SignedDistance.h"

#include "PointText.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace pbf
{
namespace
{

// 2^27 nodes is 512 MiB of floats: beyond that the resolution, not the solid, is wrong.
constexpr double kMostNodes = 134217728.0;

// The nodes over [lo, hi] padded by margin, `cell` apart; phi left to fill.
DistanceGrid gridOver(Vec3d lo, Vec3d hi, double cell, double margin, const std::string& what)
{
  if (!(cell > 0) || !std::isfinite(cell))
  {
    std::ostringstream text;
    text << what << ": grid cell = " << cell << ": must be > 0";
    throw InvalidInput(text.str());
  }
  if (!(margin >= 0) || !std::isfinite(margin))
  {
    std::ostringstream text;
    text << what << ": grid margin = " << margin << ": must be >= 0";
    throw InvalidInput(text.str());
  }
  DistanceGrid g;
  g.cell = cell;
  g.origin = lo - Vec3d{ margin, margin, margin };
  const Vec3d extent = hi - lo + Vec3d{ 2 * margin, 2 * margin, 2 * margin };
  const double n[3] = { std::ceil(extent.x / cell) + 1, std::ceil(extent.y / cell) + 1,
    std::ceil(extent.z / cell) + 1 };
  if (n[0] * n[1] * n[2] > kMostNodes)
  {
    std::ostringstream text;
    text << what << ": " << n[0] << " x " << n[1] << " x " << n[2] << " distance nodes of " << cell
         << " m (more than " << kMostNodes << "): use a coarser grid cell or a smaller solid";
    throw InvalidInput(text.str());
  }
  g.nx = static_cast<int>(n[0]);
  g.ny = static_cast<int>(n[1]);
  g.nz = static_cast<int>(n[2]);
  g.phi.assign(static_cast<std::size_t>(g.nx) * g.ny * g.nz, 0.0f);
  return g;
}

// Sets every node's value and normal from f(x) = { phi, outward unit normal }, the z-slices split
// over threads.
template <class F>
void forEachNode(DistanceGrid& g, F&& f)
{
  g.normal.assign(3 * g.phi.size(), 0.0f);
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < g.nz; ++k)
  {
    for (int j = 0; j < g.ny; ++j)
    {
      for (int i = 0; i < g.nx; ++i)
      {
        const std::pair<double, Vec3d> value = f(g.nodePosition(i, j, k));
        const std::size_t n = g.index(i, j, k);
        g.phi[n] = static_cast<float>(value.first);
        g.normal[3 * n] = static_cast<float>(value.second.x);
        g.normal[3 * n + 1] = static_cast<float>(value.second.y);
        g.normal[3 * n + 2] = static_cast<float>(value.second.z);
      }
    }
  }
}

} // namespace

double DistanceGrid::at(const Vec3d& x) const
{
  if (!isFinite(x))
  {
    return std::numeric_limits<double>::quiet_NaN(); // converting NaN to a node index is undefined
  }
  const double u[3] = { (x.x - origin.x) / cell, (x.y - origin.y) / cell, (x.z - origin.z) / cell };
  const int n[3] = { nx, ny, nz };
  int i[3];
  double t[3];
  double outside2 = 0;
  for (int a = 0; a < 3; ++a)
  {
    const double clamped = std::min(std::max(u[a], 0.0), double(n[a] - 1));
    outside2 += (u[a] - clamped) * (u[a] - clamped);
    i[a] = std::min(static_cast<int>(clamped), n[a] - 2);
    t[a] = clamped - i[a];
  }
  double value = 0;
  for (int corner = 0; corner < 8; ++corner)
  {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
    const double w = (dx ? t[0] : 1 - t[0]) * (dy ? t[1] : 1 - t[1]) * (dz ? t[2] : 1 - t[2]);
    value += w * node(i[0] + dx, i[1] + dy, i[2] + dz);
  }
  return value + std::sqrt(outside2) * cell;
}

Vec3d DistanceGrid::gradient(const Vec3d& x) const
{
  if (!isFinite(x))
  {
    return Vec3d{ 0, 0, 0 };
  }
  const double u[3] = { (x.x - origin.x) / cell, (x.y - origin.y) / cell, (x.z - origin.z) / cell };
  const int n[3] = { nx, ny, nz };
  int i[3];
  double t[3];
  for (int a = 0; a < 3; ++a)
  {
    const double clamped = std::min(std::max(u[a], 0.0), double(n[a] - 1));
    i[a] = std::min(static_cast<int>(clamped), n[a] - 2);
    t[a] = clamped - i[a];
  }
  double g[3] = { 0, 0, 0 };
  for (int corner = 0; corner < 8; ++corner)
  {
    const int d[3] = { corner & 1, (corner >> 1) & 1, (corner >> 2) & 1 };
    const double value = node(i[0] + d[0], i[1] + d[1], i[2] + d[2]);
    for (int a = 0; a < 3; ++a)
    {
      // d/du_a of the weight: the a factor differentiated, the other two as they are.
      double w = d[a] ? 1.0 : -1.0;
      for (int b = 0; b < 3; ++b)
      {
        if (b != a)
        {
          w *= d[b] ? t[b] : 1 - t[b];
        }
      }
      g[a] += w * value;
    }
  }
  return Vec3d{ g[0], g[1], g[2] } * (1.0 / cell);
}

DistanceGrid sphereDistance(const Vec3d& centre, double radius, double cell, double margin)
{
  if (!(radius > 0) || !std::isfinite(radius) || !isFinite(centre))
  {
    std::ostringstream text;
    text << "sphere at " << pointText(centre) << ", radius = " << radius
         << ": needs a finite centre and a radius > 0";
    throw InvalidInput(text.str());
  }
  const Vec3d r{ radius, radius, radius };
  DistanceGrid g = gridOver(centre - r, centre + r, cell, margin, "sphere");
  forEachNode(g, [&](const Vec3d& p) {
    const double r = length(p - centre);
    // The centre's normal is any direction: its plane lies a radius below every point of the cell.
    return std::make_pair(r - radius, r > 0 ? (p - centre) * (1.0 / r) : Vec3d{ 0, 0, 1 });
  });
  return g;
}

DistanceGrid boxDistance(const Box& box, double cell, double margin)
{
  if (!isFinite(box.min) || !isFinite(box.max) || !(box.min.x < box.max.x) ||
    !(box.min.y < box.max.y) || !(box.min.z < box.max.z))
  {
    throw InvalidInput("box " + pointText(box.min) + " - " + pointText(box.max) +
      ": needs finite corners with min < max on every axis");
  }
  return boxDistanceOn(box, gridOver(box.min, box.max, cell, margin, "box"));
}

DistanceGrid boxDistanceOn(const Box& box, DistanceGrid grid)
{
  const Vec3d centre = (box.min + box.max) * 0.5, half = (box.max - box.min) * 0.5;
  forEachNode(grid, [&](const Vec3d& p) {
    // Outside: the distance to the box, along the way from its nearest point; inside: minus the
    // distance to the nearest face, along that face's normal.
    const Vec3d side{ p.x < centre.x ? -1.0 : 1.0, p.y < centre.y ? -1.0 : 1.0,
      p.z < centre.z ? -1.0 : 1.0 };
    const Vec3d q{ std::abs(p.x - centre.x) - half.x, std::abs(p.y - centre.y) - half.y,
      std::abs(p.z - centre.z) - half.z };
    const Vec3d out{ std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0) };
    const double outside = length(out), deepest = std::max({ q.x, q.y, q.z });
    if (outside > 0)
    {
      const Vec3d n = out * (1.0 / outside);
      return std::make_pair(outside, Vec3d{ n.x * side.x, n.y * side.y, n.z * side.z });
    }
    const Vec3d n = deepest == q.x ? Vec3d{ side.x, 0, 0 }
      : deepest == q.y             ? Vec3d{ 0, side.y, 0 }
                                   : Vec3d{ 0, 0, side.z };
    return std::make_pair(deepest, n);
  });
  return grid;
}

DistanceGrid gridOver(const Box& over, double cell, double margin, const std::string& what)
{
  return gridOver(over.min, over.max, cell, margin, what);
}

} // namespace pbf
