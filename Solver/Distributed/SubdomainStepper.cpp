#include "SubdomainStepper.h"

#include "HostMemory.h"

#include "RankFailure.h"

#include "CellSort.h"
#include "HostParticles.h"
#include "ParticleChecks.h"
#include "RankReductions.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pbf::distributed
{

namespace
{

double millisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
    .count();
}

template <class Real>
void putVec(Bytes& b, const Vec3<Real>& v)
{
  put(b, v.x);
  put(b, v.y);
  put(b, v.z);
}

template <class Real>
Vec3<Real> takeVec(const Bytes& b, std::size_t& offset)
{
  Vec3<Real> v;
  v.x = take<Real>(b, offset);
  v.y = take<Real>(b, offset);
  v.z = take<Real>(b, offset);
  return v;
}

} // namespace

template <class Real>
SubdomainStepper<Real>::SubdomainStepper(Communicator& communicator, bool parallel,
  const Parameters& parameters, const ParticleBatch& everything)
  : SubdomainStepper(communicator, parallel, parameters,
      BatchSource((checkBatch(parameters, everything), everything)))
{
}

// The balanced cut from every rank's count of the whole fluid per column (the same on every
// rank), and this rank's slab of it: no rank holds the whole fluid, and nothing migrates before
// the first step.
template <class Real>
SubdomainStepper<Real>::SubdomainStepper(Communicator& communicator, bool parallel,
  const Parameters& parameters, const FluidSource& fluid)
  : HostStepper<DecomposedStepper, Real>(parallel, parameters)
  , communicator_(communicator)
  , columns_(fluid_.geometry)
{
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  sendIndex_.resize(ranks);
  ghostIndex_.resize(ranks);
  const std::vector<std::uint64_t> perColumn = fluid.countPerColumn(
    [&](const Vec3d& q) { return static_cast<std::size_t>(column(Vec3<Real>::from(q))); },
    static_cast<std::size_t>(columns_.nx));
  slabs_ = Slabs::balanced(perColumn, communicator_.size());
  // A particle that fails its check, or a share that the host cannot hold, fails every rank
  // alike, before the collectives that follow.
  together(communicator_, [&] {
    reserveParticles(slabs_.plannedCapacity(perColumn, communicator_.rank()));
    // A neighbour's border lists: one column, as large as the largest, and as much swing.
    const std::uint64_t largest = *std::max_element(perColumn.begin(), perColumn.end());
    for (int r : { communicator_.rank() - 1, communicator_.rank() + 1 })
    {
      if (r >= 0 && r < communicator_.size())
      {
        sendIndex_[static_cast<std::size_t>(r)].reserve(2 * largest);
        ghostIndex_[static_cast<std::size_t>(r)].reserve(2 * largest);
      }
    }
    keepOwn(fluid, true);
  });
  cut();
  evaluateAtRest();
}

template <class Real>
std::string SubdomainStepper<Real>::description() const
{
  std::string threads = "Serial";
#ifdef _OPENMP
  if (parallel_)
  {
    threads = "OpenMP, " + std::to_string(omp_get_max_threads()) + " threads";
  }
#endif
  return threads + ", rank " + std::to_string(communicator_.rank()) + " of " +
    std::to_string(communicator_.size()) + " (grid columns " +
    std::to_string(slabs_.first[static_cast<std::size_t>(communicator_.rank())]) + "-" +
    std::to_string(slabs_.first[static_cast<std::size_t>(communicator_.rank()) + 1] - 1) + " of " +
    std::to_string(slabs_.columns()) + " along x)";
}

template <class Real>
void SubdomainStepper<Real>::append(const ParticleBatch& batch)
{
  checkBatch(fluid_.parameters, batch);
  // Every rank holds the whole batch: each keeps the particles in its slab, so each particle is
  // kept once, and the new cut then balances the counts.
  keepOwn(BatchSource(batch), false);
  cut();
  evaluateAtRest();
}

