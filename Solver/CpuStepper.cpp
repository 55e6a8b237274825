#include "CpuStepper.h"

#include "CellSort.h"
#include "ParticleChecks.h"

#include <algorithm>
#include <cmath>
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
FluidView<Real> CpuStepper<Real>::view()
{
  FluidView<Real> f;
  f.x = x_.data();
  f.p = p_.data();
  f.v = v_.data();
  f.density = density_.data();
  f.lambda = lambda_.data();
  f.scratch = scratch_.data();
  f.omega = omega_.data();
  f.grid = GridView<Real>{ geometry_, cellOffsets_.data(), keys_.data() };
  f.c = coefficients_;
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
  for (int iteration = 0; iteration < parameters_.solverIterations; ++iteration)
  {
    forEachParticle([&](std::uint32_t i) { densityAndLambda(i, f); });
    forEachParticle([&](std::uint32_t i) { positionCorrection(i, f); });
    forEachParticle([&](std::uint32_t i) { applyCorrection(i, f); });
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
template <class Out>
void CpuStepper<Real>::copyOut(Snapshot<Out>& out) const
{
  const std::size_t n = x_.size();
  out.position.resize(n);
  out.velocity.resize(n);
  out.density.resize(n);
  out.lambda.resize(n);
  out.id = id_;
  for (std::size_t i = 0; i < n; ++i)
  {
    out.position[i] = Vec3<Out>::from(x_[i]);
    out.velocity[i] = Vec3<Out>::from(v_[i]);
    out.density[i] = static_cast<Out>(density_[i]);
    out.lambda[i] = static_cast<Out>(lambda_[i]);
  }
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
  const GridView<Real> grid{ geometry_, cellOffsets_.data(), keys_.data() };
  const double h2 = parameters_.smoothingLength() * parameters_.smoothingLength();
  const double mass = calibratedParticleMass(parameters_);
  double errorSum = 0, neighborSum = 0;
  for (std::uint32_t i = 0; i < x_.size(); ++i)
  {
    const double error = std::max(double(density_[i]) / parameters_.restDensity - 1.0, 0.0);
    errorSum += error;
    s.maxDensityError = std::max(s.maxDensityError, error);
    const Vec3d xi = Vec3d::from(x_[i]);
    forEachNeighbor(grid, i, [&](std::uint32_t j) {
      const Vec3d r = xi - Vec3d::from(x_[j]);
      neighborSum += (j != i && dot(r, r) < h2) ? 1.0 : 0.0;
    });
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

template class CpuStepper<float>;
template class CpuStepper<double>;

} // namespace pbf
