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
  : HostStepper<Stepper, Real>(parallel, parameters)
{
  checkBatch(fluid_.parameters, initial);
  append(initial);
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
  const auto n = static_cast<std::int64_t>(fluid_.x.size());
#pragma omp parallel for schedule(static) if (parallel_)
  for (std::int64_t i = 0; i < n; ++i)
  {
    stage(static_cast<std::uint32_t>(i));
  }
}

template <class Real>
void CpuStepper<Real>::sortByCell()
{
  fluid_.sortByCell([&](auto&& f) { forEachParticle(f); }, [](auto&&) {});
}

template <class Real>
void CpuStepper<Real>::evaluateDensityAtRest()
{
  fluid_.p = fluid_.x;
  sortByCell();
  const FluidView<Real> f = fluid_.view();
  forEachParticle([&](std::uint32_t i) { densityAndLambda(i, f); });
  // The pressure's mean goes on (the sort carried it); appended particles start at 0.
}

template <class Real>
void CpuStepper<Real>::step()
{
  if (fluid_.x.empty())
  {
    return;
  }
  report_ = StepReport{};
  HostStepLoop<Real, CpuStepper> loop(fluid_, *this, report_);
  runStep(loop, SolveRule::of(fluid_.parameters));
}

template <class Real>
void CpuStepper<Real>::predict()
{
  const FluidView<Real> f = fluid_.view();
  forEachParticle([&](std::uint32_t i) { predictPosition(i, f); });
}

template <class Real>
void CpuStepper<Real>::append(const ParticleBatch& batch)
{
  checkBatch(fluid_.parameters, batch);
  const std::size_t n = fluid_.x.size() + batch.position.size();
  fluid_.appendState(batch);
  fluid_.resizeWork(n);
  evaluateDensityAtRest();
}

template <class Real>
Compression CpuStepper<Real>::compression()
{
  Compression c;
  if (fluid_.density.empty())
  {
    return c;
  }
  // Fixed blocks summed in parallel, then the block sums in order: the same bits whatever the
  // number of threads, so OpenMP stays identical to serial.
  // With several liquids the mean is the most compressed liquid's: a thin light layer must not
  // hide a deep heavy one's compression. Each block keeps a sum and a count per liquid.
  constexpr std::size_t block = 4096;
  const std::size_t n = fluid_.density.size();
  const auto liquids = static_cast<std::size_t>(fluid_.parameters.liquidCount());
  const auto blocks = static_cast<std::size_t>((n + block - 1) / block);
  // Per block b: the sums of liquids l at [l blocks + b], the counts at [(liquids + l) blocks + b]
  // (with several liquids), the maxima at [2 liquids blocks + b].
  blockSums_.assign((2 * liquids + 1) * blocks, 0.0);
  const double inverseRho0 = 1.0 / fluid_.parameters.restDensity;
  const std::uint8_t* liquid = fluid_.liquid.empty() ? nullptr : fluid_.liquid.data();
#pragma omp parallel for schedule(static) if (parallel_)
  for (std::int64_t b = 0; b < static_cast<std::int64_t>(blocks); ++b)
  {
    const auto k = static_cast<std::size_t>(b);
    double largest = 0.0;
    const std::size_t end = std::min(n, (k + 1) * block);
    for (std::size_t i = k * block; i < end; ++i)
    {
      const double e = std::max(double(fluid_.density[i]) * inverseRho0 - 1.0, 0.0);
      const std::size_t l = liquid ? liquid[i] : 0;
      blockSums_[l * blocks + k] += e;
      blockSums_[(liquids + l) * blocks + k] += 1.0;
      largest = std::max(largest, e);
    }
    blockSums_[2 * liquids * blocks + k] = largest;
  }
  for (std::size_t b = 0; b < blocks; ++b)
  {
    c.max = std::max(c.max, blockSums_[2 * liquids * blocks + b]);
  }
  for (std::size_t l = 0; l < liquids; ++l)
  {
    double total = 0.0, count = 0.0;
    for (std::size_t b = 0; b < blocks; ++b)
    {
      total += blockSums_[l * blocks + b];
      count += blockSums_[(liquids + l) * blocks + b];
    }
    c.mean = std::max(c.mean, liquids == 1 ? total / double(n) : total / std::max(count, 1.0));
  }
  return c;
}

template <class Real>
Statistics CpuStepper<Real>::statistics() const
{
  Statistics s;
  s.particles = fluid_.x.size();
  if (fluid_.x.empty())
  {
    return s;
  }
  // Neighbours are counted at the current positions on a grid of their own, so the answer does
  // not depend on when the step's grid was built (or on a checkpoint having been loaded).
  std::vector<CellKey> keys(fluid_.x.size());
  for (std::size_t i = 0; i < fluid_.x.size(); ++i)
  {
    keys[i] = fluid_.geometry.keyOf(fluid_.x[i]);
  }
  std::vector<std::uint32_t> offsets(std::size_t(fluid_.geometry.cellCount()) + 1), order, cursor;
  countingSortByCell(keys, offsets, order, cursor);
  std::vector<Vec3d> sorted(fluid_.x.size());
  std::vector<CellKey> sortedKeys(fluid_.x.size());
  for (std::size_t k = 0; k < order.size(); ++k)
  {
    sorted[k] = Vec3d::from(fluid_.x[order[k]]);
    sortedKeys[k] = keys[order[k]];
  }
  const GridView<Real> grid{ fluid_.geometry, offsets.data(), sortedKeys.data() };
  const double h2 = fluid_.parameters.smoothingLength() * fluid_.parameters.smoothingLength();
  const LiquidMasses masses(fluid_.parameters);
  double errorSum = 0, neighborSum = 0;
  for (std::uint32_t k = 0; k < sorted.size(); ++k)
  {
    forEachNeighbor(grid, k, [&](std::uint32_t j) {
      const Vec3d r = sorted[k] - sorted[j];
      neighborSum += (j != k && dot(r, r) < h2) ? 1.0 : 0.0;
    });
  }
  for (std::size_t i = 0; i < fluid_.x.size(); ++i)
  {
    const double error = std::max(double(fluid_.density[i]) / fluid_.parameters.restDensity - 1.0, 0.0);
    errorSum += error;
    s.maxDensityError = std::max(s.maxDensityError, error);
    const Vec3d xi = Vec3d::from(fluid_.x[i]);
    const Vec3d vi = Vec3d::from(fluid_.v[i]);
    const double speed2 = dot(vi, vi);
    const double mass = masses(fluid_.liquid, i);
    s.maxSpeed = std::max(s.maxSpeed, std::sqrt(speed2));
    s.kineticEnergy += 0.5 * mass * speed2;
    s.momentum += vi * mass;
    s.finite = s.finite && std::isfinite(xi.x + xi.y + xi.z + vi.x + vi.y + vi.z);
  }
  s.averageDensityError = errorSum / double(fluid_.x.size());
  s.averageNeighbors = neighborSum / double(fluid_.x.size());
  return s;
}

template <class Real>
Health CpuStepper<Real>::health() const
{
  return scanHealth(fluid_.parameters, fluid_.particles(), nullptr);
}

template class CpuStepper<float>;
template class CpuStepper<double>;

} // namespace pbf
