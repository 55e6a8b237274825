// The signed distance of a triangle mesh (SignedDistance.h: meshDistance), in three passes whose
// cost grows with the surface, not with nodes x triangles:
// 1. the exact distance at the nodes within `band` of each triangle (the band the boundary and
//    the collision read), each triangle visiting only the nodes of its padded bounds;
// 2. beyond the band, a chamfer distance transform (two sweeps, 26 neighbours) carries the band's
//    values on: an upper bound that keeps growing away from the surface, so that a particle found
//    deep inside is still pushed towards the nearest face;
// 3. the sign from rays along x through every row of nodes: a node is inside when an odd number
//    of triangles cross its row before it. Edge functions are evaluated once per edge in one
//    orientation (lower point index first) and a point on an edge belongs to exactly one of the two
//    triangles sharing it (the rasterizers' top-left rule), so a ray through an edge or a vertex
//    of a closed mesh counts one crossing, or none or two where it grazes a silhouette.
#include "SignedDistance.h"

#include "PointText.h"

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

// The point of the triangle abc closest to p, by the triangle's Voronoi regions (Ericson,
// Real-Time Collision Detection, 5.1.5).
Vec3d closestOnTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c)
{
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0)
  {
    return a;
  }
  const Vec3d bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3)
  {
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
  {
    return a + ab * (d1 / (d1 - d3));
  }
  const Vec3d cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6)
  {
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
  {
    return a + ac * (d2 / (d2 - d6));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
  {
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denominator = 1.0 / (va + vb + vc);
  return a + ab * (vb * denominator) + ac * (vc * denominator);
}

// The nodes [first, last] along one axis whose coordinates lie in [lo, hi], clamped to the grid.
std::pair<int, int> nodeRange(double lo, double hi, double origin, double cell, int n)
{
  const double first = std::ceil((lo - origin) / cell), last = std::floor((hi - origin) / cell);
  return { static_cast<int>(std::max(first, 0.0)),
    static_cast<int>(std::min(last, static_cast<double>(n - 1))) };
}

// A node this share of a cell from its nearest surface point lies on the surface, for its normal:
// the nearest point of a face through the node is off by rounding (1e-16 m on a 1 m mesh).
constexpr double kOnSurface = 1e-6;

// Pass 1: |distance| at the nodes within `band` of a triangle (the others stay infinite), and
// `away`, the unit direction from each such node's nearest surface point to the node (zero beyond
// the band and where the node lies on the surface: closer than kOnSurface cells, where the offset
// is the rounding of the nearest point, whose direction can lie in the face).
std::vector<double> bandDistance(
  const TriangleMesh& mesh, const DistanceGrid& g, double band, std::vector<Vec3d>& away)
{
  std::vector<double> d2(g.phi.size(), std::numeric_limits<double>::infinity());
  away.assign(g.phi.size(), Vec3d{ 0, 0, 0 });
  struct Reach
  {
    std::pair<int, int> i, j, k;
  };
  std::vector<Reach> reach(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
  {
    const auto& v = mesh.triangles[t];
    const Vec3d &a = mesh.points[v[0]], &b = mesh.points[v[1]], &c = mesh.points[v[2]];
    auto range = [&](double Vec3d::*axis, double origin, int n) {
      return nodeRange(std::min({ a.*axis, b.*axis, c.*axis }) - band,
        std::max({ a.*axis, b.*axis, c.*axis }) + band, origin, g.cell, n);
    };
    reach[t] = { range(&Vec3d::x, g.origin.x, g.nx), range(&Vec3d::y, g.origin.y, g.ny),
      range(&Vec3d::z, g.origin.z, g.nz) };
  }
  const double onSurface2 = (kOnSurface * g.cell) * (kOnSurface * g.cell);
  // One z-slice per thread: every node is written by one thread only.
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < g.nz; ++k)
  {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    {
      const Reach& r = reach[t];
      if (k < r.k.first || k > r.k.second)
      {
        continue;
      }
      const auto& v = mesh.triangles[t];
      const Vec3d &a = mesh.points[v[0]], &b = mesh.points[v[1]], &c = mesh.points[v[2]];
      for (int j = r.j.first; j <= r.j.second; ++j)
      {
        for (int i = r.i.first; i <= r.i.second; ++i)
        {
          const Vec3d x = g.nodePosition(i, j, k);
          const Vec3d offset = x - closestOnTriangle(x, a, b, c);
          const double squared = dot(offset, offset);
          const std::size_t n = g.index(i, j, k);
          if (squared < d2[n])
          {
            d2[n] = squared;
            away[n] = squared > onSurface2 ? offset * (1.0 / std::sqrt(squared)) : Vec3d{ 0, 0, 0 };
          }
        }
      }
    }
  }
  const double band2 = band * band;
  for (std::size_t n = 0; n < d2.size(); ++n)
  {
    const bool near = d2[n] <= band2;
    d2[n] = near ? std::sqrt(d2[n]) : std::numeric_limits<double>::infinity();
    away[n] = near ? away[n] : Vec3d{ 0, 0, 0 };
  }
  return d2;
}

// The unit gradient of phi at node (i, j, k) by central differences (one-sided at the grid's
// faces): the normal of a node that lies on the surface or beyond the band, where no nearest
// point gives one; (0, 0, 0) where phi is flat there.
Vec3d differenceNormal(const DistanceGrid& g, int i, int j, int k)
{
  const int at[3] = { i, j, k }, n[3] = { g.nx, g.ny, g.nz };
  double gradient[3];
  for (int a = 0; a < 3; ++a)
  {
    int lo[3] = { i, j, k }, hi[3] = { i, j, k };
    lo[a] = std::max(at[a] - 1, 0);
    hi[a] = std::min(at[a] + 1, n[a] - 1);
    gradient[a] = hi[a] > lo[a]
      ? (double(g.node(hi[0], hi[1], hi[2])) - g.node(lo[0], lo[1], lo[2])) / (hi[a] - lo[a])
      : 0.0;
  }
  const Vec3d v{ gradient[0], gradient[1], gradient[2] };
  const double size = length(v);
  return size > 0 ? v * (1.0 / size) : Vec3d{ 0, 0, 0 };
}

// Pass 2: the chamfer transform over the nodes the band left infinite (Borgefors 1984, with
// the 26-neighbour weights 1, sqrt 2, sqrt 3 cells): a forward and a backward sweep.
void chamfer(std::vector<double>& d, const DistanceGrid& g)
{
  struct Step
  {
    int di, dj, dk;
    double w;
  };
  std::vector<Step> before; // the 13 neighbours that precede a node in x-fastest order
  for (int dk = -1; dk <= 0; ++dk)
  {
    for (int dj = -1; dj <= 1; ++dj)
    {
      for (int di = -1; di <= 1; ++di)
      {
        if (dk < 0 || dj < 0 || (dj == 0 && di < 0))
        {
          before.push_back({ di, dj, dk, g.cell * std::sqrt(double(di * di + dj * dj + dk * dk)) });
        }
      }
    }
  }
  auto sweep = [&](int sign) {
    const int k0 = sign > 0 ? 0 : g.nz - 1, j0 = sign > 0 ? 0 : g.ny - 1;
    const int i0 = sign > 0 ? 0 : g.nx - 1;
    for (int k = k0; k >= 0 && k < g.nz; k += sign)
    {
      for (int j = j0; j >= 0 && j < g.ny; j += sign)
      {
        for (int i = i0; i >= 0 && i < g.nx; i += sign)
        {
          double& here = d[g.index(i, j, k)];
          for (const Step& s : before)
          {
            const int a = i + sign * s.di, b = j + sign * s.dj, c = k + sign * s.dk;
            if (a >= 0 && a < g.nx && b >= 0 && b < g.ny && c >= 0 && c < g.nz)
            {
              here = std::min(here, d[g.index(a, b, c)] + s.w);
            }
          }
        }
      }
    }
  };
  sweep(+1);
  sweep(-1);
}

// Pass 3: inside (true) or outside, per node, from the crossings of rows along x.
std::vector<char> insideByRays(const TriangleMesh& mesh, const DistanceGrid& g)
{
  // A triangle's edge, as the rows see it: (y, z) of its lower-index end and its direction.
  auto edge = [&](std::uint32_t u, std::uint32_t w, double y, double z) {
    const bool forward = u < w;
    const Vec3d& p = mesh.points[forward ? u : w];
    const Vec3d& q = mesh.points[forward ? w : u];
    // The same bits for both triangles of an edge, negated for the one that runs it backwards.
    const double e = (q.y - p.y) * (z - p.z) - (q.z - p.z) * (y - p.y);
    return forward ? e : -e;
  };
  // Of two triangles that meet at an edge from opposite sides, the rule claims it for one.
  auto claims = [&](std::uint32_t u, std::uint32_t w) {
    const Vec3d d = mesh.points[w] - mesh.points[u];
    return d.z < 0 || (d.z == 0 && d.y > 0);
  };
  std::vector<char> inside(g.phi.size(), 0);
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < g.nz; ++k)
  {
    const double z = g.origin.z + k * g.cell;
    std::vector<std::vector<double>> crossings(static_cast<std::size_t>(g.ny));
    for (const auto& t : mesh.triangles)
    {
      const Vec3d &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
      if (z < std::min({ a.z, b.z, c.z }) || z > std::max({ a.z, b.z, c.z }))
      {
        continue;
      }
      const std::pair<int, int> rows = nodeRange(std::min({ a.y, b.y, c.y }),
        std::max({ a.y, b.y, c.y }), g.origin.y, g.cell, g.ny);
      for (int j = rows.first; j <= rows.second; ++j)
      {
        const double y = g.origin.y + j * g.cell;
        // Edge functions, made positive inside by the projected triangle's orientation.
        double e[3] = { edge(t[1], t[2], y, z), edge(t[2], t[0], y, z), edge(t[0], t[1], y, z) };
        const double area = e[0] + e[1] + e[2];
        if (area == 0)
        {
          continue; // seen edge-on: its neighbours carry the crossing
        }
        const double orientation = area > 0 ? 1.0 : -1.0;
        bool in = true;
        for (int m = 0; m < 3 && in; ++m)
        {
          const double value = e[m] * orientation;
          const std::uint32_t u = t[(m + 1) % 3], w = t[(m + 2) % 3];
          in = value > 0 || (value == 0 && (orientation > 0 ? claims(u, w) : claims(w, u)));
        }
        if (in)
        {
          const double x = (e[0] * a.x + e[1] * b.x + e[2] * c.x) / area;
          crossings[static_cast<std::size_t>(j)].push_back(x);
        }
      }
    }
    for (int j = 0; j < g.ny; ++j)
    {
      std::vector<double>& row = crossings[static_cast<std::size_t>(j)];
      std::sort(row.begin(), row.end());
      std::size_t passed = 0;
      for (int i = 0; i < g.nx; ++i)
      {
        const double x = g.origin.x + i * g.cell;
        while (passed < row.size() && row[passed] < x)
        {
          ++passed;
        }
        inside[g.index(i, j, k)] = static_cast<char>(passed % 2);
      }
    }
  }
  return inside;
}

} // namespace

