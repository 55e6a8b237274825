#include "PairCensus.h"

#include "Cuda/NeighborMasks.h"

#include <algorithm>
#include <numeric>

namespace pbf
{

namespace
{

constexpr int kWarp = 32;

double distance2(const Vec3d& a, const Vec3d& b)
{
  const Vec3d d = a - b;
  return dot(d, d);
}

GridView<double> viewOf(const CellSortedParticles& s)
{
  return { s.geometry, s.cellOffsets.data(), s.key.data() };
}

// Calls visit(begin, end) for the 9 row ranges of particle i, as the passes walk them.
template <class Visit>
void forEachRow(const GridView<double>& grid, std::uint32_t i, Visit&& visit)
{
  const detail::RowFrame frame = detail::rowFrame(grid, i);
  for (int r = 0; r < kNeighborRows; ++r)
  {
    std::uint32_t begin = 0, end = 0;
    if (detail::rowRange(grid, frame, r, begin, end))
    {
      visit(begin, end);
    }
  }
}

struct Cluster
{
  std::uint32_t cell;
  std::vector<std::uint32_t> members;
  Vec3d lo, hi;
};

// Each cell's particles in chunks of `size`, ordered by height within the cell first (so that a
// chunk is a compact slab, as GROMACS bins its grid columns along one axis).
std::vector<Cluster> makeClusters(const CellSortedParticles& s, int size)
{
  std::vector<Cluster> clusters;
  const std::uint32_t cells = s.geometry.cellCount();
  std::vector<std::uint32_t> order;
  for (std::uint32_t c = 0; c < cells; ++c)
  {
    order.resize(s.cellOffsets[c + 1] - s.cellOffsets[c]);
    std::iota(order.begin(), order.end(), s.cellOffsets[c]);
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      const Vec3d& pa = s.position[a];
      const Vec3d& pb = s.position[b];
      return pa.y != pb.y ? pa.y < pb.y : (pa.z != pb.z ? pa.z < pb.z : pa.x < pb.x);
    });
    for (std::size_t k = 0; k < order.size(); k += static_cast<std::size_t>(size))
    {
      Cluster cl;
      cl.cell = c;
      const std::size_t stop = std::min(order.size(), k + static_cast<std::size_t>(size));
      cl.members.assign(order.begin() + static_cast<std::ptrdiff_t>(k),
        order.begin() + static_cast<std::ptrdiff_t>(stop));
      cl.lo = cl.hi = s.position[cl.members.front()];
      for (std::uint32_t m : cl.members)
      {
        const Vec3d& p = s.position[m];
        cl.lo = { std::min(cl.lo.x, p.x), std::min(cl.lo.y, p.y), std::min(cl.lo.z, p.z) };
        cl.hi = { std::max(cl.hi.x, p.x), std::max(cl.hi.y, p.y), std::max(cl.hi.z, p.z) };
      }
      clusters.push_back(std::move(cl));
    }
  }
  return clusters;
}

double boxGap2(const Cluster& a, const Cluster& b)
{
  const auto gap = [](double lo1, double hi1, double lo2, double hi2) {
    return std::max({ 0.0, lo2 - hi1, lo1 - hi2 });
  };
  const double gx = gap(a.lo.x, a.hi.x, b.lo.x, b.hi.x);
  const double gy = gap(a.lo.y, a.hi.y, b.lo.y, b.hi.y);
  const double gz = gap(a.lo.z, a.hi.z, b.lo.z, b.hi.z);
  return gx * gx + gy * gy + gz * gz;
}

