#include "SubdomainStepper.h"

#include "RankFailure.h"

#include "CellSort.h"
#include "HostParticles.h"
#include "ParticleChecks.h"
#include "LocalRank.h"
#include "RankReductions.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <memory>
#include <stdexcept>
#include <type_traits>

#ifdef PBF_WITH_CUDA
#include "Cuda/CudaSubdomain.h"
#endif

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
  : communicator_(communicator)
  , parallel_(parallel)
  , parameters_(parameters)
{
  parameters_.validate();
  checkBatch(parameters_, everything);
  coefficients_ = Coefficients<Real>::make(parameters_);
  lattice_ = calibrateLattice(parameters_);
  setTimeStep(parameters_.timeStep);
  geometry_ = makeGridGeometry<Real>(parameters_.domain, parameters_.smoothingLength());
  cellOffsets_.assign(std::size_t(geometry_.cellCount()) + 1, 0);
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  sendIndex_.resize(ranks);
  ghostIndex_.resize(ranks);
  slabs_ = Slabs::balanced(std::vector<std::uint64_t>(static_cast<std::size_t>(geometry_.nx), 1),
    communicator_.size());
  append(everything);
}

template <class Real>
Precision SubdomainStepper<Real>::precision() const
{
  return sizeof(Real) == sizeof(float) ? Precision::Single : Precision::Double;
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
  checkBatch(parameters_, batch);
  // Every rank holds the whole batch: each keeps the particles in its slab, so each particle is
  // kept once, and the new cut then balances the counts.
  for (std::size_t i = 0; i < batch.position.size(); ++i)
  {
    const Vec3<Real> q = Vec3<Real>::from(batch.position[i]);
    if (slabs_.owner(column(q)) == communicator_.rank())
    {
      x_.push_back(q);
      v_.push_back(Vec3<Real>::from(batch.velocity[i]));
      id_.push_back(batch.id[i]);
    }
  }
  density_.resize(x_.size());
  lambda_.resize(x_.size());
  cut();
  evaluateAtRest();
}

template <class Real>
void SubdomainStepper<Real>::evaluateAtRest()
{
  // As CpuStepper reports them before a step: no ghosts are refreshed after the density pass,
  // since nothing reads theirs.
  p_ = x_;
  receiveGhosts();
  sortByCell();
  const FluidView<Real> f = view();
  forOwned([&](std::uint32_t i) { densityAndLambda(i, f); });
  dropGhosts();
}

