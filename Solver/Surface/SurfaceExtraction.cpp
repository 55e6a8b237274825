#include "SurfaceExtraction.h"

#include "CellSort.h"
#include "Grid.h"
#include "Kernels.h"
#include "SurfaceCells.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace pbf
{

namespace
{

using surface::kBlock;

std::string number(double v)
{
  std::ostringstream out;
  out << v;
  return out.str();
}

// The particles sorted into cells of h over the sampled region, in double.
struct SortedParticles
{
  GridGeometry<double> geometry;
  std::vector<std::uint32_t> offsets;
  std::vector<Vec3d> x;
  std::vector<std::uint32_t> order; // sorted index -> input index

  const double* m = nullptr; // anisotropic kernels' metrics, per sorted particle

  surface::CellParticles view() const { return { geometry, offsets.data(), x.data(), m }; }
};

// Points sorted into the cells of `geometry`, within a cell by position, ties by index: the sums
// over a cell's particles then have one order whatever order the particles came in (a rank's own
// and its ghosts).
SortedParticles sortedIntoCells(const std::vector<Vec3d>& points, const GridGeometry<double>& geometry)
{
  SortedParticles sorted;
  sorted.geometry = geometry;
  std::vector<CellKey> keys(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    keys[i] = geometry.keyOf(points[i]);
  }
  std::vector<std::uint32_t> cursor;
  sorted.offsets.resize(static_cast<std::size_t>(geometry.cellCount()) + 1);
  countingSortByCell(keys, sorted.offsets, sorted.order, cursor);
  for (std::size_t c = 0; c + 1 < sorted.offsets.size(); ++c)
  {
    std::sort(sorted.order.begin() + sorted.offsets[c], sorted.order.begin() + sorted.offsets[c + 1],
      [&](std::uint32_t a, std::uint32_t b) {
        const Vec3d& pa = points[a];
        const Vec3d& pb = points[b];
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
  sorted.x.resize(points.size());
  for (std::size_t k = 0; k < points.size(); ++k)
  {
    sorted.x[k] = points[sorted.order[k]];
  }
  return sorted;
}

struct KeyedVertex
{
  std::uint64_t key; // surface::vertexKey of its edge
  Vec3d position;
};

struct BlockResult
{
  std::vector<KeyedVertex> vertices;
  std::vector<std::array<std::uint64_t, 3>> triangles; // vertex keys
  bool sampled = false;
};

class Extractor
{
public:
  Extractor(const surface::NodeGrid& grid, const SortedParticles& particles,
    const Kernels<double>& kernels, double volume, double iso, const SurfaceSolids& solids)
    : grid_(grid)
    , particles_(particles.view())
    , kernels_(kernels)
    , volume_(volume)
    , iso_(iso)
    , solids_(solids)
  {
  }

  // Block (bx, by, bz): its nodes sampled and its cells triangulated.
  void run(std::int64_t bx, std::int64_t by, std::int64_t bz, BlockResult& out) const
  {
    constexpr int m = kBlock + 1;
    std::vector<double> phi(static_cast<std::size_t>(surface::kBlockNodes), 0.0);
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
            const Vec3d q = grid_.at(g[0], g[1], g[2]);
            value = surface::clipped(surface::colour(particles_, kernels_, volume_, q),
              solids_.views.data(), static_cast<int>(solids_.views.size()), q, iso_, 1.0 / grid_.cell);
          }
          phi[static_cast<std::size_t>(surface::nodeSlot(i, j, k))] = value;
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
    auto keyed = [&](const surface::EdgeVertex& e) {
      return KeyedVertex{ surface::vertexKey(grid_, e.node[0], e.node[1], e.node[2], e.dir),
        e.position };
    };
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
              surface::nodeSlot(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)))];
            inside += corner[c] > iso_ ? 1 : 0;
          }
          if (inside == 0 || inside == 8)
          {
            continue;
          }
          surface::triangulateCell(grid_, base[0] + i, base[1] + j, base[2] + k, corner, iso_,
            [&](const surface::EdgeVertex& a, const surface::EdgeVertex& b,
              const surface::EdgeVertex& c) {
              const KeyedVertex ka = keyed(a), kb = keyed(b), kc = keyed(c);
              out.vertices.push_back(ka);
              out.vertices.push_back(kb);
              out.vertices.push_back(kc);
              out.triangles.push_back({ ka.key, kb.key, kc.key });
            });
        }
      }
    }
  }

