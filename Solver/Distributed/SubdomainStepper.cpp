// SubdomainStepper's own: its slab of the fluid kept and its memory planned, the step's stages
// over the owned particles, and the sums over the ranks. Its exchanges with the other ranks (the
// cut, migration, ghosts): SubdomainExchange.cpp.
#include "SubdomainStepper.h"

#include "HostMemory.h"

#include "RankFailure.h"

#include "CellSort.h"
#include "HostParticles.h"
#include "ParticleChecks.h"
#include "RankReductions.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pbf::distributed
{

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
  // The pressure's mean goes on (the sort carried it); appended particles start at 0.
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
std::vector<std::uint64_t> SubdomainStepper<Real>::particlesPerRank() const
{
  return countsPerRank(communicator_, fluid_.x.size());
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