Box meshBounds(const TriangleMesh& mesh, double thickness, const std::string& what)
{
  if (mesh.triangles.empty())
  {
    throw InvalidInput(what + ": the surface has no triangles (an empty solid)");
  }
  for (std::size_t i = 0; i < mesh.points.size(); ++i)
  {
    const Vec3d& p = mesh.points[i];
    if (!isFinite(p))
    {
      throw InvalidInput(
        what + ": point " + std::to_string(i) + " = " + pointText(p) + ": must be finite");
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
  Box bounds{ mesh.points[mesh.triangles[0][0]], mesh.points[mesh.triangles[0][0]] };
  for (const auto& t : mesh.triangles)
  {
    for (std::uint32_t v : t)
    {
      const Vec3d& p = mesh.points[v];
      bounds.min = Vec3d{ std::min(bounds.min.x, p.x), std::min(bounds.min.y, p.y),
        std::min(bounds.min.z, p.z) };
      bounds.max = Vec3d{ std::max(bounds.max.x, p.x), std::max(bounds.max.y, p.y),
        std::max(bounds.max.z, p.z) };
    }
  }
  if (thickness > 0)
  {
    return bounds; // a shell needs no inside
  }
  // Closed: every edge has two triangles, or an even number where solids touch along it (the
  // outer surface of a tetrahedral mesh can have such edges); the rays' parity holds for both.
  for (const auto& edge : edges)
  {
    if (edge.second % 2 != 0)
    {
      throw InvalidInput(what + ": the surface is not closed: the edge between points " +
        std::to_string(edge.first.first) + " and " + std::to_string(edge.first.second) +
        " belongs to " + std::to_string(edge.second) +
        (edge.second == 1 ? " triangle" : " triangles") + ", not 2. Close the surface (Fill Holes), or give it a thickness to make it a thin shell");
    }
  }
  return bounds;
}

DistanceGrid meshDistance(const TriangleMesh& mesh, double cell, double margin, double thickness,
  const std::string& what, double band, const Box* within)
{
  const Box bounds = meshBounds(mesh, thickness, what);
  Vec3d lo = bounds.min, hi = bounds.max;
  if (!(band > 0))
  {
    std::ostringstream text;
    text << what << ": distance band = " << band << ": must be > 0";
    throw InvalidInput(text.str());
  }
  if (within)
  {
    lo = Vec3d{ std::max(lo.x, within->min.x), std::max(lo.y, within->min.y),
      std::max(lo.z, within->min.z) };
    hi = Vec3d{ std::min(hi.x, within->max.x), std::min(hi.y, within->max.y),
      std::min(hi.z, within->max.z) };
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z))
    {
      throw InvalidInput(what + ": lies outside the region its field is wanted in");
    }
  }
  DistanceGrid g = gridOver(Box{ lo, hi }, cell, margin + 0.5 * thickness, what);
  // A shell's surface lies thickness / 2 off the triangles: the band reaches past it.
  std::vector<Vec3d> away;
  std::vector<double> d = bandDistance(mesh, g, band + 0.5 * thickness, away);
  if (std::any_of(d.begin(), d.end(), [](double v) { return std::isinf(v); }))
  {
    chamfer(d, g);
  }
  const std::vector<char> inside = thickness > 0 ? std::vector<char>() : insideByRays(mesh, g);
  for (std::size_t n = 0; n < d.size(); ++n)
  {
    const double value = thickness > 0 ? d[n] - 0.5 * thickness : (inside[n] ? -d[n] : d[n]);
    g.phi[n] = static_cast<float>(value);
    // Outward: away from the surface outside (and from a shell's mid-surface), towards it inside.
    away[n] = (thickness == 0 && inside[n]) ? away[n] * -1.0 : away[n];
  }
  g.normal.assign(3 * d.size(), 0.0f);
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < g.nz; ++k)
  {
    for (int j = 0; j < g.ny; ++j)
    {
      for (int i = 0; i < g.nx; ++i)
      {
        const std::size_t n = g.index(i, j, k);
        const Vec3d normal = dot(away[n], away[n]) > 0 ? away[n] : differenceNormal(g, i, j, k);
        g.normal[3 * n] = static_cast<float>(normal.x);
        g.normal[3 * n + 1] = static_cast<float>(normal.y);
        g.normal[3 * n + 2] = static_cast<float>(normal.z);
      }
    }
  }
  return g;
}

} // namespace pbf
