#include "SignedDistance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

namespace pbf
{
namespace
{

constexpr double kPi = 3.14159265358979323846;
// 2^27 nodes is 512 MiB of floats: beyond that the resolution, not the solid, is wrong.
constexpr double kMostNodes = 134217728.0;

std::string format(const Vec3d& v)
{
  std::ostringstream out;
  out << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return out.str();
}

bool finite(const Vec3d& v)
{
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

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

// Runs f(i, j, k) for every node, the z-slices split over threads.
template <class F>
void forEachNode(DistanceGrid& g, F&& f)
{
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < g.nz; ++k)
  {
    for (int j = 0; j < g.ny; ++j)
    {
      for (int i = 0; i < g.nx; ++i)
      {
        g.node(i, j, k) = static_cast<float>(f(g.nodePosition(i, j, k)));
      }
    }
  }
}

// Squared distance from p to the triangle abc: the closest point by the triangle's Voronoi
// regions (Ericson, Real-Time Collision Detection, 5.1.5).
double squaredDistanceToTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c)
{
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  auto squared = [&](const Vec3d& q) { return dot(p - q, p - q); };
  if (d1 <= 0 && d2 <= 0)
  {
    return squared(a);
  }
  const Vec3d bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3)
  {
    return squared(b);
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
  {
    return squared(a + ab * (d1 / (d1 - d3)));
  }
  const Vec3d cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6)
  {
    return squared(c);
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
  {
    return squared(a + ac * (d2 / (d2 - d6)));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
  {
    return squared(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
  }
  const double denominator = 1.0 / (va + vb + vc);
  return squared(a + ab * (vb * denominator) + ac * (vc * denominator));
}

// The solid angle of triangle abc seen from p, signed by its orientation (Van Oosterom and
// Strackee 1983); over a closed surface they sum to 4 pi inside and 0 outside.
double solidAngle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c)
{
  const Vec3d x = a - p, y = b - p, z = c - p;
  const double lx = length(x), ly = length(y), lz = length(z);
  const double numerator = dot(x, cross(y, z));
  const double denominator = lx * ly * lz + dot(x, y) * lz + dot(x, z) * ly + dot(y, z) * lx;
  return 2.0 * std::atan2(numerator, denominator);
}

void checkMesh(const TriangleMesh& mesh, double thickness, const std::string& what)
{
  if (mesh.triangles.empty())
  {
    throw InvalidInput(what + ": the surface has no triangles (an empty solid)");
  }
  for (std::size_t i = 0; i < mesh.points.size(); ++i)
  {
    if (!finite(mesh.points[i]))
    {
      throw InvalidInput(
        what + ": point " + std::to_string(i) + " = " + format(mesh.points[i]) + ": must be finite");
    }
  }
  if (!(thickness >= 0) || !std::isfinite(thickness))
  {
    std::ostringstream text;
    text << what << ": thickness = " << thickness << ": must be >= 0";
    throw InvalidInput(text.str());
  }
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
  {
    const auto& v = mesh.triangles[t];
    for (int e = 0; e < 3; ++e)
    {
      if (v[e] >= mesh.points.size())
      {
        throw InvalidInput(what + ": triangle " + std::to_string(t) + " names point " +
          std::to_string(v[e]) + " of " + std::to_string(mesh.points.size()));
      }
      const std::uint32_t a = v[e], b = v[(e + 1) % 3];
      ++edges[{ std::min(a, b), std::max(a, b) }];
    }
  }
  if (thickness > 0)
  {
    return; // a shell needs no inside
  }
  for (const auto& edge : edges)
  {
    if (edge.second != 2)
    {
      throw InvalidInput(what + ": the surface is not closed: the edge between points " +
        std::to_string(edge.first.first) + " and " + std::to_string(edge.first.second) +
        " belongs to " + std::to_string(edge.second) +
        " triangles, not 2. Close the surface (Fill Holes), or give it a thickness to make it a "
        "thin shell");
    }
  }
}

} // namespace

double DistanceGrid::at(const Vec3d& x) const
{
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

DistanceGrid meshDistance(const TriangleMesh& mesh, double cell, double margin, double thickness,
  const std::string& what)
{
  checkMesh(mesh, thickness, what);
  Vec3d lo = mesh.points[mesh.triangles[0][0]], hi = lo;
  for (const auto& t : mesh.triangles)
  {
    for (std::uint32_t v : t)
    {
      const Vec3d& p = mesh.points[v];
      lo = Vec3d{ std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z) };
      hi = Vec3d{ std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z) };
    }
  }
  DistanceGrid g = gridOver(lo, hi, cell, margin + 0.5 * thickness, what);
  forEachNode(g, [&](const Vec3d& p) {
    double nearest2 = std::numeric_limits<double>::infinity();
    double angle = 0;
    for (const auto& t : mesh.triangles)
    {
      const Vec3d &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
      nearest2 = std::min(nearest2, squaredDistanceToTriangle(p, a, b, c));
      if (thickness == 0)
      {
        angle += solidAngle(p, a, b, c);
      }
    }
    const double distance = std::sqrt(nearest2);
    if (thickness > 0)
    {
      return distance - 0.5 * thickness;
    }
    const bool inside = std::abs(angle / (4 * kPi)) > 0.5;
    return inside ? -distance : distance;
  });
  return g;
}

DistanceGrid sphereDistance(const Vec3d& centre, double radius, double cell, double margin)
{
  if (!(radius > 0) || !std::isfinite(radius) || !finite(centre))
  {
    std::ostringstream text;
    text << "sphere at " << format(centre) << ", radius = " << radius
         << ": needs a finite centre and a radius > 0";
    throw InvalidInput(text.str());
  }
  const Vec3d r{ radius, radius, radius };
  DistanceGrid g = gridOver(centre - r, centre + r, cell, margin, "sphere");
  forEachNode(g, [&](const Vec3d& p) { return length(p - centre) - radius; });
  return g;
}

DistanceGrid boxDistance(const Box& box, double cell, double margin)
{
  if (!finite(box.min) || !finite(box.max) || !(box.min.x < box.max.x) ||
    !(box.min.y < box.max.y) || !(box.min.z < box.max.z))
  {
    throw InvalidInput("box " + format(box.min) + " - " + format(box.max) +
      ": needs finite corners with min < max on every axis");
  }
  return boxDistanceOn(box, gridOver(box.min, box.max, cell, margin, "box"));
}

DistanceGrid boxDistanceOn(const Box& box, DistanceGrid grid)
{
  const Vec3d centre = (box.min + box.max) * 0.5, half = (box.max - box.min) * 0.5;
  forEachNode(grid, [&](const Vec3d& p) {
    // Outside: the distance to the box; inside: minus the distance to the nearest face.
    const Vec3d q{ std::abs(p.x - centre.x) - half.x, std::abs(p.y - centre.y) - half.y,
      std::abs(p.z - centre.z) - half.z };
    const Vec3d out{ std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0) };
    return length(out) + std::min(std::max({ q.x, q.y, q.z }), 0.0);
  });
  return grid;
}

DistanceGrid gridOver(const Box& over, double cell, double margin, const std::string& what)
{
  return gridOver(over.min, over.max, cell, margin, what);
}

} // namespace pbf
