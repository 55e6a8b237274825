#include "SurfaceExtraction.h"

#include "CellSort.h"
#include "Grid.h"
#include "Kernels.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace pbf
{

namespace
{

constexpr int kBlock = 8; // cells per block edge; a block samples (kBlock + 1)^3 nodes

std::string number(double v)
{
  std::ostringstream out;
  out << v;
  return out.str();
}

// The sampling grid: node (i, j, k) at origin + (i, j, k) cell, computed by this one expression
// wherever it is needed, so that a node shared by two blocks has the same bits in both.
struct NodeGrid
{
  Vec3d origin;
  double cell = 0;
  std::int64_t n[3] = { 0, 0, 0 };   // nodes per axis
  std::int64_t blocks[3] = { 0, 0, 0 };

  Vec3d at(std::int64_t i, std::int64_t j, std::int64_t k) const
  {
    return origin + Vec3d{ static_cast<double>(i) * cell, static_cast<double>(j) * cell,
                      static_cast<double>(k) * cell };
  }
  std::uint64_t id(std::int64_t i, std::int64_t j, std::int64_t k) const
  {
    return static_cast<std::uint64_t>((k * n[1] + j) * n[0] + i);
  }
};

// The particles sorted into cells of h over the sampled region, in double.
struct SortedParticles
{
  GridGeometry<double> geometry;
  std::vector<std::uint32_t> offsets;
  std::vector<Vec3d> x;
  std::vector<std::uint32_t> order; // sorted index -> input index
};

// Calls visit(j) for the sorted particles of the 27 cells around q's cell, in a fixed order.
template <class Visit>
void forEachParticleNear(const SortedParticles& p, const Vec3d& q, Visit&& visit)
{
  const GridGeometry<double>& g = p.geometry;
  const int cx = g.clampedCell(q.x, g.origin.x, g.nx);
  const int cy = g.clampedCell(q.y, g.origin.y, g.ny);
  const int cz = g.clampedCell(q.z, g.origin.z, g.nz);
  const int x0 = std::max(cx - 1, 0), x1 = std::min(cx + 1, g.nx - 1);
  for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, g.nz - 1); ++z)
  {
    for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, g.ny - 1); ++y)
    {
      const std::size_t row = (static_cast<std::size_t>(z) * g.ny + y) * g.nx;
      for (std::uint32_t j = p.offsets[row + x0]; j < p.offsets[row + x1 + 1]; ++j)
      {
        visit(j);
      }
    }
  }
}

struct EdgeVertex
{
  std::uint64_t key; // lower node's id x 8 + the edge's direction (bits x, y, z)
  Vec3d position;
};

struct BlockResult
{
  std::vector<EdgeVertex> vertices;
  std::vector<std::array<std::uint64_t, 3>> triangles; // vertex keys
  bool sampled = false;
};

// Kuhn's six tetrahedra of a cell, as corner bits (x 1, y 2, z 4): 0, a, a | b, 7 for every
// order of the axes. Along each tetrahedron's corners the bits only grow, so of two corners the
// earlier is the edge's lower end.
constexpr int kTetrahedra[6][4] = { { 0, 1, 3, 7 }, { 0, 1, 5, 7 }, { 0, 2, 3, 7 }, { 0, 2, 6, 7 },
  { 0, 4, 5, 7 }, { 0, 4, 6, 7 } };

class Extractor
{
public:
  Extractor(const NodeGrid& grid, const SortedParticles& particles, const Kernels<double>& kernels,
    double volume, double iso)
    : grid_(grid)
    , particles_(particles)
    , kernels_(kernels)
    , volume_(volume)
    , iso_(iso)
  {
  }

  double colour(const Vec3d& q) const
  {
    double phi = 0;
    forEachParticleNear(particles_, q, [&](std::uint32_t j) {
      const Vec3d r = q - particles_.x[j];
      phi += kernels_.poly6(dot(r, r));
    });
    return phi * volume_;
  }