private:
  const surface::NodeGrid& grid_;
  surface::CellParticles particles_;
  const Kernels<double>& kernels_;
  double volume_;
  double iso_;
  const SurfaceSolids& solids_;
};

// The particles in cells of h over the node grid's region (Green 2008, as the solver's grid).
// With anisotropic kernels, each particle's centre and metric from its neighbours within h, then
// the particles sorted again, by their centres, into cells as wide as the kernels reach; the
// metrics go into `metric`, which the result points into.
SortedParticles sortParticles(const std::vector<Vec3d>& positions, const surface::NodeGrid& grid,
  const Parameters& p, const SurfaceOptions& options, bool parallel, std::vector<double>& metric)
{
  const double h = p.smoothingLength();
  const std::size_t n = positions.size();
  SortedParticles sorted = sortedIntoCells(positions, surface::particleCells(grid, p, h));
  if (!options.anisotropic)
  {
    return sorted;
  }
  const double fullCount = 4.0 / 3.0 * 3.14159265358979323846 * std::pow(p.smoothingRatio, 3);
  std::vector<surface::Anisotropy> shape(n);
  const auto count = static_cast<std::int64_t>(n);
  const surface::CellParticles around = sorted.view();
#pragma omp parallel for schedule(static) if (parallel)
  for (std::int64_t k = 0; k < count; ++k)
  {
    shape[static_cast<std::size_t>(k)] =
      surface::anisotropyOf(around, static_cast<std::uint32_t>(k), h, fullCount);
  }
  std::vector<Vec3d> centres(n);
  for (std::size_t k = 0; k < n; ++k)
  {
    centres[k] = shape[k].centre;
  }
  const double reach = surface::reachFactor(options) * h;
  SortedParticles bySorted = sortedIntoCells(centres, surface::particleCells(grid, p, reach));
  metric.resize(6 * n);
  for (std::size_t k = 0; k < n; ++k)
  {
    const std::uint32_t was = bySorted.order[k];
    std::copy(shape[was].m, shape[was].m + 6, metric.begin() + 6 * static_cast<std::ptrdiff_t>(k));
    bySorted.order[k] = sorted.order[was]; // to the input's index
  }
  bySorted.m = metric.data();
  return bySorted;
}

// The keys of the blocks within `reach` of a particle (a node within reach of one belongs to
// every block it is in), this share's only (those whose lower x lies in its range), sorted.
std::vector<std::uint64_t> blocksNear(const SortedParticles& sorted, const surface::NodeGrid& grid,
  double reach, const SurfaceShare& share)
{
  std::vector<std::uint64_t> blockKeys;
  blockKeys.reserve(sorted.x.size() * 2);
  for (const Vec3d& q : sorted.x)
  {
    std::int64_t first[3], last[3];
    surface::blocksNear(grid, reach, q, first, last);
    for (std::int64_t z = first[2]; z <= last[2]; ++z)
    {
      for (std::int64_t y = first[1]; y <= last[1]; ++y)
      {
        for (std::int64_t b = first[0]; b <= last[0]; ++b)
        {
          const double blockX = grid.origin.x + static_cast<double>(b * kBlock) * grid.cell;
          if (blockX >= share.xMin && blockX < share.xMax)
          {
            blockKeys.push_back(grid.blockKey(b, y, z));
          }
        }
      }
    }
  }
  std::sort(blockKeys.begin(), blockKeys.end());
  blockKeys.erase(std::unique(blockKeys.begin(), blockKeys.end()), blockKeys.end());
  return blockKeys;
}

