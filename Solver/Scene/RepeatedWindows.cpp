#include "RepeatedWindows.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace pbf
{
namespace
{

// A node's value as bits; beyond the grid a pattern no float a grid holds has (a NaN's).
constexpr std::uint32_t kMissing = 0xffffffffu;

std::uint32_t bitsAt(const DistanceGrid& g, int i, int j, int k)
{
  if (i < 0 || j < 0 || k < 0 || i >= g.nx || j >= g.ny || k >= g.nz)
  {
    return kMissing;
  }
  std::uint32_t bits;
  const float value = g.node(i, j, k);
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}

// Visits the window's values of nodes a and b side by side, in the same order; stops when
// visit returns false.
template <class Visit>
void walkWindows(
  const DistanceGrid& g, const GridNode& a, const GridNode& b, int radius, Visit&& visit)
{
  for (int dk = -radius; dk <= radius; ++dk)
  {
    for (int dj = -radius; dj <= radius; ++dj)
    {
      for (int di = -radius; di <= radius; ++di)
      {
        if (!visit(bitsAt(g, a.i + di, a.j + dj, a.k + dk),
              bitsAt(g, b.i + di, b.j + dj, b.k + dk)))
        {
          return;
        }
      }
    }
  }
}

// FNV-1a over the window's values, on four interleaved lanes so the multiplications overlap.
std::uint64_t windowHash(const DistanceGrid& g, const GridNode& n, int radius)
{
  std::uint64_t lanes[4] = { 0xcbf29ce484222325ull, 0x84222325cbf29ce4ull, 0x9e3779b97f4a7c15ull,
    0xc2b2ae3d27d4eb4full };
  unsigned lane = 0;
  walkWindows(g, n, n, radius, [&](std::uint32_t bits, std::uint32_t) {
    lanes[lane] = (lanes[lane] ^ bits) * 0x100000001b3ull;
    lane = (lane + 1) & 3;
    return true;
  });
  return lanes[0] ^ (lanes[1] * 3) ^ (lanes[2] * 5) ^ (lanes[3] * 7);
}

bool sameWindow(const DistanceGrid& g, const GridNode& a, const GridNode& b, int radius)
{
  bool same = true;
  walkWindows(g, a, b, radius, [&same](std::uint32_t x, std::uint32_t y) {
    same = x == y;
    return same;
  });
  return same;
}

} // namespace

GridNode gridNode(const DistanceGrid& g, std::int64_t index)
{
  const std::int64_t plane = static_cast<std::int64_t>(g.nx) * g.ny;
  return { static_cast<int>(index % g.nx), static_cast<int>((index % plane) / g.nx),
    static_cast<int>(index / plane) };
}

std::vector<std::int64_t> repeatedWindows(
  const DistanceGrid& g, const std::vector<std::uint8_t>& marked, int radius)
{
  const std::int64_t nodes = static_cast<std::int64_t>(marked.size());
  std::vector<std::int64_t> candidates;
  for (std::int64_t index = 0; index < nodes; ++index)
  {
    if (marked[static_cast<std::size_t>(index)])
    {
      candidates.push_back(index);
    }
  }
  const std::int64_t count = static_cast<std::int64_t>(candidates.size());
  std::vector<std::pair<std::uint64_t, std::int64_t>> keyed(candidates.size());
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < count; ++c)
  {
    const std::int64_t index = candidates[static_cast<std::size_t>(c)];
    keyed[static_cast<std::size_t>(c)] = { windowHash(g, gridNode(g, index), radius), index };
  }
  // By hash, then by index: each run of one hash lists its nodes in index order, so the first
  // equal window found in a run is the first in index order, whatever the threads.
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::size_t> runStart(keyed.size(), 0);
  for (std::size_t c = 1; c < keyed.size(); ++c)
  {
    runStart[c] = keyed[c].first == keyed[c - 1].first ? runStart[c - 1] : c;
  }
  std::vector<std::int64_t> first(marked.size(), -1);
#pragma omp parallel for schedule(dynamic, 64)
  for (std::int64_t c = 0; c < count; ++c)
  {
    const std::size_t at = static_cast<std::size_t>(c), run = runStart[at];
    const GridNode self = gridNode(g, keyed[at].second);
    for (std::size_t e = run; e <= at; ++e)
    {
      if (e == at || sameWindow(g, gridNode(g, keyed[e].second), self, radius))
      {
        first[static_cast<std::size_t>(keyed[at].second)] = keyed[e].second;
        break;
      }
    }
  }
  return first;
}

} // namespace pbf
