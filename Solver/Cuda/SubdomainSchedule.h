// The per-particle stages that one rank of a domain-decomposed run adds to StepSchedule.h on a
// GPU: the column histogram for the cut, the owner of each particle, packing the
// particles that leave and the border particles that others mirror, and gathering and
// scattering the fields of the ghost refreshes. Written over the same executor as StepSchedule.h
// (plus selectIf, below), so the tests run them on the host; DeviceSubdomainStepper.h strings
// them together with the exchanges.
//
// Executor additions:
//   selectIf(n, pred, out, count)   out = the i in [0, n) with pred(i), ascending; *count = how
//                                   many (both in device memory). Stable, so deterministic.
#pragma once

#include "Equations.h"
#include "Grid.h"
#include "HostDevice.h"
#include "StepSchedule.h"

#include <cstddef>
#include <cstdint>
#include <initializer_list>

namespace pbf
{
namespace cuda
{
namespace subdomain
{

// Integer counting: exact in any order, so the histograms do not depend on scheduling. On the
// GPU the lanes of a warp that count into the same counter add once together (a particle's
// owner is the same for nearly all lanes: one atomic per warp instead of 32 on one address).
// Even so, at 8M particles a step's owner counts were ~250,000 atomics on one address, which
// serialise: 213 us on the H200, and 171 us for each column histogram. So every counter has
// kCounterCopies copies, side by side, a block adds to the copy of its block number, and the host
// sums the copies (sumOfCopies). The host executors run a stage sequentially, into copy 0.
constexpr std::size_t kCounterCopies = 16;

PBF_HD PBF_INLINE std::size_t counterCopy()
{
#if defined(__CUDA_ARCH__)
  return blockIdx.x % kCounterCopies;
#else
  return 0;
#endif
}

PBF_HD PBF_INLINE void countOne(std::uint32_t* counter)
{
#if defined(__CUDA_ARCH__)
  const unsigned active = __activemask();
  const unsigned same =
    __match_any_sync(active, static_cast<unsigned long long>(reinterpret_cast<std::uintptr_t>(counter)));
  if (static_cast<int>(threadIdx.x & 31u) == __ffs(static_cast<int>(same)) - 1)
  {
    atomicAdd(counter, static_cast<unsigned>(__popc(static_cast<int>(same))));
  }
#else
  ++*counter;
#endif
}

// Counter c of an array of counters with kCounterCopies copies each (host side).
inline std::uint32_t sumOfCopies(const std::uint32_t* copies, std::size_t c)
{
  std::uint32_t sum = 0;
  for (std::size_t k = 0; k < kCounterCopies; ++k)
  {
    sum += copies[c * kCounterCopies + k];
  }
  return sum;
}

// The slabs on the device: rank r owns the grid columns [first[r], first[r + 1]).
struct SlabView
{
  const int* first; // ranks + 1 entries
  int ranks;
  int me;

  PBF_HD PBF_INLINE int owner(int column) const
  {
    int r = 0;
    while (r + 1 < ranks && column >= first[r + 1])
    {
      ++r;
    }
    return r;
  }
  PBF_HD PBF_INLINE int begin() const { return first[me]; }
  PBF_HD PBF_INLINE int end() const { return first[me + 1]; }
};

template <class Real>
PBF_HD PBF_INLINE int columnOf(const GridGeometry<Real>& g, const Vec3<Real>& q)
{
  return g.clampedCell(q.x, g.origin.x, g.nx);
}

PBF_HD PBF_INLINE int columnOfKey(CellKey key, int nx)
{
  return static_cast<int>(key % static_cast<CellKey>(nx));
}

// What a particle that changes rank takes along: everything the step still needs of it, and its
// pressure's mean over the frame so far (56 bytes in single precision; few particles migrate
// in a step).
template <class Real>
struct Migrant
{
  Vec3<Real> x, p, v;
  Real pressure;
  std::uint8_t liquid; // 0 in a scene without liquids
  std::int64_t id;
};

// What a ghost starts from: its predicted position, nothing else. Its id is never read (the
// ghost lists match slots by order, and only owned particles are output), so it does not travel:
// with it a seed took 24 bytes in single precision instead of 12, and on 4 GPUs the seeds'
// exchange through the host is the longest wait of a step's set-up.
template <class Real>
struct GhostSeed
{
  Vec3<Real> p;

  PBF_HD static GhostSeed of(std::uint32_t i, const Vec3<Real>* q, const std::uint8_t*)
  {
    return { q[i] };
  }
  PBF_HD void liquidInto(std::uint32_t, std::uint8_t*) const {}
};

// A ghost's seed in a scene of several liquids: its liquid too, which the density pass weighs its
// neighbours by and the colour reads. It is set for the whole step, so it travels once, here,
// and not with every refresh (16 bytes in single precision).
template <class Real>
struct LiquidSeed
{
  Vec3<Real> p;
  std::uint32_t liquid;

