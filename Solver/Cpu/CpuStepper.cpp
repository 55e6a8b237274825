#include "CpuStepper.h"

#include "CellSort.h"
#include "HostParticles.h"
#include "ParticleChecks.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pbf
{

template <class Real>
CpuStepper<Real>::CpuStepper(bool parallel, const Parameters& parameters,
  const ParticleBatch& initial)
  : parallel_(parallel)
  , parameters_(parameters)
{
  parameters_.validate();
  checkBatch(parameters_, initial);
  coefficients_ = Coefficients<Real>::make(parameters_);
  lattice_ = calibrateLattice(parameters_);
  setTimeStep(parameters_.timeStep);
  geometry_ = makeGridGeometry<Real>(parameters_.domain, parameters_.smoothingLength());
  cellOffsets_.assign(std::size_t(geometry_.cellCount()) + 1, 0);
  append(initial);
}

template <class Real>
Precision CpuStepper<Real>::precision() const
{
  return sizeof(Real) == sizeof(float) ? Precision::Single : Precision::Double;
}

template <class Real>
std::string CpuStepper<Real>::description() const
{
  if (!parallel_)
  {
    return "Serial";
  }
#ifdef _OPENMP
  return "OpenMP, " + std::to_string(omp_get_max_threads()) + " threads";
#else
  return "OpenMP requested, built without OpenMP: 1 thread";
#endif
}

template <class Real>
template <class Stage>
void CpuStepper<Real>::forEachParticle(Stage&& stage)
{
  const auto n = static_cast<std::int64_t>(x_.size());
#pragma omp parallel for schedule(static) if (parallel_)
  for (std::int64_t i = 0; i < n; ++i)
  {
    stage(static_cast<std::uint32_t>(i));
  }
}

template <class Real>
void CpuStepper<Real>::setTimeStep(double dt)
{
  checkTimeStep(dt);
  dt_ = dt;
  time_ = StepTime<Real>::make(parameters_, lattice_, dt);
}

template <class Real>
FluidView<Real> CpuStepper<Real>::view(bool tensile)
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
void CpuStepper<Real>::sortByCell()
{
  const std::size_t n = x_.size();
  forEachParticle([&](std::uint32_t i) { keys_[i] = geometry_.keyOf(p_[i]); });

  // O(N + cells) and serial in both CPU backends; the per-particle stages dominate.
  countingSortByCell(keys_, cellOffsets_, order_, cursor_);

  auto gather = [&](auto& array, auto& tmp) {
    tmp.resize(n);
    forEachParticle([&](std::uint32_t i) { tmp[i] = array[order_[i]]; });
    array.swap(tmp);
  };
  gather(x_, gatherVec_);
  gather(p_, gatherVec_);
  gather(v_, gatherVec_);
  gather(id_, gatherId_);
  gather(keys_, gatherKey_);
}

template <class Real>
void CpuStepper<Real>::evaluateDensityAtRest()
{
  p_ = x_;
  sortByCell();
  const FluidView<Real> f = view();
  forEachParticle([&](std::uint32_t i) { densityAndLambda(i, f); });
}

template <class Real>
void CpuStepper<Real>::step()
{
  if (x_.empty())
  {
    return;
  }
  {
    const FluidView<Real> f = view();
    forEachParticle([&](std::uint32_t i) { predictPosition(i, f); });
  }
  // Neighbours are found once per step, on the predicted positions (Algorithm 1, line 7).
  sortByCell();
  const FluidView<Real> f = view();
  const FluidView<Real> first = view(true); // the first projection adds s_corr
  const bool adaptive = parameters_.densityErrorTolerance > 0;
  report_ = StepReport{};
  for (int iteration = 0; iteration < parameters_.solverIterations; ++iteration)
  {
    forEachParticle([&](std::uint32_t i) { densityAndLambda(i, f); });
    if (adaptive)
    {
      // Adaptive mode: the constraint already holds well enough, no need to project again. The
      // first projection always runs: it carries the step's tensile push.
      const Compression c = compression();
      report_.densityError = c.mean;
      if (iteration > 0 &&
        c.within(parameters_.densityErrorTolerance, parameters_.maxDensityErrorTolerance))
      {
        break;
      }
    }
    const FluidView<Real>& pass = iteration == 0 ? first : f;
    forEachParticle([&](std::uint32_t i) { positionCorrection(i, pass); });
    forEachParticle([&](std::uint32_t i) { applyCorrection(i, f); });
    ++report_.iterations;
  }
  if (!adaptive)
  {
    report_.densityError = std::numeric_limits<double>::quiet_NaN();
  }
  forEachParticle([&](std::uint32_t i) { updateVelocity(i, f); });
  forEachParticle([&](std::uint32_t i) { vorticityAndXsph(i, f); });
  forEachParticle([&](std::uint32_t i) { vorticityConfinement(i, f); });
  forEachParticle([&](std::uint32_t i) { commitPosition(i, f, x_.data()); });
}

template <class Real>
void CpuStepper<Real>::append(const ParticleBatch& batch)
{
  checkBatch(parameters_, batch);
  const std::size_t n = x_.size() + batch.position.size();
  for (std::size_t i = 0; i < batch.position.size(); ++i)
  {
    x_.push_back(Vec3<Real>::from(batch.position[i]));
    v_.push_back(Vec3<Real>::from(batch.velocity[i]));
    id_.push_back(batch.id[i]);
  }
  p_.resize(n);
  scratch_.resize(n);
  omega_.resize(n);
  density_.resize(n);
  lambda_.resize(n);
  keys_.resize(n);
  evaluateDensityAtRest();
}

template <class Real>
Compression CpuStepper<Real>::compression()
{
  Compression c;
  if (density_.empty())
  {
    return c;
  }
  // Fixed blocks summed in parallel, then the block sums in order: the same bits whatever the
  // number of threads, so OpenMP stays identical to serial.
  constexpr std::size_t block = 4096;
  const std::size_t n = density_.size();
  const auto blocks = static_cast<std::int64_t>((n + block - 1) / block);
  // Sums then maxima, one block each: blockSums_[b] and blockSums_[blocks + b].
  blockSums_.assign(2 * static_cast<std::size_t>(blocks), 0.0);
  const double inverseRho0 = 1.0 / parameters_.restDensity;
#pragma omp parallel for schedule(static) if (parallel_)
  for (std::int64_t b = 0; b < blocks; ++b)
  {
    double sum = 0.0, largest = 0.0;
    const std::size_t end = std::min(n, static_cast<std::size_t>(b + 1) * block);
    for (std::size_t i = static_cast<std::size_t>(b) * block; i < end; ++i)
    {
      const double e = std::max(double(density_[i]) * inverseRho0 - 1.0, 0.0);
      sum += e;
      largest = std::max(largest, e);
    }
    blockSums_[static_cast<std::size_t>(b)] = sum;
    blockSums_[static_cast<std::size_t>(blocks + b)] = largest;
  }
  double total = 0.0;
  for (std::int64_t b = 0; b < blocks; ++b)
  {
    total += blockSums_[static_cast<std::size_t>(b)];
    c.max = std::max(c.max, blockSums_[static_cast<std::size_t>(blocks + b)]);
  }
  c.mean = total / double(n);
  return c;
}

template <class Real>
template <class In>
void CpuStepper<Real>::loadState(const Snapshot<In>& state)
{
  loadFromSnapshot(state, particles());
  const std::size_t n = x_.size();
  for (auto* array : { &p_, &scratch_, &omega_ })
  {
    array->resize(n);
  }
  keys_.resize(n);
  // Nothing else is state: the next step predicts, re-sorts (stably, from this order) and
  // recomputes every other array.
}

template <class Real>
template <class Out>
void CpuStepper<Real>::copyOut(Snapshot<Out>& out) const
{
  copyToSnapshot(particles(), out);
}

template <class Real>
Statistics CpuStepper<Real>::statistics() const
{
  Statistics s;
  s.particles = x_.size();
  if (x_.empty())
  {
    return s;
  }
  // Neighbours are counted at the current positions on a grid of their own, so the answer does
  // not depend on when the step's grid was built (or on a checkpoint having been loaded).
  std::vector<CellKey> keys(x_.size());
  for (std::size_t i = 0; i < x_.size(); ++i)
  {
    keys[i] = geometry_.keyOf(x_[i]);
  }
  std::vector<std::uint32_t> offsets(cellOffsets_.size()), order, cursor;
  countingSortByCell(keys, offsets, order, cursor);
  std::vector<Vec3d> sorted(x_.size());
  std::vector<CellKey> sortedKeys(x_.size());
  for (std::size_t k = 0; k < order.size(); ++k)
  {
    sorted[k] = Vec3d::from(x_[order[k]]);
    sortedKeys[k] = keys[order[k]];
  }
  const GridView<Real> grid{ geometry_, offsets.data(), sortedKeys.data() };
  const double h2 = parameters_.smoothingLength() * parameters_.smoothingLength();
  const double mass = calibratedParticleMass(parameters_);
  double errorSum = 0, neighborSum = 0;
  for (std::uint32_t k = 0; k < sorted.size(); ++k)
  {
    forEachNeighbor(grid, k, [&](std::uint32_t j) {
      const Vec3d r = sorted[k] - sorted[j];
      neighborSum += (j != k && dot(r, r) < h2) ? 1.0 : 0.0;
    });
  }
  for (std::size_t i = 0; i < x_.size(); ++i)
  {
    const double error = std::max(double(density_[i]) / parameters_.restDensity - 1.0, 0.0);
    errorSum += error;
    s.maxDensityError = std::max(s.maxDensityError, error);
    const Vec3d xi = Vec3d::from(x_[i]);
    const Vec3d vi = Vec3d::from(v_[i]);
    const double speed2 = dot(vi, vi);
    s.maxSpeed = std::max(s.maxSpeed, std::sqrt(speed2));
    s.kineticEnergy += 0.5 * mass * speed2;
    s.momentum += vi * mass;
    s.finite = s.finite && std::isfinite(xi.x + xi.y + xi.z + vi.x + vi.y + vi.z);
  }
  s.averageDensityError = errorSum / double(x_.size());
  s.averageNeighbors = neighborSum / double(x_.size());
  return s;
}

template <class Real>
Health CpuStepper<Real>::health() const
{
  return scanHealth(parameters_, particles(), nullptr);
}

template class CpuStepper<float>;
template class CpuStepper<double>;

} // namespace pbf
