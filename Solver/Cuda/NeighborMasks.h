// Neighbour lists for the CUDA backend, as bit masks over the rows that forEachNeighbor walks.
//
// forEachNeighbor (Grid.h) visits the 27 cells around a particle as 9 contiguous index ranges
// ("rows": 3 cells along x). About 1 candidate in 6 lies within h, and on a GPU a warp pays for
// the whole neighbour body whenever any of its 32 lanes has a hit, so walking the cells in every
// pass costs close to 6 times the work. Instead, once per step each particle marks, per row, the
// first 32 candidates that lie within h + skin in a 32-bit mask (9 masks, 36 bytes a particle);
// the passes then visit only the marked candidates and, unconditionally, any candidate past the
// 32nd of a row. The candidates keep forEachNeighbor's order and the equations still test r < h
// themselves, so the sums see the same terms in the same order: results are bit-identical to the
// walk as long as no skipped candidate can have come within h. That is guaranteed by bounding how
// far particles moved since the masks were built (MaskSchedule below) and rebuilding when the
// bound could be exceeded. Wall images (Equations.h) lie farther away than the neighbour itself
// for particles inside the box, so they never need a skipped candidate either.
#pragma once

#include "Grid.h"
#include "HostDevice.h"
#include "Vec3.h"

#include <cstdint>
#include <cstring>
#include <limits>