  // Block (bx, by, bz): its nodes sampled and its cells triangulated.
  void run(std::int64_t bx, std::int64_t by, std::int64_t bz, BlockResult& out) const
  {
    constexpr int m = kBlock + 1;
    std::vector<double> phi(static_cast<std::size_t>(m * m * m), 0.0);
    const std::int64_t base[3] = { bx * kBlock, by * kBlock, bz * kBlock };
    bool any = false, all = true;
    for (int k = 0; k < m; ++k)
    {
      for (int j = 0; j < m; ++j)
      {
        for (int i = 0; i < m; ++i)
        {
          const std::int64_t g[3] = { base[0] + i, base[1] + j, base[2] + k };
          double value = 0; // beyond the grid: outside, as the padding is
          if (g[0] < grid_.n[0] && g[1] < grid_.n[1] && g[2] < grid_.n[2])
          {
            value = colour(grid_.at(g[0], g[1], g[2]));
          }
          phi[static_cast<std::size_t>((k * m + j) * m + i)] = value;
          any = any || value > iso_;
          all = all && value > iso_;
        }
      }
    }
    out.sampled = true;
    if (!any || all)
    {
      return; // the level does not pass through this block
    }
    for (int k = 0; k < kBlock; ++k)
    {
      for (int j = 0; j < kBlock; ++j)
      {
        for (int i = 0; i < kBlock; ++i)
        {
          if (base[0] + i + 1 >= grid_.n[0] || base[1] + j + 1 >= grid_.n[1] ||
            base[2] + k + 1 >= grid_.n[2])
          {
            continue;
          }
          double corner[8];
          int inside = 0;
          for (int c = 0; c < 8; ++c)
          {
            corner[c] = phi[static_cast<std::size_t>(
              ((k + (c >> 2)) * m + (j + ((c >> 1) & 1))) * m + (i + (c & 1)))];
            inside += corner[c] > iso_ ? 1 : 0;
          }
          if (inside == 0 || inside == 8)
          {
            continue;
          }
          cell(base[0] + i, base[1] + j, base[2] + k, corner, out);
        }
      }
    }
  }

private:
  // The vertex on the edge from corner u to corner v (u's bits a subset of v's) of cell (i, j, k).
  EdgeVertex vertex(std::int64_t i, std::int64_t j, std::int64_t k, int u, int v,
    const double* corner) const
  {
    const std::int64_t ui = i + (u & 1), uj = j + ((u >> 1) & 1), uk = k + (u >> 2);
    const std::int64_t vi = i + (v & 1), vj = j + ((v >> 1) & 1), vk = k + (v >> 2);
    const Vec3d a = grid_.at(ui, uj, uk), b = grid_.at(vi, vj, vk);
    const double t = (iso_ - corner[u]) / (corner[v] - corner[u]);
    return { grid_.id(ui, uj, uk) * 8 + static_cast<std::uint64_t>(v & ~u), a + (b - a) * t };
  }

  void triangle(EdgeVertex a, EdgeVertex b, EdgeVertex c, const Vec3d& outward, BlockResult& out) const
  {
    const Vec3d n = cross(b.position - a.position, c.position - a.position);
    if (dot(n, outward) < 0)
    {
      std::swap(b, c);
    }
    out.vertices.push_back(a);
    out.vertices.push_back(b);
    out.vertices.push_back(c);
    out.triangles.push_back({ a.key, b.key, c.key });
  }

  void cell(std::int64_t i, std::int64_t j, std::int64_t k, const double* corner, BlockResult& out) const
  {
    for (const auto& tet : kTetrahedra)
    {
      int in[4], outside[4], nin = 0, nout = 0;
      for (int c = 0; c < 4; ++c)
      {
        if (corner[tet[c]] > iso_)
        {
          in[nin++] = c;
        }
        else
        {
          outside[nout++] = c;
        }
      }
      if (nin == 0 || nout == 0)
      {
        continue;
      }
      // From the inside corners' centre to the outside ones': the way the normal must face.
      auto centre = [&](const int* list, int count) {
        Vec3d sum{ 0, 0, 0 };
        for (int q = 0; q < count; ++q)
        {
          const int b = tet[list[q]];
          sum += grid_.at(i + (b & 1), j + ((b >> 1) & 1), k + (b >> 2));
        }
        return sum * (1.0 / count);
      };
      const Vec3d outward = centre(outside, nout) - centre(in, nin);
      // The edge between tetrahedron corners p and q, lower bits first.
      auto edge = [&](int p, int q) {
        const int a = std::min(p, q), b = std::max(p, q); // corner order is bit order here
        return vertex(i, j, k, tet[a], tet[b], corner);
      };
      if (nin == 1 || nout == 1)
      {
        const int lone = nin == 1 ? in[0] : outside[0];
        const int* others = nin == 1 ? outside : in;
        triangle(edge(lone, others[0]), edge(lone, others[1]), edge(lone, others[2]), outward, out);
      }
      else
      {
        // Two in, two out: the quad through the four crossing edges, in cyclic order.
        const EdgeVertex ac = edge(in[0], outside[0]), ad = edge(in[0], outside[1]);
        const EdgeVertex bd = edge(in[1], outside[1]), bc = edge(in[1], outside[0]);
        triangle(ac, ad, bd, outward, out);
        triangle(ac, bd, bc, outward, out);
      }
    }
  }