template <class Real>
int SubdomainStepper<Real>::column(const Vec3<Real>& q) const
{
  return geometry_.clampedCell(q.x, geometry_.origin.x, geometry_.nx);
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
void SubdomainStepper<Real>::setTimeStep(double dt)
{
  checkTimeStep(dt);
  dt_ = dt;
  time_ = StepTime<Real>::make(parameters_, lattice_, dt);
}

template <class Real>
FluidView<Real> SubdomainStepper<Real>::view(bool tensile)
{
  FluidView<Real> f{};
  f.x = x_.data();
  f.p = p_.data();
  f.v = v_.data();
  f.density = density_.data();
  f.lambda = lambda_.data();
  f.scratch = scratch_.data();
  f.omega = omega_.data();
  f.grid = GridView<Real>{ geometry_, cellOffsets_.data(), keys_.data() };
  f.c = coefficients_;
  f.time = &time_;
  f.tensile = tensile;
  return f;
}

template <class Real>
void SubdomainStepper<Real>::migrate(bool byPrediction)
{
  const auto start = std::chrono::steady_clock::now();
  const int me = communicator_.rank();
  std::vector<Bytes> out(static_cast<std::size_t>(communicator_.size()));
  std::size_t kept = 0;
  for (std::size_t i = 0; i < x_.size(); ++i)
  {
    const int owner = slabs_.owner(column(byPrediction ? p_[i] : x_[i]));
    if (owner == me)
    {
      x_[kept] = x_[i];
      p_[kept] = p_[i];
      v_[kept] = v_[i];
      id_[kept] = id_[i];
      density_[kept] = density_[i];
      lambda_[kept] = lambda_[i];
      ++kept;
      continue;
    }
    Bytes& b = out[static_cast<std::size_t>(owner)];
    putVec(b, x_[i]);
    putVec(b, p_[i]);
    putVec(b, v_[i]);
    put(b, id_[i]);
    put(b, density_[i]);
    put(b, lambda_[i]);
  }
  x_.resize(kept);
  p_.resize(kept);
  v_.resize(kept);
  id_.resize(kept);
  density_.resize(kept);
  lambda_.resize(kept);
  const std::vector<Bytes> in = communicator_.exchange(out);
  for (const Bytes& b : in)
  {
    for (std::size_t offset = 0; offset < b.size();)
    {
      x_.push_back(takeVec<Real>(b, offset));
      p_.push_back(takeVec<Real>(b, offset));
      v_.push_back(takeVec<Real>(b, offset));
      id_.push_back(take<std::int64_t>(b, offset));
      density_.push_back(take<Real>(b, offset));
      lambda_.push_back(take<Real>(b, offset));
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
  const std::size_t owned = x_.size();
  // Which owned particles each rank mirrors, by index before the sort (mapped after it).
  std::vector<std::vector<std::uint32_t>> sendOriginal(ranks);
  std::vector<Bytes> out(ranks);
  for (std::size_t i = 0; i < owned; ++i)
  {
    const int c = column(p_[i]);
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
      putVec(b, p_[i]);
      put(b, id_[i]);
    }
  }
  const std::vector<Bytes> in = communicator_.exchange(out);
  std::vector<std::int32_t> from(owned, -1);
  for (std::size_t r = 0; r < ranks; ++r)
  {
    for (std::size_t offset = 0; offset < in[r].size();)
    {
      const Vec3<Real> q = takeVec<Real>(in[r], offset);
      x_.push_back(q);
      p_.push_back(q);
      v_.push_back(Vec3<Real>{ Real(0), Real(0), Real(0) });
      id_.push_back(take<std::int64_t>(in[r], offset));
      from.push_back(static_cast<std::int32_t>(r));
    }
  }
  const std::size_t n = x_.size();
  exchange_.ghosts = n - owned;
  density_.resize(n);
  lambda_.resize(n);
  scratch_.resize(n);
  omega_.resize(n);
  keys_.resize(n);
  tag_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    tag_[i] = static_cast<std::uint32_t>(i);
  }
  // Kept for sortByCell, which maps both lists to sorted indices.
  for (std::size_t r = 0; r < ranks; ++r)
  {
    sendIndex_[r] = std::move(sendOriginal[r]);
    ghostIndex_[r].clear();
  }
  ghostFrom_ = std::move(from);
  exchange_.ghostMilliseconds += millisecondsSince(start);
}

template <class Real>
void SubdomainStepper<Real>::sortByCell()
{
  const std::size_t n = x_.size();
  for (std::size_t i = 0; i < n; ++i)
  {
    keys_[i] = geometry_.keyOf(p_[i]);
  }
  countingSortByCell(keys_, cellOffsets_, order_, cursor_);
  // Into scratch kept from step to step, as CpuStepper gathers: nothing allocated once the
  // arrays have their size.
  auto gather = [&](auto& array, auto& scratch) {
    scratch.resize(n);
    for (std::size_t k = 0; k < n; ++k)
    {
      scratch[k] = array[order_[k]];
    }
    array.swap(scratch);
  };
  gather(x_, gatherVec_);
  gather(p_, gatherVec_);
  gather(v_, gatherVec_);
  gather(id_, gatherId_);
  gather(keys_, gatherIndex_);
  gather(tag_, gatherIndex_);
  gather(ghostFrom_, gatherFrom_);
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
  keep(x_);
  keep(p_);
  keep(v_);
  keep(id_);
  keep(density_);
  keep(lambda_);
  ghostFrom_.assign(owned, -1);
}

template <class Real>
Compression SubdomainStepper<Real>::compression()
{
  // In fixed blocks per rank, then the ranks in order: deterministic, though summed in another
  // order than the serial backend's blocks.
  double sum = 0.0, largest = 0.0;
  const double inverseRho0 = 1.0 / parameters_.restDensity;
  for (std::uint32_t i : owned_)
  {
    const double e = std::max(double(density_[i]) * inverseRho0 - 1.0, 0.0);
    sum += e;
    largest = std::max(largest, e);
  }
  double total = 0.0, count = 0.0;
  Compression c;
  for (const std::vector<double>& r :
    allGather(communicator_, { sum, double(owned_.size()), largest }))
  {
    total += r[0];
    count += r[1];
    c.max = std::max(c.max, r[2]);
  }
  c.mean = count > 0 ? total / count : 0.0;
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
  cut();
  {
    owned_.resize(x_.size());
    for (std::size_t i = 0; i < owned_.size(); ++i)
    {
      owned_[i] = static_cast<std::uint32_t>(i);
    }
    p_.resize(x_.size());
    scratch_.resize(x_.size());
    omega_.resize(x_.size());
    keys_.resize(x_.size());
    const FluidView<Real> f = view();
    forOwned([&](std::uint32_t i) { predictPosition(i, f); });
  }
  migrate(true);
  receiveGhosts();
  // Neighbours are found once per step, on the predicted positions (Algorithm 1, line 7).
  sortByCell();
  const FluidView<Real> f = view();
  const FluidView<Real> first = view(true); // the first projection adds s_corr
  const bool adaptive = parameters_.densityErrorTolerance > 0;
  for (int iteration = 0; iteration < parameters_.solverIterations; ++iteration)
  {
    forOwned([&](std::uint32_t i) { densityAndLambda(i, f); });
    refreshGhosts([&](std::uint32_t i) -> Real& { return density_[i]; });
    refreshGhosts([&](std::uint32_t i) -> Real& { return lambda_[i]; });
    if (adaptive)
    {
      const Compression c = compression();
      report_.densityError = c.mean;
      if (iteration > 0 &&
        c.within(parameters_.densityErrorTolerance, parameters_.maxDensityErrorTolerance))
      {
        break;
      }
    }
    const FluidView<Real>& pass = iteration == 0 ? first : f;
    forOwned([&](std::uint32_t i) { positionCorrection(i, pass); });
    forOwned([&](std::uint32_t i) { applyCorrection(i, f); });
    refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return p_[i]; });
    ++report_.iterations;
  }
  if (!adaptive)
  {
    report_.densityError = std::numeric_limits<double>::quiet_NaN();
  }
  forOwned([&](std::uint32_t i) { updateVelocity(i, f); });
  refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return v_[i]; });
  forOwned([&](std::uint32_t i) { vorticityAndXsph(i, f); });
  refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return omega_[i]; });
  forOwned([&](std::uint32_t i) { vorticityConfinement(i, f); });
  forOwned([&](std::uint32_t i) { commitPosition(i, f, x_.data()); });
  dropGhosts();
}