// The blocks' results joined into the mesh's triangles, with vertices in key order shared wherever
// their edge is; returns the vertices' positions and fills the mesh's counts and peak memory.
std::vector<Vec3d> joinBlocks(std::vector<BlockResult>& results, const SortedParticles& sorted,
  std::size_t blocks, SurfaceMesh& mesh)
{
  std::vector<KeyedVertex> vertices;
  std::size_t triangleCount = 0;
  for (const BlockResult& r : results)
  {
    vertices.insert(vertices.end(), r.vertices.begin(), r.vertices.end());
    triangleCount += r.triangles.size();
    mesh.sampledBlocks += r.sampled ? 1 : 0;
    mesh.keptBlocks += r.triangles.empty() ? 0 : 1;
  }
  mesh.sampledNodes = mesh.sampledBlocks * surface::kBlockNodes;
  // The working memory at its largest, here: the sorted particles, the block list, every block's
  // vertices (each edge's as often as cells share it) and triangles.
  const std::size_t n = sorted.x.size();
  mesh.peakBytes = n * (sizeof(Vec3d) + sizeof(CellKey) + 2 * sizeof(std::uint32_t)) +
    sorted.offsets.size() * sizeof(std::uint32_t) + blocks * sizeof(std::uint64_t) +
    results.size() * sizeof(BlockResult) + 2 * vertices.size() * sizeof(KeyedVertex) +
    triangleCount * sizeof(std::array<std::uint64_t, 3>);
  std::stable_sort(vertices.begin(), vertices.end(),
    [](const KeyedVertex& a, const KeyedVertex& b) { return a.key < b.key; });
  vertices.erase(std::unique(vertices.begin(), vertices.end(),
                   [](const KeyedVertex& a, const KeyedVertex& b) { return a.key == b.key; }),
    vertices.end());
  auto indexOf = [&](std::uint64_t key) {
    const auto it = std::lower_bound(vertices.begin(), vertices.end(), key,
      [](const KeyedVertex& a, std::uint64_t k) { return a.key < k; });
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
  return position;
}

// Laplacian smoothing: each vertex halfway to the mean of its neighbours, all at once, `passes`
// times.
void smoothVertices(std::vector<Vec3d>& position,
  const std::vector<std::array<std::uint32_t, 3>>& triangles, int passes)
{
  if (passes <= 0)
  {
    return;
  }
  std::vector<std::uint64_t> edges;
  edges.reserve(triangles.size() * 6);
  for (const auto& t : triangles)
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
  std::vector<std::size_t> first(position.size() + 1, 0);
  for (const std::uint64_t e : edges)
  {
    ++first[(e >> 32) + 1];
  }
  for (std::size_t i = 0; i < position.size(); ++i)
  {
    first[i + 1] += first[i];
  }
  std::vector<Vec3d> next(position.size());
  for (int pass = 0; pass < passes; ++pass)
  {
    for (std::size_t i = 0; i < position.size(); ++i)
    {
      const std::uint64_t* around = edges.data() + first[i];
      next[i] = surface::smoothedPosition(position[i], static_cast<int>(first[i + 1] - first[i]),
        [&](int e) { return position[around[e] & 0xffffffffu]; });
    }
    position.swap(next);
  }
}

} // namespace

surface::NodeGrid surface::makeNodeGrid(const Parameters& p, const SurfaceOptions& options)
{
  // (A particle a rounding beyond a wall is still well inside the padding.)
  NodeGrid grid;
  grid.cell = options.resolution * p.particleSpacing;
  const double pad = surface::reachFactor(options) * p.smoothingLength() + 2 * grid.cell;
  grid.pad = pad;
  grid.origin = p.domain.min - Vec3d{ pad, pad, pad };
  const Vec3d size = p.domain.max - p.domain.min + Vec3d{ 2 * pad, 2 * pad, 2 * pad };
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
  return grid;
}

GridGeometry<double> surface::particleCells(const NodeGrid& grid, const Parameters& p, double cell)
{
  const Vec3d size = p.domain.max - p.domain.min + Vec3d{ 2 * grid.pad, 2 * grid.pad, 2 * grid.pad };
  return makeGridGeometry<double>(Box{ grid.origin, grid.origin + size }, cell);
}

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
  // Anisotropic kernels reach farther (their cells with them), their centres move by up to h, and
  // each one's shape needs its own neighbours within h.
  const double cell = options.resolution * p.particleSpacing;
  const double h = p.smoothingLength();
  return options.anisotropic ? kBlock * cell + 2 * surface::kAnisotropicReach * h + 2 * h
                             : kBlock * cell + 2 * h;
}