  const NodeGrid& grid_;
  const SortedParticles& particles_;
  const Kernels<double>& kernels_;
  double volume_;
  double iso_;
};

} // namespace

void SurfaceOptions::validate() const
{
  if (!(resolution > 0 && resolution <= 4))
  {
    throw InvalidInput("SurfaceResolution = " + number(resolution) +
      ": must be in (0, 4] (node spacing in particle spacings)");
  }
  if (!(isoValue > 0 && isoValue < 1))
  {
    throw InvalidInput("SurfaceIsoValue = " + number(isoValue) +
      ": must be in (0, 1) (the colour function's level)");
  }
  if (smoothing < 0 || smoothing > 100)
  {
    throw InvalidInput("SurfaceSmoothing = " + std::to_string(smoothing) + ": must be in 0..100");
  }
}

double surfaceGhostReach(const Parameters& p, const SurfaceOptions& options)
{
  // A share's blocks reach one block beyond its slab, and a node there sums particles within h
  // (the cells of h around it: one more h).
  const double cell = options.resolution * p.particleSpacing;
  return kBlock * cell + 2 * p.smoothingLength();
}

template <class Real>
SurfaceMesh extractSurface(const Vec3<Real>* x, const Vec3<Real>* v, const Real* rho,
  std::size_t n, const Parameters& p, const SurfaceOptions& options, bool parallel,
  const SurfaceShare& share)
{
  options.validate();
  SurfaceMesh mesh;
  if (n == 0)
  {
    return mesh;
  }
  const double h = p.smoothingLength();
  const Kernels<double> kernels = Kernels<double>::make(h);
  const double volume = calibratedParticleMass(p) / p.restDensity;

  // The sampled region: the domain (where the particles are) padded by h and two nodes, so that
  // the colour is below any level at the grid's faces and the surface closes inside it. Anchored
  // at the domain, it is the same grid on every rank of a decomposed run.
  // (A particle a rounding beyond a wall is still well inside the padding.)
  const Vec3d lo = p.domain.min, hi = p.domain.max;
  for (std::size_t i = 0; i < n; ++i)
  {
    const Vec3d q = Vec3d::from(x[i]);
    if (!std::isfinite(q.x + q.y + q.z))
    {
      throw InvalidInput("surface: particle " + std::to_string(i) + " has a non-finite position");
    }
  }
  NodeGrid grid;
  grid.cell = options.resolution * p.particleSpacing;
  const double pad = h + 2 * grid.cell;
  grid.origin = lo - Vec3d{ pad, pad, pad };
  const Vec3d size = hi - lo + Vec3d{ 2 * pad, 2 * pad, 2 * pad };
  const double extent[3] = { size.x, size.y, size.z };
  double total = 1;
  for (int a = 0; a < 3; ++a)
  {
    grid.n[a] = static_cast<std::int64_t>(std::ceil(extent[a] / grid.cell)) + 1;
    grid.blocks[a] = (grid.n[a] - 1 + kBlock - 1) / kBlock;
    total *= static_cast<double>(grid.n[a]);
  }
  if (total > 1e15)
  {
    throw InvalidInput("SurfaceResolution = " + number(options.resolution) + ": " + number(total) +
      " nodes over the particles' bounds; coarsen the surface");
  }

  // The particles in cells of h over the same region (Green 2008, as the solver's grid).
  SortedParticles sorted;
  sorted.geometry = makeGridGeometry<double>(Box{ grid.origin, grid.origin + size }, h);
  std::vector<CellKey> keys(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    keys[i] = sorted.geometry.keyOf(Vec3d::from(x[i]));
  }
  std::vector<std::uint32_t> cursor;
  sorted.offsets.resize(static_cast<std::size_t>(sorted.geometry.cellCount()) + 1);
  countingSortByCell(keys, sorted.offsets, sorted.order, cursor);
  // Within a cell, by position: the sums over a cell's particles then have one order whatever
  // order the particles came in (a rank's own and its ghosts).
  for (std::size_t c = 0; c + 1 < sorted.offsets.size(); ++c)
  {
    std::sort(sorted.order.begin() + sorted.offsets[c], sorted.order.begin() + sorted.offsets[c + 1],
      [&](std::uint32_t a, std::uint32_t b) {
        const Vec3<Real>& pa = x[a];
        const Vec3<Real>& pb = x[b];
        if (pa.x != pb.x)
        {
          return pa.x < pb.x;
        }
        if (pa.y != pb.y)
        {
          return pa.y < pb.y;
        }
        return pa.z != pb.z ? pa.z < pb.z : a < b;
      });
  }
  sorted.x.resize(n);
  for (std::size_t k = 0; k < n; ++k)
  {
    sorted.x[k] = Vec3d::from(x[sorted.order[k]]);
  }

  // The blocks within h of a particle: a node within h of one belongs to every block it is in.
  std::vector<std::uint64_t> blockKeys;
  blockKeys.reserve(n * 2);
  const std::uint64_t bx = static_cast<std::uint64_t>(grid.blocks[0]);
  const std::uint64_t by = static_cast<std::uint64_t>(grid.blocks[1]);
  for (std::size_t k = 0; k < n; ++k)
  {
    const Vec3d q = sorted.x[k] - grid.origin;
    const double c[3] = { q.x, q.y, q.z };
    std::int64_t first[3], last[3];
    for (int a = 0; a < 3; ++a)
    {
      const auto i0 = static_cast<std::int64_t>(std::ceil((c[a] - h) / grid.cell));
      const auto i1 = static_cast<std::int64_t>(std::floor((c[a] + h) / grid.cell));
      first[a] = std::max<std::int64_t>(0, i0 > 0 ? (i0 - 1) / kBlock : 0);
      last[a] = std::min<std::int64_t>(grid.blocks[a] - 1, std::max<std::int64_t>(i1, 0) / kBlock);
    }
    for (std::int64_t z = first[2]; z <= last[2]; ++z)
    {
      for (std::int64_t y = first[1]; y <= last[1]; ++y)
      {
        for (std::int64_t b = first[0]; b <= last[0]; ++b)
        {
          // Only this share's blocks: those whose lower x lies in its range.
          const double blockX = grid.origin.x + static_cast<double>(b * kBlock) * grid.cell;
          if (!(blockX >= share.xMin && blockX < share.xMax))
          {
            continue;
          }
          blockKeys.push_back((static_cast<std::uint64_t>(z) * by + static_cast<std::uint64_t>(y)) * bx +
            static_cast<std::uint64_t>(b));
        }
      }
    }
  }
  std::sort(blockKeys.begin(), blockKeys.end());
  blockKeys.erase(std::unique(blockKeys.begin(), blockKeys.end()), blockKeys.end());

  const Extractor extractor(grid, sorted, kernels, volume, options.isoValue);
  std::vector<BlockResult> results(blockKeys.size());
  const auto count = static_cast<std::int64_t>(blockKeys.size());
#pragma omp parallel for schedule(dynamic, 8) if (parallel)
  for (std::int64_t b = 0; b < count; ++b)
  {
    const std::uint64_t key = blockKeys[static_cast<std::size_t>(b)];
    const auto b0 = static_cast<std::int64_t>(key % bx);
    const auto b1 = static_cast<std::int64_t>((key / bx) % by);
    const auto b2 = static_cast<std::int64_t>(key / (bx * by));
    extractor.run(b0, b1, b2, results[static_cast<std::size_t>(b)]);
  }

  // Vertices in key order, shared wherever their edge is.
  std::vector<EdgeVertex> vertices;
  std::size_t triangleCount = 0;
  for (const BlockResult& r : results)
  {
    vertices.insert(vertices.end(), r.vertices.begin(), r.vertices.end());
    triangleCount += r.triangles.size();
    mesh.sampledBlocks += r.sampled ? 1 : 0;
    mesh.keptBlocks += r.triangles.empty() ? 0 : 1;
  }
  mesh.sampledNodes = mesh.sampledBlocks * (kBlock + 1) * (kBlock + 1) * (kBlock + 1);
  // The working memory at its largest, here: the sorted particles, the block list, every block's
  // vertices (each edge's as often as cells share it) and triangles.
  mesh.peakBytes = n * (sizeof(Vec3d) + sizeof(CellKey) + 2 * sizeof(std::uint32_t)) +
    sorted.offsets.size() * sizeof(std::uint32_t) + blockKeys.size() * sizeof(std::uint64_t) +
    results.size() * sizeof(BlockResult) + 2 * vertices.size() * sizeof(EdgeVertex) +
    triangleCount * sizeof(std::array<std::uint64_t, 3>);
  std::stable_sort(vertices.begin(), vertices.end(),
    [](const EdgeVertex& a, const EdgeVertex& b) { return a.key < b.key; });
  vertices.erase(std::unique(vertices.begin(), vertices.end(),
                   [](const EdgeVertex& a, const EdgeVertex& b) { return a.key == b.key; }),
    vertices.end());
  auto indexOf = [&](std::uint64_t key) {
    const auto it = std::lower_bound(vertices.begin(), vertices.end(), key,
      [](const EdgeVertex& a, std::uint64_t k) { return a.key < k; });
    return static_cast<std::uint32_t>(it - vertices.begin());
  };
  mesh.triangles.reserve(triangleCount);
  for (const BlockResult& r : results)
  {
    for (const auto& t : r.triangles)
    {
      mesh.triangles.push_back({ indexOf(t[0]), indexOf(t[1]), indexOf(t[2]) });
    }
  }
  results.clear();
  results.shrink_to_fit();

  std::vector<Vec3d> position(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i)
  {
    position[i] = vertices[i].position;
  }
  // Laplacian smoothing: each vertex halfway to the mean of its neighbours, all at once.
  if (options.smoothing > 0)
  {
    std::vector<std::uint64_t> edges;
    edges.reserve(mesh.triangles.size() * 6);
    for (const auto& t : mesh.triangles)
    {
      for (int e = 0; e < 3; ++e)
      {
        const std::uint64_t a = t[e], b = t[(e + 1) % 3];
        edges.push_back(a << 32 | b);
        edges.push_back(b << 32 | a);
      }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    std::vector<Vec3d> next(position.size());
    for (int pass = 0; pass < options.smoothing; ++pass)
    {
      std::size_t e = 0;
      for (std::size_t i = 0; i < position.size(); ++i)
      {
        Vec3d sum{ 0, 0, 0 };
        int neighbours = 0;
        for (; e < edges.size() && (edges[e] >> 32) == i; ++e)
        {
          sum += position[edges[e] & 0xffffffffu];
          ++neighbours;
        }
        next[i] = neighbours ? position[i] + (sum * (1.0 / neighbours) - position[i]) * 0.5
                             : position[i];
      }
      position.swap(next);
    }
  }

  // Normals and the particles' fields at the vertices.
  const std::size_t m = position.size();
  mesh.points.resize(m);
  mesh.normals.resize(m);
  if (v)
  {
    mesh.velocity.resize(m);
  }
  if (rho)
  {
    mesh.density.resize(m);
  }
  const auto vertexCount = static_cast<std::int64_t>(m);
#pragma omp parallel for schedule(static) if (parallel)
  for (std::int64_t i = 0; i < vertexCount; ++i)
  {
    const Vec3d q = position[static_cast<std::size_t>(i)];
    double weight = 0, density = 0;
    Vec3d gradient{ 0, 0, 0 }, velocity{ 0, 0, 0 };
    forEachParticleNear(sorted, q, [&](std::uint32_t j) {
      const Vec3d r = q - sorted.x[j];
      const double r2 = dot(r, r);
      if (r2 < kernels.h2)
      {
        const double w = kernels.poly6Within(r2);
        const double d = kernels.h2 - r2;
        gradient += r * (-6.0 * kernels.poly6Scale * d * d);
        weight += w;
        const std::uint32_t original = sorted.order[j];
        if (v)
        {
          velocity += Vec3d::from(v[original]) * w;
        }
        if (rho)
        {
          density += static_cast<double>(rho[original]) * w;
        }
      }
    });
    const double g = length(gradient);
    const auto k = static_cast<std::size_t>(i);
    mesh.points[k] = Vec3<float>::from(q);
    mesh.normals[k] = g > 0 ? Vec3<float>::from(gradient * (-1.0 / g)) : Vec3<float>{ 0, 0, 0 };
    if (v)
    {
      mesh.velocity[k] = Vec3<float>::from(weight > 0 ? velocity * (1.0 / weight) : velocity);
    }
    if (rho)
    {
      mesh.density[k] = static_cast<float>(weight > 0 ? density / weight : 0.0);
    }
  }
  return mesh;
}

template SurfaceMesh extractSurface<float>(const Vec3<float>*, const Vec3<float>*, const float*,
  std::size_t, const Parameters&, const SurfaceOptions&, bool, const SurfaceShare&);
template SurfaceMesh extractSurface<double>(const Vec3<double>*, const Vec3<double>*,
  const double*, std::size_t, const Parameters&, const SurfaceOptions&, bool, const SurfaceShare&);

} // namespace pbf
