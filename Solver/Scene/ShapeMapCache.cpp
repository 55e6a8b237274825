#include "ShapeMapCache.h"

#include <atomic>
#include <cstddef>
#include <list>
#include <mutex>
#include <utility>

namespace pbf
{
namespace
{

constexpr std::size_t kCacheBytes = std::size_t(512) << 20;

struct Entry
{
  Vec3d origin;
  double cell;
  int nx, ny, nz;
  std::vector<float> phi;
  ShapeKernels kernels;
  ShapeWalls walls;
  ShapeRule rule;
  std::vector<float> shape;

  bool matches(
    const DistanceGrid& g, const ShapeKernels& k, const ShapeWalls& w, const ShapeRule& r) const
  {
    const Box &a = walls.domain, &b = w.domain;
    const bool sameWalls = walls.mirror == w.mirror &&
      (!w.mirror ||
        (a.min.x == b.min.x && a.min.y == b.min.y && a.min.z == b.min.z && a.max.x == b.max.x &&
          a.max.y == b.max.y && a.max.z == b.max.z));
    return origin.x == g.origin.x && origin.y == g.origin.y && origin.z == g.origin.z &&
      cell == g.cell && nx == g.nx && ny == g.ny && nz == g.nz && kernels.h == k.h &&
      kernels.sCorrN == k.sCorrN && kernels.wDeltaQ == k.wDeltaQ && rule.polar == r.polar &&
      rule.marchSteps == r.marchSteps && sameWalls && phi == g.phi;
  }
  std::size_t bytes() const { return (phi.size() + shape.size()) * sizeof(float); }
};

std::atomic<std::size_t> built{ 0 };
std::mutex cacheMutex;
std::list<Entry> cache; // most recently used first

} // namespace

std::size_t shapeMapsBuilt()
{
  return built.load();
}

void attachShapeMap(
  DistanceGrid& grid, const ShapeKernels& k, const ShapeWalls& walls, const ShapeRule& rule)
{
  {
    const std::lock_guard<std::mutex> lock(cacheMutex);
    for (auto entry = cache.begin(); entry != cache.end(); ++entry)
    {
      if (entry->matches(grid, k, walls, rule))
      {
        cache.splice(cache.begin(), cache, entry);
        grid.shape = cache.front().shape;
        return;
      }
    }
  }
  // Built outside the lock: other solids' maps are built or read meanwhile; two threads that
  // build the same one store two equal entries, which costs memory, never a wrong map.
  buildShapeMap(grid, k, walls, rule);
  ++built;
  Entry entry{ grid.origin, grid.cell, grid.nx, grid.ny, grid.nz, grid.phi, k, walls, rule,
    grid.shape };
  if (entry.bytes() > kCacheBytes)
  {
    return;
  }
  const std::lock_guard<std::mutex> lock(cacheMutex);
  cache.push_front(std::move(entry));
  std::size_t total = 0;
  for (auto e = cache.begin(); e != cache.end(); ++e)
  {
    total += e->bytes();
    if (total > kCacheBytes)
    {
      cache.erase(e, cache.end());
      break;
    }
  }
}

} // namespace pbf