template <class Real>
SurfaceMesh extractSurface(const Vec3<Real>* x, const Vec3<Real>* v, const Real* rho,
  std::size_t n, const Parameters& p, const SurfaceOptions& options, bool parallel,
  const SurfaceShare& share, const SurfaceSolids& solids)
{
  options.validate();
  SurfaceMesh mesh;
  if (n == 0)
  {
    return mesh;
  }
  std::vector<Vec3d> positions(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    positions[i] = Vec3d::from(x[i]);
    if (!std::isfinite(positions[i].x + positions[i].y + positions[i].z))
    {
      throw InvalidInput("surface: particle " + std::to_string(i) + " has a non-finite position");
    }
  }
  const double h = p.smoothingLength();
  const Kernels<double> kernels = Kernels<double>::make(h);
  const double volume = calibratedParticleMass(p) / p.restDensity;
  const surface::NodeGrid grid = surface::makeNodeGrid(p, options);
  std::vector<double> metric; // the anisotropic kernels' metrics, which `sorted` points into
  const SortedParticles sorted = sortParticles(positions, grid, p, options, parallel, metric);
  const std::vector<std::uint64_t> blockKeys =
    blocksNear(sorted, grid, surface::reachFactor(options) * h, share);

  const Extractor extractor(grid, sorted, kernels, volume, options.isoValue, solids);
  std::vector<BlockResult> results(blockKeys.size());
  const auto count = static_cast<std::int64_t>(blockKeys.size());
#pragma omp parallel for schedule(dynamic, 8) if (parallel)
  for (std::int64_t b = 0; b < count; ++b)
  {
    std::int64_t at[3];
    grid.blockOf(blockKeys[static_cast<std::size_t>(b)], at);
    extractor.run(at[0], at[1], at[2], results[static_cast<std::size_t>(b)]);
  }
  std::vector<Vec3d> position = joinBlocks(results, sorted, blockKeys.size(), mesh);
  smoothVertices(position, mesh.triangles, options.smoothing);

  // Normals and the particles' fields at the vertices.
  const std::size_t m = position.size();
  mesh.points.resize(m);
  mesh.normals.resize(m);
  mesh.velocity.resize(v ? m : 0);
  mesh.density.resize(rho ? m : 0);
  const auto vertexCount = static_cast<std::int64_t>(m);
#pragma omp parallel for schedule(static) if (parallel)
  for (std::int64_t i = 0; i < vertexCount; ++i)
  {
    const auto k = static_cast<std::size_t>(i);
    const surface::VertexFields f = surface::vertexFields(sorted.view(), kernels, position[k],
      v != nullptr, rho != nullptr,
      [&](std::uint32_t j) { return Vec3d::from(v[sorted.order[j]]); },
      [&](std::uint32_t j) { return static_cast<double>(rho[sorted.order[j]]); }, volume,
      solids.views.data(), static_cast<int>(solids.views.size()), options.isoValue, 1.0 / grid.cell);
    mesh.points[k] = Vec3<float>::from(position[k]);
    mesh.normals[k] = f.normal;
    if (v)
    {
      mesh.velocity[k] = f.velocity;
    }
    if (rho)
    {
      mesh.density[k] = f.density;
    }
  }
  return mesh;
}

template SurfaceMesh extractSurface<float>(const Vec3<float>*, const Vec3<float>*, const float*,
  std::size_t, const Parameters&, const SurfaceOptions&, bool, const SurfaceShare&,
  const SurfaceSolids&);
template SurfaceMesh extractSurface<double>(const Vec3<double>*, const Vec3<double>*,
  const double*, std::size_t, const Parameters&, const SurfaceOptions&, bool, const SurfaceShare&,
  const SurfaceSolids&);

} // namespace pbf