namespace pbf
{

constexpr int kNeighborRows = 9;  // (z, y) rows of 3 cells along x
constexpr int kMaskWidth = 32;    // candidates per row covered by a mask
constexpr int kMaskBlock = 128;   // most threads per block of a pass that walks the masks (GPU)
constexpr int kMaskWords = 12;    // (base, mask) words a GPU lane stages (forEachNeighbor)

template <class Real>
struct MaskedNeighbors
{
  GridView<Real> cells;
  const std::uint32_t* masks; // row r of particle i at masks[r * stride + i]
  std::uint32_t stride;
  bool useMasks;              // false: walk the 27 cells like the CPU backends
};

namespace detail
{

// A mask holds candidate k of its row at bit 31 - k, so the next candidate in ascending order is
// the highest set bit: one leading-zero count (on a GPU a bit reversal and a find-first had
// cost two instructions a visit).
PBF_HD PBF_INLINE int firstCandidate(std::uint32_t mask)
{
#if defined(__CUDA_ARCH__)
  return __clz(static_cast<int>(mask));
#else
  return __builtin_clz(mask);
#endif
}

// The mask without candidate k (its first): the bits below bit 31 - k.
PBF_HD PBF_INLINE std::uint32_t withoutFirst(std::uint32_t mask, int k)
{
  return mask & (0x7fffffffu >> k);
}

// The first `count` candidates of a row, all marked (a row's tail beyond the first 32).
PBF_HD PBF_INLINE std::uint32_t firstCandidates(std::uint32_t count)
{
  return count >= static_cast<std::uint32_t>(kMaskWidth) ? ~0u : ~(~0u >> count);
}

#if defined(__CUDA_ARCH__)
// The word whose top bit is the sign of x (the rest of it is not used): the mask build's bit.
PBF_HD PBF_INLINE std::uint32_t signWord(float x)
{
  return __float_as_uint(x);
}
PBF_HD PBF_INLINE std::uint32_t signWord(double x)
{
  return static_cast<std::uint32_t>(static_cast<unsigned long long>(__double_as_longlong(x)) >> 32);
}
#endif

// The cell of sorted particle i and the x range of its rows, as forEachNeighbor computes them.
struct RowFrame
{
  int cx, cy, cz, x0, x1;
};

template <class Real>
PBF_HD PBF_INLINE RowFrame rowFrame(const GridView<Real>& grid, std::uint32_t i)
{
  const GridGeometry<Real>& g = grid.geometry;
  const CellKey key = grid.particleKeys[i];
  RowFrame f;
  f.cx = static_cast<int>(key % static_cast<CellKey>(g.nx));
  f.cy = static_cast<int>((key / static_cast<CellKey>(g.nx)) % static_cast<CellKey>(g.ny));
  f.cz = static_cast<int>(key / (static_cast<CellKey>(g.nx) * g.ny));
  f.x0 = f.cx > 0 ? f.cx - 1 : 0;
  f.x1 = f.cx + 1 < g.nx ? f.cx + 1 : f.cx;
  return f;
}

// Row r (z-major, as forEachNeighbor loops) as a sorted index range; false outside the grid.
template <class Real>
PBF_HD PBF_INLINE bool rowRange(const GridView<Real>& grid, const RowFrame& f, int r,
  std::uint32_t& begin, std::uint32_t& end)
{
  const GridGeometry<Real>& g = grid.geometry;
  const int z = f.cz - 1 + r / 3;
  const int y = f.cy - 1 + r % 3;
  if (z < 0 || z >= g.nz || y < 0 || y >= g.ny)
  {
    return false;
  }
  const CellKey row = (static_cast<CellKey>(z) * g.ny + y) * g.nx;
  begin = grid.cellOffsets[row + f.x0];
  end = grid.cellOffsets[row + f.x1 + 1];
  return true;
}

} // namespace detail

// Marks, in each of particle i's rows, the candidates j among the first 32 with |p_i - p_j|^2 <
// reach2 = (h + skin)^2. Only particle i's own masks are written, so a pass may rebuild them
// while other particles read positions.
template <class Real>
PBF_HD PBF_INLINE void buildNeighborMasks(std::uint32_t i, const GridView<Real>& grid,
  const Vec3<Real>* p, Real reach2, std::uint32_t* masks, std::uint32_t stride)
{
  const detail::RowFrame frame = detail::rowFrame(grid, i);
  const Vec3<Real> pi = p[i];
  for (int r = 0; r < kNeighborRows; ++r)
  {
    std::uint32_t begin = 0, end = 0, mask = 0;
    if (detail::rowRange(grid, frame, r, begin, end))
    {
      // The first candidate is shifted in first and ends in the highest of `count` bits; one
      // shift at the end puts candidate k at bit 31 - k (firstCandidate). A shift a candidate,
      // instead of a shift by k, an or and the index arithmetic (on a GPU the build is a third
      // of the density pass).
      const std::uint32_t count = end - begin > kMaskWidth ? kMaskWidth : end - begin;
      const Vec3<Real>* q = p + begin;
      std::uint32_t reversed = 0;
      for (std::uint32_t k = 0; k < count; ++k)
      {
        const Vec3<Real> d = pi - q[k];
#if defined(__CUDA_ARCH__)
        // The sign of r^2 - reach2 is the bit (negative: closer than the reach; equal gives +0):
        // one funnel shift moves it in, where a compare, a select, a shift and an or did.
        reversed = __funnelshift_l(detail::signWord(dot(d, d) - reach2), reversed, 1);
#else
        reversed = (reversed << 1) | (dot(d, d) < reach2 ? 1u : 0u);
#endif
      }
      mask = count == 0 ? 0u : reversed << (kMaskWidth - count);
    }
    masks[static_cast<std::size_t>(r) * stride + i] = mask;
  }
}

// Found by argument-dependent lookup from the equations when their FluidView carries
// MaskedNeighbors. Visits the marked candidates, then each row's candidates past the 32nd, in
// ascending sorted index: forEachNeighbor's order without the skipped ones. One loop over all
// rows, so a lane that runs out of candidates in a row moves on instead of idling while the rest
// of its warp finishes that row, and the visit body is inlined once.
//
// On the GPU each lane first stages its visits in shared memory as a list of (base, mask) words,
// in visit order: one per row with a marked candidate, then one per 32 candidates of a row's tail
// (all of their bits set, as the tail is visited unconditionally). The loop then refills with one
// shared load when a word runs out. Lanes refill at different iterations, so the warp pays a
// refill in nearly every iteration: fetched from the grid (ncu, 1M particles, 9 rows with a
// separate tail case) it took 27% of the density pass's instructions and 38% of the correction
// pass's; staged rows with the tail decided in the loop still took 23 instructions an iteration,
// 9% and 13% of those passes.
namespace detail
{

#if defined(__CUDA_ARCH__)
// Lane i's visits staged at word[0], word[kMaskBlock], ...: one (base, mask) word per row with a
// marked candidate, then one per 32 candidates of a row's tail (all of their bits set, as the
// tail is visited unconditionally). Returns how many words the visits need; beyond kMaskWords
// only the first kMaskWords are written.
template <class Real>
__device__ PBF_INLINE int stageMaskWords(
  const MaskedNeighbors<Real>& neighbors, std::uint32_t i, uint2* word)
{
  int count = 0;
  const RowFrame frame = rowFrame(neighbors.cells, i);
#pragma unroll
  for (int r = 0; r < kNeighborRows; ++r)
  {
    std::uint32_t begin = 0, end = 0;
    if (rowRange(neighbors.cells, frame, r, begin, end))
    {
      const std::uint32_t mask = neighbors.masks[static_cast<std::size_t>(r) * neighbors.stride + i];
      if (mask != 0)
      {
        if (count < kMaskWords)
        {
          word[count * kMaskBlock] = make_uint2(begin, mask);
        }
        ++count;
      }
      for (std::uint32_t b = begin + kMaskWidth; b < end; b += kMaskWidth)
      {
        const std::uint32_t left = end - b;
        if (count < kMaskWords)
        {
          word[count * kMaskBlock] = make_uint2(b, firstCandidates(left));
        }
        ++count;
      }
    }
  }
  return count;
}

// The staged words' candidates in order, refilling with one shared load when a word runs out.
template <class Visit>
__device__ PBF_INLINE void visitMaskWords(const uint2* word, int count, Visit& visit)
{
  const uint2* const last = word + count * kMaskBlock;
  std::uint32_t mask = 0, base = 0;
  for (;;)
  {
    if (mask == 0)
    {
      if (word == last)
      {
        break;
      }
      const uint2 w = *word;
      word += kMaskBlock;
      base = w.x;
      mask = w.y;
    }
    const int k = firstCandidate(mask);
    const std::uint32_t j = base + static_cast<std::uint32_t>(k);
    mask = withoutFirst(mask, k);
    visit(j);
  }
}
#endif

// The host's walk of the same visits, row by row: the marked candidates, then the row's tail.
template <class Real, class Visit>
PBF_HD PBF_INLINE void walkMaskedRows(
  const MaskedNeighbors<Real>& neighbors, std::uint32_t i, Visit& visit)
{
  const RowFrame frame = rowFrame(neighbors.cells, i);
  int nextRow = 0;
  std::uint32_t mask = 0, base = 0, tail = 0, tailEnd = 0;
  for (;;)
  {
    while (mask == 0 && tail == tailEnd && nextRow < kNeighborRows)
    {
      const int r = nextRow++;
      std::uint32_t begin = 0, end = 0;
      if (rowRange(neighbors.cells, frame, r, begin, end))
      {
        base = begin;
        mask = neighbors.masks[static_cast<std::size_t>(r) * neighbors.stride + i];
        tail = end - begin > kMaskWidth ? begin + kMaskWidth : end;
        tailEnd = end;
      }
    }
    std::uint32_t j;
    if (mask != 0)
    {
      const int k = firstCandidate(mask);
      j = base + static_cast<std::uint32_t>(k);
      mask = withoutFirst(mask, k);
    }
    else if (tail != tailEnd)
    {
      j = tail++;
    }
    else
    {
      break;
    }
    visit(j);
  }
}

} // namespace detail

template <class Real, class Visit>
PBF_HD PBF_INLINE void forEachNeighbor(
  const MaskedNeighbors<Real>& neighbors, std::uint32_t i, Visit&& visit)
{
  if (!neighbors.useMasks)
  {
    forEachNeighbor(neighbors.cells, i, visit);
    return;
  }
#if defined(__CUDA_ARCH__)
  // Each thread uses its own column only: no barrier, no sharing between threads. 96 bytes a
  // thread: shared memory comes out of L1, which holds the passes' neighbour reads. A row of 3
  // cells holds ~24 particles, so tails are rare and 12 words hold the 9 rows and 3 tail words; a
  // lane that needs more (a strongly compressed neighbourhood) walks its 27 cells instead, which
  // visits the same candidates within h in the same order.
  __shared__ uint2 words[kMaskWords][kMaskBlock];
  uint2* const word = &words[0][threadIdx.x];
  const int count = detail::stageMaskWords(neighbors, i, word);
  if (count > kMaskWords)
  {
    forEachNeighbor(neighbors.cells, i, visit);
    return;
  }
  detail::visitMaskWords(word, count, visit);
#else
  detail::walkMaskedRows(neighbors, i, visit);
#endif
}

// When masks are rebuilt. Every correction moves a particle by |delta p_i| at most, plus rounding;
// collisions only project onto the box, which moves no closer to anything inside it. So after
// corrections k0..k-1 no particle is farther than S = sum of max_i |delta p_i| from where the masks
// were built, and a skipped pair, at least h + skin apart then, is still farther than h now while
// 2 S stays under the skin. The margins cover rounding of distances and of positions.
struct MaskSchedule
{
  double skin;             // [m]
  double h;                // [m]
  double roundingPerStep;  // bound on a position's rounding error per correction [m]
  int enabled;             // 0: masks off, never rebuilt