  PBF_HD static LiquidSeed of(std::uint32_t i, const Vec3<Real>* q, const std::uint8_t* liquids)
  {
    return { q[i], liquids[i] };
  }
  PBF_HD void liquidInto(std::uint32_t i, std::uint8_t* liquids) const
  {
    liquids[i] = static_cast<std::uint8_t>(liquid);
  }
};

// The id a ghost slot carries; never read (only owned particles are output or matched by id).
constexpr std::int64_t kGhostId = -1;

// Counter c (copies: kCounterCopies) += particles of column c (counts zeroed by the caller).
template <class Real, class Exec>
void countColumns(Exec& exec, const GridGeometry<Real>& g, std::uint32_t n, const Vec3<Real>* x,
  std::uint32_t* counts)
{
  exec.forEach(KeyStage{}, n, [=] PBF_HD(std::uint32_t i) {
    countOne(counts + static_cast<std::size_t>(columnOf(g, x[i])) * kCounterCopies + counterCopy());
  });
}

// Algorithm 1, lines 1-4, on this rank's particles.
template <class Real, class Exec>
void predict(Exec& exec, const StepConstants<Real>& k, std::uint32_t n, const Vec3<Real>* x,
  Vec3<Real>* v, Vec3<Real>* p)
{
  FluidView<Real> f = detail::plainView(k);
  f.x = x;
  f.v = v;
  f.p = p;
  exec.forEach(PredictStage{}, n, [=] PBF_HD(std::uint32_t i) { predictPosition(i, f); });
}

// The migration's sort key: 0 for a particle this rank keeps, 1 + the owner's rank otherwise,
// so a stable sort puts the kept ones first, in their order, and the others grouped by where
// they go. Counter key (copies: kCounterCopies) counts them (zeroed by the caller).
template <class Real, class Exec>
void ownerKeys(Exec& exec, const GridGeometry<Real>& g, SlabView slabs, std::uint32_t n,
  const Vec3<Real>* q, CellKey* keys, std::uint32_t* order, std::uint32_t* counts)
{
  exec.forEach(KeyStage{}, n, [=] PBF_HD(std::uint32_t i) {
    const int owner = slabs.owner(columnOf(g, q[i]));
    const CellKey key = owner == slabs.me ? 0u : static_cast<CellKey>(owner + 1);
    keys[i] = key;
    order[i] = i;
    countOne(counts + static_cast<std::size_t>(key) * kCounterCopies + counterCopy());
  });
}

// Every helper below is a template of Real, even where Real does not appear: the float and the
// double stepper live in separate CUDA translation units, and a kernel or a selection predicate
// instantiated identically in both (an extended lambda's wrapper above all) crashed the double
// stepper on the H200 with a call through a null pointer on the host. Distinct per precision,
// nothing is shared between the two units. The selections take named functors, not lambdas.

// Selection predicates (CUB copies them on the host).
template <class Real>
struct KeyIs
{
  const CellKey* keys;
  CellKey key;
  PBF_HD bool operator()(std::uint32_t i) const { return keys[i] == key; }
};

template <class Real>
struct HoleOrMover
{
  const CellKey* keys;
  std::uint32_t stay;
  bool hole;
  PBF_HD bool operator()(std::uint32_t i) const
  {
    return hole ? (i < stay && keys[i] != 0u) : (i >= stay && keys[i] == 0u);
  }
};

template <class Real>
struct PositionInColumn
{
  GridGeometry<Real> g;
  const Vec3<Real>* q;
  int column;
  PBF_HD bool operator()(std::uint32_t i) const { return columnOf(g, q[i]) == column; }
};

template <class Real>
struct KeyInColumns
{
  const CellKey* keys;
  int nx, begin, end;
  PBF_HD bool operator()(std::uint32_t i) const
  {
    const int c = columnOfKey(keys[i], nx);
    return c >= begin && c < end;
  }
};

// Owned particles (columns [begin, end)) in a border column that a neighbour mirrors (the first
// with a left neighbour, the last with a right one; each particle once), or the others.
template <class Real>
struct BorderOrInterior
{
  const CellKey* keys;
  int nx, begin, end;
  bool left, right, border;
  PBF_HD bool operator()(std::uint32_t i) const
  {
    const int c = columnOfKey(keys[i], nx);
    if (c < begin || c >= end)
    {
      return false;
    }
    const bool isBorder = (left && c == begin) || (right && c == end - 1);
    return isBorder == border;
  }
};

template <class Real, class Exec>
void selectBorder(Exec& exec, int nx, std::uint32_t n, const CellKey* keys, int begin, int end,
  bool left, bool right, bool border, std::uint32_t* out, std::uint32_t* count)
{
  exec.selectIf(n, BorderOrInterior<Real>{ keys, nx, begin, end, left, right, border }, out, count);
}

// The indices i with keys[i] == key, ascending (the leavers to one rank, in their order).
template <class Real, class Exec>
void selectKey(Exec& exec, std::uint32_t n, const CellKey* keys, CellKey key, std::uint32_t* out,
  std::uint32_t* count)
{
  exec.selectIf(n, KeyIs<Real>{ keys, key }, out, count);
}

// Compaction after the leavers are packed: the holes (leavers below `stay`) and the movers (kept
// particles at or above it), each ascending; there are as many of each.
template <class Real, class Exec>
void selectHolesAndMovers(Exec& exec, std::uint32_t n, std::uint32_t stay, const CellKey* keys,
  std::uint32_t* holes, std::uint32_t* movers, std::uint32_t* counts)
{
  exec.selectIf(n, HoleOrMover<Real>{ keys, stay, true }, holes, counts);
  exec.selectIf(n, HoleOrMover<Real>{ keys, stay, false }, movers, counts + 1);
}

// array[holes[j]] = array[movers[j]] for j < *count (a device count: up to `most` threads).
template <class Real, class T, class Exec>
void fillHoles(Exec& exec, std::uint32_t most, const std::uint32_t* count,
  const std::uint32_t* holes, const std::uint32_t* movers, T* array)
{
  exec.forEach(GatherStage{}, most, [=] PBF_HD(std::uint32_t j) {
    if (j < *count)
    {
      array[holes[j]] = array[movers[j]];
    }
  });
}

// to[i] = from[perm[i]].
template <class Real, class T, class Exec>
void gather(Exec& exec, std::uint32_t n, const std::uint32_t* perm, const T* from, T* to)
{
  exec.forEach(GatherStage{}, n, [=] PBF_HD(std::uint32_t i) { to[i] = from[perm[i]]; });
}

// liquid: null in a scene without liquids (the records carry 0).
template <class Real, class Exec>
void packMigrants(Exec& exec, std::uint32_t count, const std::uint32_t* list, const Vec3<Real>* x,
  const Vec3<Real>* p, const Vec3<Real>* v, const Real* pressure, const std::int64_t* id,
  const std::uint8_t* liquid, Migrant<Real>* out)
{
  exec.forEach(GatherStage{}, count, [=] PBF_HD(std::uint32_t k) {
    const std::uint32_t i = list[k];
    out[k] = Migrant<Real>{ x[i], p[i], v[i], pressure[i], liquid ? liquid[i] : std::uint8_t(0),
      id[i] };
  });
}

template <class Real, class Exec>
void unpackMigrants(Exec& exec, std::uint32_t first, std::uint32_t count,
  const Migrant<Real>* in, Vec3<Real>* x, Vec3<Real>* p, Vec3<Real>* v, Real* pressure,
  std::int64_t* id, std::uint8_t* liquid)
{
  exec.forEach(GatherStage{}, count, [=] PBF_HD(std::uint32_t k) {
    const std::uint32_t i = first + k;
    const Migrant<Real> m = in[k];
    x[i] = m.x;
    p[i] = m.p;
    v[i] = m.v;
    pressure[i] = m.pressure;
    id[i] = m.id;
    if (liquid)
    {
      liquid[i] = m.liquid;
    }
  });
}

// The particles of one grid column (by position), in their order: the border column that a
// neighbour mirrors.
template <class Real, class Exec>
void selectColumn(Exec& exec, const GridGeometry<Real>& g, std::uint32_t n, const Vec3<Real>* q,
  int column, std::uint32_t* out, std::uint32_t* count)
{
  exec.selectIf(n, PositionInColumn<Real>{ g, q, column }, out, count);
}

// The same after the cell sort, from the sorted keys: sorted indices with a column in
// [begin, end), ascending.
template <class Real, class Exec>
void selectColumns(Exec& exec, int nx, std::uint32_t n, const CellKey* keys, int begin, int end,
  std::uint32_t* out, std::uint32_t* count)
{
  exec.selectIf(n, KeyInColumns<Real>{ keys, nx, begin, end }, out, count);
}

// Seed is GhostSeed<Real> or LiquidSeed<Real> (then `liquid` is the particles' liquids).
template <class Real, class Seed, class Exec>
void packSeeds(Exec& exec, std::uint32_t count, const std::uint32_t* list, const Vec3<Real>* p,
  const std::uint8_t* liquid, Seed* out)
{
  exec.forEach(GatherStage{}, count, [=] PBF_HD(std::uint32_t k) {
    out[k] = Seed::of(list[k], p, liquid);
  });
}

// Ghosts enter with x = p (only the owner updates their velocity) and v = 0 until refreshed.
template <class Real, class Seed, class Exec>
void unpackSeeds(Exec& exec, std::uint32_t first, std::uint32_t count, const Seed* in,
  Vec3<Real>* x, Vec3<Real>* p, Vec3<Real>* v, std::int64_t* id, std::uint8_t* liquid)
{
  exec.forEach(GatherStage{}, count, [=] PBF_HD(std::uint32_t k) {
    const std::uint32_t i = first + k;
    const Seed s = in[k];
    x[i] = s.p;
    p[i] = s.p;
    v[i] = Vec3<Real>{ Real(0), Real(0), Real(0) };
    id[i] = kGhostId;
    s.liquidInto(i, liquid);
  });
}

// Cell keys of positions q, and the identity as the sort's values (as StepSchedule keys them).
template <class Real, class Exec>
void cellKeys(Exec& exec, const GridGeometry<Real>& g, std::uint32_t n, const Vec3<Real>* q,
  CellKey* keys, std::uint32_t* order)
{
  exec.forEach(KeyStage{}, n, [=] PBF_HD(std::uint32_t i) {
    keys[i] = g.keyOf(q[i]);
    order[i] = i;
  });
}

// XSPH and eq. 16 on the velocities in place (each particle reads only its own), as
// DeviceStepLoop's last stage, for the particles of a list; surface tension and the solids'
// images in it compiled in as there (the ghosts' colour gradients and normals are refreshed
// before it).
template <class Real, class Exec>
void confine(Exec& exec, std::uint32_t n, const std::uint32_t* list,
  const FluidView<Real, MaskedNeighbors<Real>>& f)
{
  detail::withConfinementPass(f, [&](auto pass) {
    detail::confinementPass(exec, n, detail::ListedParticles{ list }, f, f.v, pass);
  });
}

// Algorithm 1, line 21, for the particles of a list: v_i = (x*_i - x_i) / dt (adaptive mode, when
// the projections stopped before the one that would have done it).
template <class Real, class Exec>
void updateVelocities(Exec& exec, std::uint32_t n, const std::uint32_t* list,
  const FluidView<Real, MaskedNeighbors<Real>>& f)
{
  exec.forEach(
    CorrectionStage{}, n, [=] PBF_HD(std::uint32_t k) { updateVelocity(list[k], f); });
}

// The fields of one ghost refresh: up to three of type T, the first `count` of `at` used.
template <class T>
struct RefreshFields
{
  T* at[3];
  int count;