template <class Real>
void SubdomainStepper<Real>::keepOwn(const FluidSource& fluid, bool check)
{
  const int me = communicator_.rank();
  const bool liquids = !fluid_.parameters.liquids.empty();
  fluid.forEachOwned([&](const Vec3d& q) { return slabs_.owner(column(Vec3<Real>::from(q))); }, me,
    [&](const Vec3d& x, const Vec3d& v, std::int64_t id, std::uint8_t liquid) {
      if (check)
      {
        checkParticle(fluid_.parameters, id, x, v);
        checkLiquid(fluid_.parameters, id, liquid);
      }
      roomFor(fluid_.x.size() + 1);
      fluid_.x.push_back(Vec3<Real>::from(x));
      fluid_.v.push_back(Vec3<Real>::from(v));
      fluid_.id.push_back(id);
      if (liquids)
      {
        fluid_.liquid.push_back(liquid);
      }
    });
  fluid_.density.resize(fluid_.x.size());
  fluid_.lambda.resize(fluid_.x.size());
  fluid_.pressure.resize(fluid_.x.size());
}

template <class Real>
std::size_t SubdomainStepper<Real>::bytesPerParticle() const
{
  // The fluid's arrays, and tag_, owned_, ghostFrom_ and the sort's gathers of the last two.
  return fluid_.bytesPerParticle() + 3 * sizeof(std::uint32_t) + 2 * sizeof(std::int32_t);
}

template <class Real>
void SubdomainStepper<Real>::reserveParticles(std::size_t count)
{
  if (count <= capacity_)
  {
    return;
  }
  const std::size_t more = (count - capacity_) * bytesPerParticle();
  const std::size_t available = availableHostBytes();
  if (more > available)
  {
    std::ostringstream text;
    text << "particle count = " << fluid_.x.size() << " (capacity " << count << ") on rank "
         << communicator_.rank() << " of " << communicator_.size() << ": its CPU sub-domain needs "
         << (more >> 20) << " MiB more for its particle arrays (" << bytesPerParticle()
         << " bytes a particle), but the host has " << (available >> 20)
         << " MiB available; use more ranks (on more hosts) or a larger particleSpacing";
    throw InvalidInput(text.str());
  }
  fluid_.reserveParticles(count);
  tag_.reserve(count);
  owned_.reserve(count);
  ghostFrom_.reserve(count);
  gatherIndex_.reserve(count);
  gatherFrom_.reserve(count);
  capacity_ = count;
}

template <class Real>
void SubdomainStepper<Real>::roomForCells(int columns)
{
  const std::size_t perColumn = static_cast<std::size_t>(columns_.ny) * columns_.nz;
  const std::size_t cells = static_cast<std::size_t>(columns) * perColumn + 1;
  if (cells > fluid_.cellOffsets.capacity())
  {
    // An eighth more, four columns at least: the window follows the fluid and the cut a column
    // or so at a time, and a column's cells cost a tenth of its particles' arrays.
    const std::size_t room =
      std::min(cells + std::max(4 * perColumn, cells / 8), std::size_t(columns_.cellCount()) + 1);
    fluid_.cellOffsets.reserve(room);
    fluid_.cursor.reserve(room);
  }
}

template <class Real>
void SubdomainStepper<Real>::roomFor(std::size_t n)
{
  if (n > capacity_)
  {
    reserveParticles(std::max(n, capacity_ + capacity_ / 16 + 1));
  }
}

template <class Real>
std::size_t SubdomainStepper<Real>::hostBytes() const
{
  auto bytes = [](const auto& a) { return a.capacity() * sizeof(a[0]); };
  std::size_t lists = 0;
  for (const auto* perRank : { &sendIndex_, &ghostIndex_ })
  {
    for (const std::vector<std::uint32_t>& list : *perRank)
    {
      lists += bytes(list);
    }
  }
  return fluid_.heldBytes() + bytes(tag_) + bytes(owned_) + bytes(ghostFrom_) +
    bytes(gatherIndex_) + bytes(gatherFrom_) + lists;
}

template <class Real>
std::size_t SubdomainStepper<Real>::removeOutflow(const std::vector<Box>& zones)
{
  // Between steps the arrays hold the owned particles only (dropGhosts), so a removal here is the
  // serial backend's on this rank's share.
  std::size_t mine = 0;
  together(communicator_, [&] {
    mine = removeInside(OutflowZones<Real>::make(zones), fluid_.particles());
  });
  const std::size_t n = fluid_.x.size();
  owned_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    owned_[i] = static_cast<std::uint32_t>(i);
  }
  ghostFrom_.assign(n, -1);
  double removed = 0;
  for (const std::vector<double>& r : allGather(communicator_, { static_cast<double>(mine) }))
  {
    removed += r[0];
  }
  return static_cast<std::size_t>(removed);
}