  PBF_HD PBF_INLINE bool stillValid(double moved, int corrections) const
  {
    const double drift = moved * (1.0 + 1e-3) + corrections * roundingPerStep;
    // Written so that NaN (a NaN displacement) reads as invalid.
    return 2.0 * drift < skin - 1e-3 * h;
  }

  // Whether the pass that sees the positions after `corrections` corrections of this step must
  // rebuild the masks. maxMoved[k] holds max_i |delta p_i| of correction k as the bits of a
  // non-negative double. Every thread replays the same decisions from the same numbers, so they
  // agree without synchronising.
  PBF_HD PBF_INLINE bool rebuildAt(int corrections, const unsigned long long* maxMoved) const
  {
    if (corrections == 0)
    {
      return true;
    }
    int builtAt = 0;
    double moved = 0.0;
    for (int k = 1; k <= corrections; ++k)
    {
      moved += bitsToDouble(maxMoved[k - 1]);
      if (!stillValid(moved, k - builtAt))
      {
        if (k == corrections)
        {
          return true;
        }
        builtAt = k;
        moved = 0.0;
      }
    }
    return false;
  }

  // The same bound for one particle's masks, built when this step's cells were sorted and kept
  // since (MovedSinceSort below): `pair` is how far the particle moved since then plus the most
  // any candidate in its 27 cells moved, an upper bound of how much closer a skipped candidate
  // can have come; `corrections` is how many corrections there have been since the sort. Rounding
  // is counted for both particles.
  PBF_HD PBF_INLINE bool stillValidAround(double pair, int corrections) const
  {
    const double drift = pair * (1.0 + 1e-3) + 2.0 * corrections * roundingPerStep;
    return drift < skin - 1e-3 * h;
  }

