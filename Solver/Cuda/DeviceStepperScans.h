// DeviceStepper's scans of its particles (statistics(), health(), lastStep(), diagnostics()) and
// its solid obstacles. Included at the end of DeviceStepper.h; not a header of its own.
#pragma once

namespace pbf
{
namespace cuda
{

template <class Real, class Device>
Statistics DeviceStepper<Real, Device>::statistics() const
{
  Statistics s;
  s.particles = n_;
  if (n_ == 0)
  {
    return s;
  }
  device_->activate();
  const double h = parameters_.smoothingLength();
  // Neighbours at the current positions on a grid of their own, as the CPU counts them. Between
  // steps the keys, C, D and the cell offsets are free: the next step rebuilds them.
  const StepBuffers<Real>& b = buffers_;
  const auto n = static_cast<std::uint32_t>(n_);
  std::uint32_t* order = reinterpret_cast<std::uint32_t*>(b.vec[2]);
  auto exec = device_->executor();
  const CellKey* keys = enqueueSortedCopy(exec, constants_, n, b.vec[roles_.x], b.keys[0],
    b.keys[1], order, order + store_->capacity(), b.vec[3], b.cellOffsets);
  StatisticsScan<Real> scan{ b.vec[roles_.x], b.vec[roles_.v], b.density, b.vec[3],
    GridView<Real>{ constants_.geometry, b.cellOffsets, keys }, n, h * h,
    calibratedParticleMass(parameters_), parameters_.restDensity, b.liquid, {} };
  const LiquidMasses masses(parameters_);
  std::copy(std::begin(masses.of), std::end(masses.of), std::begin(scan.masses));
  device_->scanStatistics(scan, statisticsPartials_, statisticsResult_);
  double r[kStatisticsValues];
  device_->download(r, statisticsResult_, sizeof r);
  device_->synchronize();
  const double count = static_cast<double>(n_);
  s.averageDensityError = r[kErrorSum] / count;
  s.maxDensityError = r[kErrorMax];
  s.averageNeighbors = r[kNeighborSum] / count;
  s.maxSpeed = r[kSpeedMax];
  s.kineticEnergy = r[kKinetic];
  s.momentum = Vec3d{ r[kMomentumX], r[kMomentumY], r[kMomentumZ] };
  s.finite = r[kNonFinite] == 0.0;
  return s;
}

template <class Real, class Device>
Health DeviceStepper<Real, Device>::health() const
{
  Health h;
  if (n_ == 0)
  {
    return h;
  }
  device_->activate();
  auto exec = device_->executor();
  enqueueHealth(exec, buffers_.vec[roles_.x], buffers_.vec[roles_.v], buffers_.density,
    static_cast<std::uint32_t>(n_), 1.0 / parameters_.restDensity, healthBits_);
  unsigned long long bits[kHealthWords] = {};
  device_->download(bits, healthBits_, sizeof bits);
  device_->synchronize();
  double r[3];
  decodeHealth(bits, r);
  h.maxSpeed = std::sqrt(r[0]);
  h.robustSpeed = robustSpeed(speedCountsOf(bits), h.maxSpeed);
  h.maxDensityError = r[1];
  h.nonFinite = r[2] > 0.0 ? 1 : 0;
  return h;
}

template <class Real, class Device>
StepReport DeviceStepper<Real, Device>::lastStep() const
{
  StepReport report;
  if (!stepped_)
  {
    return report;
  }
  const bool adaptive = constants_.tolerance > 0;
  // Fixed mode computes no reduction inside a step, as on the CPU.
  report.iterations = constants_.iterations;
  report.densityError = std::numeric_limits<double>::quiet_NaN();
  // The solids' loads, then with TankLoads the six walls' (as the CPU's report has them).
  const std::size_t solids = static_cast<std::size_t>(constants_.obstacleCount);
  const std::size_t walls = buffers_.wallLoads ? kMirrorWalls : 0;
  if (!adaptive && solids + walls == 0)
  {
    return report;
  }
  device_->activate();
  AdaptiveState state{};
  std::vector<double> loads((solids + walls) * kLoadValues);
  if (adaptive)
  {
    device_->download(&state, buffers_.adaptive, sizeof state);
  }
  if (solids > 0)
  {
    device_->download(loads.data(), constants_.loads, solids * kLoadValues * sizeof(double));
  }
  if (walls > 0)
  {
    device_->download(
      loads.data() + solids * kLoadValues, buffers_.wallLoads, kWallLoadDoubles * sizeof(double));
  }
  device_->synchronize();
  if (adaptive)
  {
    report.iterations = state.iterations;
    report.densityError = state.densityError;
  }
  report.loads.resize(solids + walls);
  for (std::size_t o = 0; o < solids + walls; ++o)
  {
    const double* v = &loads[o * kLoadValues];
    report.loads[o].force = Vec3d{ v[0], v[1], v[2] };
    report.loads[o].torque = Vec3d{ v[3], v[4], v[5] };
  }
  return report;
}

template <class Real, class Device>
Diagnostics DeviceStepper<Real, Device>::diagnostics() const
{
  device_->activate();
  Diagnostics d;
  d.device = device_->name();
  d.deviceBytes = store_->bytes() + fixedBytes_;
  d.capacity = store_->capacity();
  // Bytes per particle of capacity that the per-particle arrays take (with the liquids' bytes
  // and surface tension's buffers when the scene has them).
  d.bytesPerParticle =
    static_cast<double>(DeviceParticleStore<Real, Device>::bytesPerParticle(store_->arrays()));
  d.steps = steps_;
  unsigned long long builds = 0;
  if (buffers_.maskBuilds)
  {
    device_->download(&builds, buffers_.maskBuilds, sizeof builds);
    device_->synchronize();
  }
  d.maskBuilds = builds;
  return d;
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::setObstacles(
  const std::vector<DistanceGrid>& obstacles, const std::vector<SolidPose>& poses)
{
  solids_ =
    replaceSolids(*device_, solids_, obstacles, poses, parameters_, constants_, solidViews_);
  // The captured step holds the constants it was captured with.
  settle();
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::setObstaclePoses(const std::vector<SolidPose>& poses)
{
  placeSolids(*device_, constants_, solidViews_, poses);
}

} // namespace cuda
} // namespace pbf