template <class Real>
void SubdomainStepper<Real>::evaluateAtRest()
{
  // As CpuStepper reports them before a step: no ghosts are refreshed after the density pass,
  // since nothing reads theirs.
  fluid_.p = fluid_.x;
  receiveGhosts();
  sortByCell();
  const FluidView<Real> f = fluid_.view();
  forOwned([&](std::uint32_t i) { densityAndLambda(i, f); });
  dropGhosts();
  // No step has corrected these positions: no pressure yet.
  std::fill(fluid_.pressure.begin(), fluid_.pressure.end(), Real(0));
}

template <class Real>
int SubdomainStepper<Real>::column(const Vec3<Real>& q) const
{
  return columns_.clampedCell(q.x, columns_.origin.x, columns_.nx);
}

template <class Real>
template <class Stage>
void SubdomainStepper<Real>::forOwned(Stage&& stage)
{
  const auto n = static_cast<std::int64_t>(owned_.size());
#pragma omp parallel for schedule(static) if (parallel_)
  for (std::int64_t k = 0; k < n; ++k)
  {
    stage(owned_[static_cast<std::size_t>(k)]);
  }
}

template <class Real>
void SubdomainStepper<Real>::migrate(bool byPrediction)
{
  const auto start = std::chrono::steady_clock::now();
  const int me = communicator_.rank();
  std::vector<Bytes> out(static_cast<std::size_t>(communicator_.size()));
  std::size_t kept = 0;
  const bool liquids = !fluid_.parameters.liquids.empty();
  for (std::size_t i = 0; i < fluid_.x.size(); ++i)
  {
    const int owner = slabs_.owner(column(byPrediction ? fluid_.p[i] : fluid_.x[i]));
    if (owner == me)
    {
      fluid_.x[kept] = fluid_.x[i];
      fluid_.p[kept] = fluid_.p[i];
      fluid_.v[kept] = fluid_.v[i];
      fluid_.id[kept] = fluid_.id[i];
      fluid_.density[kept] = fluid_.density[i];
      fluid_.lambda[kept] = fluid_.lambda[i];
      fluid_.pressure[kept] = fluid_.pressure[i];
      if (liquids)
      {
        fluid_.liquid[kept] = fluid_.liquid[i];
      }
      ++kept;
      continue;
    }
    Bytes& b = out[static_cast<std::size_t>(owner)];
    putVec(b, fluid_.x[i]);
    putVec(b, fluid_.p[i]);
    putVec(b, fluid_.v[i]);
    put(b, fluid_.id[i]);
    put(b, fluid_.density[i]);
    put(b, fluid_.lambda[i]);
    put(b, fluid_.pressure[i]);
    if (liquids)
    {
      put(b, fluid_.liquid[i]);
    }
  }
  fluid_.x.resize(kept);
  fluid_.p.resize(kept);
  fluid_.v.resize(kept);
  fluid_.id.resize(kept);
  fluid_.density.resize(kept);
  fluid_.lambda.resize(kept);
  fluid_.pressure.resize(kept);
  fluid_.liquid.resize(liquids ? kept : 0);
  const std::vector<Bytes> in = communicator_.exchange(out);
  out.clear();
  std::size_t arriving = 0;
  const std::size_t record = 3 * sizeof(Vec3<Real>) + sizeof(std::int64_t) + 3 * sizeof(Real) +
    (liquids ? sizeof(std::uint8_t) : 0);
  for (const Bytes& b : in)
  {
    arriving += b.size() / record;
  }
  roomFor(kept + arriving);
  for (const Bytes& b : in)
  {
    for (std::size_t offset = 0; offset < b.size();)
    {
      fluid_.x.push_back(takeVec<Real>(b, offset));
      fluid_.p.push_back(takeVec<Real>(b, offset));
      fluid_.v.push_back(takeVec<Real>(b, offset));
      fluid_.id.push_back(take<std::int64_t>(b, offset));
      fluid_.density.push_back(take<Real>(b, offset));
      fluid_.lambda.push_back(take<Real>(b, offset));
      fluid_.pressure.push_back(take<Real>(b, offset));
      if (liquids)
      {
        fluid_.liquid.push_back(take<std::uint8_t>(b, offset));
      }
      ++exchange_.migrated;
    }
  }
  exchange_.migrationMilliseconds += millisecondsSince(start);
}