  PBF_HD PBF_INLINE static double bitsToDouble(unsigned long long bits)
  {
#if defined(__CUDA_ARCH__)
    return __longlong_as_double(static_cast<long long>(bits));
#else
    double d;
    std::memcpy(&d, &bits, sizeof d);
    return d;
#endif
  }
  // Non-negative doubles (and NaN) order like their bit patterns as unsigned integers, so an
  // integer max gives the max displacement, and a NaN wins it: deterministic in any order.
  PBF_HD PBF_INLINE static unsigned long long doubleToBits(double d)
  {
#if defined(__CUDA_ARCH__)
    return static_cast<unsigned long long>(__double_as_longlong(d));
#else
    unsigned long long bits;
    std::memcpy(&bits, &d, sizeof d);
    return bits;
#endif
  }

  // Rounding of a coordinate of magnitude <= maxAbsCoordinate in Real, per correction: the sum
  // p + delta rounds each component by half an ulp; twice that, over three components.
  template <class Real>
  static double roundingBound(double maxAbsCoordinate)
  {
    return 2.0 * 1.7320508075688772 * static_cast<double>(std::numeric_limits<Real>::epsilon()) *
      maxAbsCoordinate;
  }
};

// Per-particle rebuilds (the single-GPU step). A global bound (MaskSchedule::rebuildAt) makes
// every particle rebuild as soon as one particle anywhere moves more than the skin allows, which
// in a dam break is every pass: 5 builds a step of 4 projections, a third of each density pass.
// Instead each particle keeps the masks of the step's first pass for as long as its own
// neighbourhood allows: moved[i] sums |delta p_i| over the step's corrections (an upper bound of
// how far i moved since the sort), cellMoved[c] is the largest of those in sorted cell c (the
// bits of a non-negative float: they order like the floats, so an integer max is exact and
// independent of the order), and a pass keeps i's masks while
// moved[i] + max over i's 27 cells of cellMoved stays within the skin. A particle whose bound
// fails rebuilds in that pass and in every later pass of the step (its masks are no longer those
// of the sort, which the bound is about): it is marked by the sign of moved[i].
struct MovedSinceSort
{
  float* moved;             // per particle; negative (or -0): rebuilt since the sort
  std::uint32_t* cellMoved; // per cell: float bits of the largest |moved| of its particles