template <class Real>
std::vector<std::uint64_t> SubdomainStepper<Real>::particlesPerRank() const
{
  return countsPerRank(communicator_, x_.size());
}

template <class Real>
void SubdomainStepper<Real>::cut()
{
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> mine(static_cast<std::size_t>(geometry_.nx), 0.0);
  for (const Vec3<Real>& q : x_)
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
  p_.resize(x_.size());
  migrate(false);
}

template <class Real>
Health SubdomainStepper<Real>::health() const
{
  return reduceHealth(communicator_, parameters_, particles());
}

template <class Real>
template <class In>
void SubdomainStepper<Real>::loadState(const Snapshot<In>& state)
{
  loadFromSnapshot(state, particles());
  // The next step cuts the slabs from this state, as the run that took it did.
}

template <class Real>
template <class Out>
void SubdomainStepper<Real>::copyOut(Snapshot<Out>& out) const
{
  copyToSnapshot(particles(), out);
}

template <class Real>
Statistics SubdomainStepper<Real>::statistics() const
{
  return reduceStatistics(communicator_, parameters_, particles());
}

template <class Real>
void SubdomainStepper<Real>::read(Snapshot<float>& out) const
{
  copyOut(out);
}

template <class Real>
void SubdomainStepper<Real>::read(Snapshot<double>& out) const
{
  copyOut(out);
}

template <class Real>
void SubdomainStepper<Real>::load(const Snapshot<float>& state)
{
  loadState(state);
}

template <class Real>
void SubdomainStepper<Real>::load(const Snapshot<double>& state)
{
  loadState(state);
}

std::unique_ptr<Stepper> makeSubdomainStepper(Communicator& communicator, Backend backend,
  Precision precision, const Parameters& parameters, const ParticleBatch& everything)
{
  if (backend == Backend::CUDA)
  {
#ifdef PBF_WITH_CUDA
    // Collective: every rank asks for CUDA, and they agree on whether all have a device before
    // any constructs, so that a rank without one does not leave the others waiting for it in
    // the first exchange: then every rank throws.
    const int local = localRank(communicator);
    const int devices = cuda::cudaDeviceCount();
    std::string why;
    const bool mine = devices > 0 && cudaAvailable(&why);
    if (!everyRankHasAGpu(communicator))
    {
      throw std::runtime_error("CUDA backend unavailable on " +
        (mine ? std::string("another rank") :
                "rank " + std::to_string(communicator.rank()) + ": " +
              (why.empty() ? "no CUDA device" : why)) +
        "; a decomposed run needs a GPU on every rank for Backend = CUDA (Auto falls back to "
        "the CPU on every rank)");
    }
    return cuda::makeCudaSubdomainStepper(
      communicator, precision, parameters, everything, local % devices);
#else
    throw std::runtime_error("Backend = CUDA: this build has no CUDA backend (CUDA compiler not "
                             "found at configure time); choose CPU (OpenMP) or Serial");
#endif
  }
  const bool parallel = backend == Backend::OpenMP;
  if (precision == Precision::Single)
  {
    return std::make_unique<SubdomainStepper<float>>(communicator, parallel, parameters, everything);
  }
  return std::make_unique<SubdomainStepper<double>>(communicator, parallel, parameters, everything);
}

bool everyRankHasAGpu(Communicator& communicator)
{
  double mine = 0;
#ifdef PBF_WITH_CUDA
  mine = cudaAvailable() && cuda::cudaDeviceCount() > 0 ? 1.0 : 0.0;
#endif
  bool all = true;
  for (const std::vector<double>& r : allGather(communicator, { mine }))
  {
    all = all && r[0] != 0;
  }
  return all;
}

std::unique_ptr<Stepper> makeSubdomainStepperAuto(Communicator& communicator, Precision precision,
  const Parameters& parameters, const ParticleBatch& everything, Backend cpu)
{
  const Backend backend = everyRankHasAGpu(communicator) ? Backend::CUDA : cpu;
  return makeSubdomainStepper(communicator, backend, precision, parameters, everything);
}

template class SubdomainStepper<float>;
template class SubdomainStepper<double>;

} // namespace pbf::distributed