template <class Real>
void SubdomainStepper<Real>::receiveGhosts()
{
  const auto start = std::chrono::steady_clock::now();
  const int me = communicator_.rank();
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  const std::size_t owned = fluid_.x.size();
  // Which owned particles each rank mirrors, by index before the sort (mapped after it).
  std::vector<std::vector<std::uint32_t>> sendOriginal(ranks);
  std::vector<Bytes> out(ranks);
  const bool liquids = !fluid_.parameters.liquids.empty();
  for (std::size_t i = 0; i < owned; ++i)
  {
    const int c = column(fluid_.p[i]);
    const int left = c > 0 ? slabs_.owner(c - 1) : me;
    const int right = c + 1 < slabs_.columns() ? slabs_.owner(c + 1) : me;
    for (int to : { left, right })
    {
      if (to == me || (to == right && right == left))
      {
        continue;
      }
      sendOriginal[static_cast<std::size_t>(to)].push_back(static_cast<std::uint32_t>(i));
      Bytes& b = out[static_cast<std::size_t>(to)];
      putVec(b, fluid_.p[i]);
      put(b, fluid_.id[i]);
      if (liquids)
      {
        put(b, fluid_.liquid[i]);
      }
    }
  }
  const std::vector<Bytes> in = communicator_.exchange(out);
  out.clear();
  std::size_t arriving = 0;
  const std::size_t record = sizeof(Vec3<Real>) + sizeof(std::int64_t) + (liquids ? sizeof(std::uint8_t) : 0);
  for (const Bytes& b : in)
  {
    arriving += b.size() / record;
  }
  roomFor(owned + arriving);
  std::vector<std::int32_t> from;
  from.reserve(capacity_);
  from.assign(owned, -1);
  for (std::size_t r = 0; r < ranks; ++r)
  {
    for (std::size_t offset = 0; offset < in[r].size();)
    {
      const Vec3<Real> q = takeVec<Real>(in[r], offset);
      fluid_.x.push_back(q);
      fluid_.p.push_back(q);
      fluid_.v.push_back(Vec3<Real>{ Real(0), Real(0), Real(0) });
      fluid_.id.push_back(take<std::int64_t>(in[r], offset));
      if (liquids)
      {
        fluid_.liquid.push_back(take<std::uint8_t>(in[r], offset));
      }
      from.push_back(static_cast<std::int32_t>(r));
    }
  }
  const std::size_t n = fluid_.x.size();
  exchange_.ghosts = n - owned;
  fluid_.density.resize(n);
  fluid_.lambda.resize(n);
  fluid_.pressure.resize(n);
  fluid_.scratch.resize(n);
  fluid_.omega.resize(n);
  fluid_.colour.resize(fluid_.coefficients.surfaceTension ? n : 0);
  fluid_.normal.resize(fluid_.coefficients.surfaceTension ? n : 0);
  fluid_.keys.resize(n);
  tag_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    tag_[i] = static_cast<std::uint32_t>(i);
  }
  // Kept for sortByCell, which maps both lists to sorted indices.
  for (std::size_t r = 0; r < ranks; ++r)
  {
    sendIndex_[r].assign(sendOriginal[r].begin(), sendOriginal[r].end()); // keeps the planned room
    ghostIndex_[r].clear();
  }
  ghostFrom_ = std::move(from);
  exchange_.ghostMilliseconds += millisecondsSince(start);
}