  // The non-null ones of a, b, c, in that order.
  static RefreshFields of(T* a, T* b = nullptr, T* c = nullptr)
  {
    RefreshFields f{ { nullptr, nullptr, nullptr }, 0 };
    for (T* p : { a, b, c })
    {
      if (p)
      {
        f.at[f.count++] = p;
      }
    }
    return f;
  }
  std::size_t record() const { return sizeof(T) * static_cast<std::size_t>(count); }
};

// A ghost refresh's message layout, for the fields of type T: to the left neighbour
// [field 0 of its nLeft][field 1 of its nLeft]..., then to the right one the same of nRight. The
// receiver's ghosts from a side are in the order the sender lists them (DeviceSubdomainStepper.h
// says why), so the same layout scatters them.
template <class T, class Exec>
void packFields(Exec& exec, const std::uint32_t* list, std::uint32_t nLeft, std::uint32_t nRight,
  RefreshFields<T> fields, unsigned char* out)
{
  exec.forEach(GatherStage{}, nLeft + nRight, [=] PBF_HD(std::uint32_t k) {
    const bool left = k < nLeft;
    const std::uint32_t count = left ? nLeft : nRight;
    const std::uint32_t j = left ? k : k - nLeft;
    T* region = reinterpret_cast<T*>(out) + (left ? 0u : nLeft * fields.count);
    const std::uint32_t i = list[k];
    for (int f = 0; f < fields.count; ++f)
    {
      region[f * count + j] = fields.at[f][i];
    }
  });
}

template <class T, class Exec>
void scatterFields(Exec& exec, const std::uint32_t* list, std::uint32_t nLeft,
  std::uint32_t nRight, const unsigned char* in, RefreshFields<T> fields)
{
  exec.forEach(GatherStage{}, nLeft + nRight, [=] PBF_HD(std::uint32_t k) {
    const bool left = k < nLeft;
    const std::uint32_t count = left ? nLeft : nRight;
    const std::uint32_t j = left ? k : k - nLeft;
    const T* region = reinterpret_cast<const T*>(in) + (left ? 0u : nLeft * fields.count);
    const std::uint32_t i = list[k];
    for (int f = 0; f < fields.count; ++f)
    {
      fields.at[f][i] = region[f * count + j];
    }
  });
}

} // namespace subdomain
} // namespace cuda
} // namespace pbf