  PBF_HD PBF_INLINE static std::uint32_t bitsOf(float f)
  {
#if defined(__CUDA_ARCH__)
    return static_cast<std::uint32_t>(__float_as_uint(f));
#else
    std::uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
#endif
  }
  PBF_HD PBF_INLINE static float floatOf(std::uint32_t b)
  {
#if defined(__CUDA_ARCH__)
    return __uint_as_float(b);
#else
    float f;
    std::memcpy(&f, &b, sizeof f);
    return f;
#endif
  }
  PBF_HD PBF_INLINE static bool marked(float m) { return (bitsOf(m) >> 31) != 0; }

  // After a correction moved particle i (sorted cell `key`) by `distance`.
  PBF_HD PBF_INLINE void add(std::uint32_t i, CellKey key, double distance) const
  {
    const float before = moved[i];
    const float total = (marked(before) ? -before : before) + static_cast<float>(distance);
    moved[i] = marked(before) ? -total : total;
    const std::uint32_t bits = bitsOf(total);
    std::uint32_t* cell = cellMoved + key;
#if defined(__CUDA_ARCH__)
    atomicMax(cell, bits);
#else
    // Host executors run a stage's particles one after another.
    *cell = *cell > bits ? *cell : bits;
#endif
  }

  // Whether particle i (frame: its rows) may keep its masks after `corrections` corrections.
  template <class Real>
  PBF_HD PBF_INLINE bool keeps(const GridView<Real>& grid, std::uint32_t i,
    const MaskSchedule& schedule, int corrections) const
  {
    const float own = moved[i];
    if (marked(own))
    {
      return false;
    }
    // The 27 cells with the grid's edges clamped: a cell read twice changes no maximum, and the
    // reads need no bounds test or loop (on a GPU the rows' tests and variable loops had cost a
    // twentieth of the density passes that check).
    const detail::RowFrame frame = detail::rowFrame(grid, i);
    const GridGeometry<Real>& g = grid.geometry;
    const int z0 = frame.cz > 0 ? frame.cz - 1 : 0, z1 = frame.cz + 1 < g.nz ? frame.cz + 1 : frame.cz;
    const int y0 = frame.cy > 0 ? frame.cy - 1 : 0, y1 = frame.cy + 1 < g.ny ? frame.cy + 1 : frame.cy;
    const int zs[3] = { z0, frame.cz, z1 };
    const int ys[3] = { y0, frame.cy, y1 };
    std::uint32_t around = 0;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
    for (int r = 0; r < kNeighborRows; ++r)
    {
      const std::uint32_t* row =
        cellMoved + (static_cast<CellKey>(zs[r / 3]) * g.ny + ys[r % 3]) * g.nx;
      const std::uint32_t a = row[frame.x0], b = row[frame.cx], c = row[frame.x1];
      const std::uint32_t ab = a > b ? a : b;
      around = around > ab ? around : ab;
      around = around > c ? around : c;
    }
    return schedule.stillValidAround(double(own) + double(floatOf(around)), corrections);
  }

  // Particle i rebuilt its masks: it rebuilds in every later pass of this step.
  PBF_HD PBF_INLINE void mark(std::uint32_t i) const
  {
    const float m = moved[i];
    if (!marked(m))
    {
      moved[i] = -m; // -0 for 0: marked too
    }
  }
};

} // namespace pbf