template <class Real>
void SubdomainStepper<Real>::sortByCell()
{
  const std::size_t n = fluid_.x.size();
  // The window: the columns of the particles sorted (owned and ghosts), so that the cells are
  // this rank's share of the domain's; a key is the domain's column offset, the same order.
  int lo = columns_.nx, hi = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const int c = column(fluid_.p[i]);
    lo = std::min(lo, c);
    hi = std::max(hi, c + 1);
  }
  fluid_.geometry.firstColumn = lo < hi ? lo : 0;
  fluid_.geometry.nx = lo < hi ? hi - lo : 1;
  roomForCells(fluid_.geometry.nx);
  // Serially over owned particles and ghosts, as before this rank knows which are which.
  fluid_.sortByCell(
    [n](auto&& f) {
      for (std::size_t i = 0; i < n; ++i)
      {
        f(static_cast<std::uint32_t>(i));
      }
    },
    [&](auto&& gather) {
      gather(tag_, gatherIndex_);
      gather(ghostFrom_, gatherFrom_);
    });
  // Sorted index of each pre-sort index; ghosts keep their arrival order per rank, which is the
  // order in which their owner packs their fields.
  std::vector<std::uint32_t>& sortedOf = gatherIndex_;
  sortedOf.resize(n);
  owned_.clear();
  for (std::size_t k = 0; k < n; ++k)
  {
    sortedOf[tag_[k]] = static_cast<std::uint32_t>(k);
  }
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::uint32_t k = sortedOf[i];
    if (ghostFrom_[k] >= 0)
    {
      ghostIndex_[static_cast<std::size_t>(ghostFrom_[k])].push_back(k);
    }
  }
  for (std::size_t k = 0; k < n; ++k)
  {
    if (ghostFrom_[k] < 0)
    {
      owned_.push_back(static_cast<std::uint32_t>(k));
    }
  }
  for (auto& list : sendIndex_)
  {
    for (std::uint32_t& i : list)
    {
      i = sortedOf[i];
    }
  }
}

template <class Real>
template <class Field>
void SubdomainStepper<Real>::refreshGhosts(Field field)
{
  const auto start = std::chrono::steady_clock::now();
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  std::vector<Bytes> out(ranks);
  for (std::size_t r = 0; r < ranks; ++r)
  {
    for (std::uint32_t i : sendIndex_[r])
    {
      put(out[r], field(i));
    }
  }
  const std::vector<Bytes> in = communicator_.exchange(out);
  for (std::size_t r = 0; r < ranks; ++r)
  {
    std::size_t offset = 0;
    for (std::uint32_t i : ghostIndex_[r])
    {
      field(i) = take<std::remove_reference_t<decltype(field(i))>>(in[r], offset);
    }
  }
  exchange_.ghostMilliseconds += millisecondsSince(start);
}

template <class Real>
void SubdomainStepper<Real>::dropGhosts()
{
  const std::size_t owned = owned_.size();
  auto keep = [&](auto& array) {
    for (std::size_t k = 0; k < owned; ++k)
    {
      array[k] = array[owned_[k]]; // owned_ is increasing: never overwrites one still to read
    }
    array.resize(owned);
  };
  keep(fluid_.x);
  keep(fluid_.p);
  keep(fluid_.v);
  keep(fluid_.id);
  keep(fluid_.density);
  keep(fluid_.lambda);
  keep(fluid_.pressure);
  if (!fluid_.liquid.empty())
  {
    keep(fluid_.liquid);
  }
  ghostFrom_.assign(owned, -1);
}

template <class Real>
Compression SubdomainStepper<Real>::compression()
{
  // In fixed blocks per rank, then the ranks in order: deterministic, though summed in another
  // order than the serial backend's blocks.
  // With several liquids, each liquid's sum and count (the mean is the most compressed liquid's).
  const std::size_t liquids = static_cast<std::size_t>(fluid_.parameters.liquidCount());
  std::vector<double> mine(2 * liquids + 1, 0.0); // sums, counts, the largest
  const double inverseRho0 = 1.0 / fluid_.parameters.restDensity;
  for (std::uint32_t i : owned_)
  {
    const double e = std::max(double(fluid_.density[i]) * inverseRho0 - 1.0, 0.0);
    const std::size_t l = fluid_.liquid.empty() ? 0 : fluid_.liquid[i];
    mine[l] += e;
    mine[liquids + l] += 1.0;
    mine[2 * liquids] = std::max(mine[2 * liquids], e);
  }
  std::vector<double> total(2 * liquids, 0.0);
  Compression c;
  for (const std::vector<double>& r : allGather(communicator_, mine))
  {
    for (std::size_t k = 0; k < 2 * liquids; ++k)
    {
      total[k] += r[k];
    }
    c.max = std::max(c.max, r[2 * liquids]);
  }
  for (std::size_t l = 0; l < liquids; ++l)
  {
    c.mean = std::max(c.mean, total[liquids + l] > 0 ? total[l] / total[liquids + l] : 0.0);
  }
  return c;
}