ClusterPairCensus countClusterPairs(
  const CellSortedParticles& s, double h, double skin, const ClusterShape& shape)
{
  const std::vector<Cluster> iClusters = makeClusters(s, shape.i);
  const std::vector<Cluster> jClusters =
    shape.j == shape.i ? std::vector<Cluster>() : makeClusters(s, shape.j);
  const std::vector<Cluster>& js = shape.j == shape.i ? iClusters : jClusters;
  // The j-clusters of each cell, to find those of the 27 cells around an i-cluster's.
  std::vector<std::uint32_t> firstOfCell(s.geometry.cellCount() + 1, 0);
  for (const Cluster& c : js)
  {
    ++firstOfCell[c.cell + 1];
  }
  std::partial_sum(firstOfCell.begin(), firstOfCell.end(), firstOfCell.begin());
  const GridGeometry<double>& g = s.geometry;
  const double reach2 = (h + skin) * (h + skin);
  const double h2 = h * h;
  double slots = 0, slotsOnce = 0, hits = 0, pairs = 0;
  const double tile = static_cast<double>(shape.i) * shape.j;
  for (std::size_t ci = 0; ci < iClusters.size(); ++ci)
  {
    const Cluster& a = iClusters[ci];
    const int cx = static_cast<int>(a.cell % static_cast<CellKey>(g.nx));
    const int cy = static_cast<int>((a.cell / static_cast<CellKey>(g.nx)) % g.ny);
    const int cz = static_cast<int>(a.cell / (static_cast<CellKey>(g.nx) * g.ny));
    for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, g.nz - 1); ++z)
    {
      for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, g.ny - 1); ++y)
      {
        for (int x = std::max(cx - 1, 0); x <= std::min(cx + 1, g.nx - 1); ++x)
        {
          const CellKey cell = (static_cast<CellKey>(z) * g.ny + y) * g.nx + x;
          for (std::uint32_t cj = firstOfCell[cell]; cj < firstOfCell[cell + 1]; ++cj)
          {
            const Cluster& b = js[cj];
            if (boxGap2(a, b) >= reach2)
            {
              continue;
            }
            pairs += 1;
            slots += tile;
            if (shape.j == shape.i && cj >= ci)
            {
              slotsOnce += tile;
            }
            for (std::uint32_t p : a.members)
            {
              for (std::uint32_t q : b.members)
              {
                hits += distance2(s.position[p], s.position[q]) < h2 ? 1.0 : 0.0;
              }
            }
          }
        }
      }
    }
  }
  const double n = static_cast<double>(s.position.size());
  ClusterPairCensus c;
  c.shape = shape;
  c.slotsPerParticle = slots / n;
  c.slotsOncePerParticle = shape.j == shape.i ? slotsOnce / n : 0.0;
  c.hitFraction = slots > 0 ? hits / slots : 0.0;
  c.clusterPairsPerCluster = pairs / static_cast<double>(iClusters.size());
  return c;
}

} // namespace

CellSortedParticles sortByCell(const std::vector<Vec3d>& position, const GridGeometry<double>& g)
{
  const std::size_t n = position.size();
  std::vector<CellKey> keys(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    keys[i] = g.keyOf(position[i]);
  }
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
    [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
  CellSortedParticles s;
  s.geometry = g;
  s.position.resize(n);
  s.key.resize(n);
  s.cellOffsets.assign(static_cast<std::size_t>(g.cellCount()) + 1, 0);
  for (std::size_t k = 0; k < n; ++k)
  {
    s.position[k] = position[order[k]];
    s.key[k] = keys[order[k]];
    ++s.cellOffsets[s.key[k] + 1];
  }
  std::partial_sum(s.cellOffsets.begin(), s.cellOffsets.end(), s.cellOffsets.begin());
  return s;
}

PairCensus countPairs(const CellSortedParticles& s, double h, double skin,
  const std::vector<ClusterShape>& shapes)
{
  const GridView<double> grid = viewOf(s);
  const std::size_t n = s.position.size();
  const double h2 = h * h;
  const double reach2 = (h + skin) * (h + skin);
  double withinH = 0, walk = 0, visits = 0, walkSlots = 0, maskSlots = 0, onceSlots = 0;
  for (std::size_t w = 0; w < n; w += kWarp)
  {
    double warpWalk = 0, warpVisits = 0, warpOnce = 0;
    for (std::size_t i = w; i < std::min(n, w + kWarp); ++i)
    {
      double cand = 0, visit = 0, once = 0;
      const Vec3d& pi = s.position[i];
      forEachRow(grid, static_cast<std::uint32_t>(i), [&](std::uint32_t begin, std::uint32_t end) {
        cand += end - begin;
        for (std::uint32_t j = begin; j < end; ++j)
        {
          const double r2 = distance2(pi, s.position[j]);
          withinH += r2 < h2 ? 1.0 : 0.0;
          // A mask covers the first 32 candidates of a row; the rest are visited regardless.
          const bool visited = j - begin >= static_cast<std::uint32_t>(kMaskWidth) || r2 < reach2;
          visit += visited ? 1.0 : 0.0;
          once += visited && j > i ? 1.0 : 0.0;
        }
      });
      walk += cand;
      visits += visit;
      warpWalk = std::max(warpWalk, cand);
      warpVisits = std::max(warpVisits, visit);
      warpOnce = std::max(warpOnce, once);
    }
    onceSlots += kWarp * warpOnce;
    walkSlots += kWarp * warpWalk;
    maskSlots += kWarp * warpVisits;
  }
  PairCensus c;
  c.particles = n;
  const double dn = n > 0 ? static_cast<double>(n) : 1.0;
  c.withinH = withinH / dn;
  c.cellWalk = walk / dn;
  c.maskVisits = visits / dn;
  c.cellWalkSlots = walkSlots / dn;
  c.maskSlots = maskSlots / dn;
  c.maskHitFraction = maskSlots > 0 ? withinH / maskSlots : 0.0;
  c.maskOnceSlots = onceSlots / dn;
  for (const ClusterShape& shape : shapes)
  {
    c.clusters.push_back(countClusterPairs(s, h, skin, shape));
  }
  return c;
}

} // namespace pbf