template <class Real>
void SubdomainStepper<Real>::step()
{
  // A rank that fails mid-step (its memory, say) stops every rank with the same error.
  together(communicator_, [&] { stepAlone(); });
}

template <class Real>
void SubdomainStepper<Real>::stepAlone()
{
  exchange_ = ExchangeReport{};
  report_ = StepReport{};
  HostStepLoop<Real, SubdomainStepper> loop(fluid_, *this, report_);
  runStep(loop, SolveRule::of(fluid_.parameters));
  dropGhosts();
}

template <class Real>
void SubdomainStepper<Real>::predict()
{
  cut();
  owned_.resize(fluid_.x.size());
  for (std::size_t i = 0; i < owned_.size(); ++i)
  {
    owned_[i] = static_cast<std::uint32_t>(i);
  }
  fluid_.p.resize(fluid_.x.size());
  fluid_.scratch.resize(fluid_.x.size());
  fluid_.omega.resize(fluid_.x.size());
  fluid_.colour.resize(fluid_.coefficients.surfaceTension ? fluid_.x.size() : 0);
  fluid_.normal.resize(fluid_.coefficients.surfaceTension ? fluid_.x.size() : 0);
  fluid_.keys.resize(fluid_.x.size());
  const FluidView<Real> f = fluid_.view();
  forOwned([&](std::uint32_t i) { predictPosition(i, f); });
}

template <class Real>
void SubdomainStepper<Real>::findNeighbours()
{
  migrate(true);
  receiveGhosts();
  sortByCell();
}

template <class Real>
std::vector<double> SubdomainStepper<Real>::sumOverRanks(const std::vector<double>& mine)
{
  return sumInRankOrder(communicator_, mine);
}

template <class Real>
void SubdomainStepper<Real>::refresh(HostField field)
{
  switch (field)
  {
    case HostField::DensityAndLambda:
      refreshGhosts([&](std::uint32_t i) -> Real& { return fluid_.density[i]; });
      refreshGhosts([&](std::uint32_t i) -> Real& { return fluid_.lambda[i]; });
      break;
    case HostField::Predicted:
      refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.p[i]; });
      break;
    case HostField::Velocity:
      refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.v[i]; });
      break;
    case HostField::Vorticity:
      refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.omega[i]; });
      if (fluid_.parameters.xsphHyperViscosity > 0)
      {
        // XSPH's sum (HostFluid::view puts it in scratch), which the bi-Laplacian smooths.
        refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.scratch[i]; });
      }
      if (!fluid_.colour.empty())
      {
        // grad c, whose normals the confinement's surface tension reads (SurfaceTension.h).
        refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.colour[i]; });
      }
      break;
    case HostField::Normal:
      refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.normal[i]; });
      break;
  }
}

template <class Real>
std::vector<std::uint64_t> SubdomainStepper<Real>::particlesPerRank() const
{
  return countsPerRank(communicator_, fluid_.x.size());
}

template <class Real>
void SubdomainStepper<Real>::cut()
{
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> mine(static_cast<std::size_t>(columns_.nx), 0.0);
  for (const Vec3<Real>& q : fluid_.x)
  {
    mine[static_cast<std::size_t>(column(q))] += 1.0;
  }
  std::vector<std::uint64_t> perColumn(mine.size(), 0);
  for (const std::vector<double>& r : allGather(communicator_, mine))
  {
    for (std::size_t c = 0; c < r.size(); ++c)
    {
      perColumn[c] += static_cast<std::uint64_t>(r[c]);
    }
  }
  const Slabs balanced = Slabs::balanced(perColumn, communicator_.size());
  exchange_.cutMoved = balanced.first != slabs_.first;
  slabs_ = balanced;
  exchange_.migrationMilliseconds += millisecondsSince(start);
  fluid_.p.resize(fluid_.x.size());
  migrate(false);
}

template <class Real>
Health SubdomainStepper<Real>::health() const
{
  return reduceHealth(communicator_, fluid_.parameters, fluid_.particles());
}

template <class Real>
Statistics SubdomainStepper<Real>::statistics() const
{
  return reduceStatistics(communicator_, fluid_.parameters, fluid_.particles());
}

template class SubdomainStepper<float>;
template class SubdomainStepper<double>;

} // namespace pbf::distributed
