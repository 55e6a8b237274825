// The setup of DeviceSubdomainStepper and the calls that change its particles outside a step:
// construction (the balanced cut from the fluid's counts per column), release, the time step,
// appended particles (each rank keeps its slab's) and the health scan reduced over the ranks.
// Included at the end of DeviceSubdomainStepper.h; not a header of its own (it does
// not include it: the class whose members it defines comes from there).
#pragma once

namespace pbf::cuda
{

template <class Real, class Device>
inline DeviceSubdomainStepper<Real, Device>::DeviceSubdomainStepper(
  distributed::Communicator& communicator, const Parameters& parameters, const FluidSource& fluid,
  std::unique_ptr<Device> device, double skin, bool masks)
try : communicator_(communicator)
  , parameters_(parameters)
  , device_(std::move(device))
{
  parameters_.validate();
  constants_ = makeStepConstants<Real>(parameters_, skin, masks);
  columns_ = constants_.geometry;
  lattice_ = calibrateLattice(parameters_);
  inPlace_ = communicator_.exchangesInPlace();
  // The masks are rebuilt at every pass: a ghost moves by its owner's corrections, which this
  // rank learns only with the positions, and a pass runs its border particles before the
  // interior ones have their max |delta p|. The single-GPU schedule rebuilds at every pass of
  // the dam break anyway at these sizes (pbf_bench: 5.00 builds per step of 4 iterations), so
  // the bound buys nothing here. A zero skin makes MaskSchedule::stillValid false at once.
  constants_.schedule.skin = 0.0;
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  out_.resize(ranks);
  hostFirst_.resize(ranks + 1);
  hostCounts_.resize(
    2 * static_cast<std::size_t>(columns_.nx) * subdomain::kCounterCopies);
  ownerExpected_.resize(ranks + 1);
  in_.resize(ranks);
  inSizes_.resize(ranks);
  sendAt_.resize(ranks);
  sendSizes_.resize(ranks);
  receiveAt_.resize(ranks);
  device_->activate();
  allocateFixed();
  setTimeStep(parameters_.timeStep);
  // The whole initial fluid's count per column (FluidSource::countPerColumn): the balanced cut
  // follows from the counts on every rank alike, so each keeps its share at once and nothing migrates (a cut
  // from uniform slabs would first gather most of a dam break on one rank and then move it:
  // gigabytes at 64M).
  const GridGeometry<Real> g = columns_;
  const std::vector<std::uint64_t> perColumn = fluid.countPerColumn(
    [&](const Vec3d& q) {
      return static_cast<std::size_t>(subdomain::columnOf(g, Vec3<Real>::from(q)));
    },
    static_cast<std::size_t>(g.nx));
  slabs_ = distributed::Slabs::balanced(perColumn, communicator_.size());
  uploadSlabs();
  distributed::together(communicator_, [&] {
    // Slabs::plannedCapacity: the first evaluation grows nothing.
    reserve(slabs_.plannedCapacity(perColumn, communicator_.rank()), 0);
    appendOwned(ownedOf(fluid, true));
  });
}
catch (...)
{
  // A rank that cannot hold its share (its device's memory, say) stops every rank.
  distributed::failTogether(communicator, std::current_exception());
}

template <class Real, class Device>
inline DeviceSubdomainStepper<Real, Device>::~DeviceSubdomainStepper()
{
  try
  {
    device_->activate();
    device_->synchronize();
  }
  catch (...)
  {
  }
  releaseParticles();
  for (void* p : fixed_)
  {
    device_->release(p);
  }
  if (solids_)
  {
    device_->release(solids_);
  }
  if (cellOffsets_)
  {
    device_->release(cellOffsets_);
  }
  for (HostBuffer* b : { &hostPack_, &hostRecv_ })
  {
    if (b->data)
    {
      device_->releaseHost(b->data);
    }
  }
  if (listCounts_)
  {
    device_->releaseHost(listCounts_);
  }
  if (setupCounts_)
  {
    device_->releaseHost(setupCounts_);
  }
}

template <class Real, class Device>
inline Health DeviceSubdomainStepper<Real, Device>::healthAlone() const
{
  device_->activate();
  auto exec = device_->executor();
  enqueueHealth(exec, vec_[xBuffer_], vec_[vBuffer_], density_, count(n_),
    1.0 / parameters_.restDensity, healthBits_);
  unsigned long long bits[kHealthWords] = {};
  device_->download(bits, healthBits_, sizeof bits);
  device_->synchronize();
  double maxima[3];
  decodeHealth(bits, maxima);
  // The maxima, then the speeds' counts (exact as doubles), added over the ranks.
  std::vector<double> mine(maxima, maxima + 3);
  const std::uint32_t* counts = speedCountsOf(bits);
  mine.insert(mine.end(), counts, counts + kSpeedBins);
  Health all;
  std::vector<double> speeds(kSpeedBins, 0.0);
  for (const std::vector<double>& r : distributed::allGather(communicator_, mine))
  {
    all.maxSpeed = std::max(all.maxSpeed, std::sqrt(r[0]));
    all.maxDensityError = std::max(all.maxDensityError, r[1]);
    all.nonFinite += r[2] > 0.0 ? 1 : 0;
    for (int b = 0; b < kSpeedBins; ++b)
    {
      speeds[static_cast<std::size_t>(b)] += r[3 + static_cast<std::size_t>(b)];
    }
  }
  all.robustSpeed = robustSpeed(speeds.data(), all.maxSpeed);
  return all;
}

template <class Real, class Device>
inline void DeviceSubdomainStepper<Real, Device>::setTimeStepAlone(
  double dt, double pressureElapsed)
{
  checkTimeStep(dt);
  device_->activate();
  const StepTime<Real> time = StepTime<Real>::make(parameters_, lattice_, dt, pressureElapsed);
  device_->upload(deviceTime_, &time, sizeof time);
  device_->synchronize(); // `time` dies here
  dt_ = dt;
}

template <class Real, class Device>
inline void DeviceSubdomainStepper<Real, Device>::appendAlone(const ParticleBatch& batch)
{
  checkBatch(parameters_, batch);
  appendOwned(ownedOf(BatchSource(batch), false));
}

template <class Real, class Device>
inline typename DeviceSubdomainStepper<Real, Device>::Owned DeviceSubdomainStepper<Real, Device>::ownedOf(
  const FluidSource& fluid, bool check) const
{
  Owned o;
  const GridGeometry<Real> g = columns_;
  const int me = communicator_.rank();
  fluid.forEachOwned(
    [&](const Vec3d& q) { return slabs_.owner(subdomain::columnOf(g, Vec3<Real>::from(q))); }, me,
    [&](const Vec3d& x, const Vec3d& v, std::int64_t id, std::uint8_t liquid) {
      if (check)
      {
        checkParticle(parameters_, id, x, v);
        checkLiquid(parameters_, id, liquid);
      }
      o.x.push_back(Vec3<Real>::from(x));
      o.v.push_back(Vec3<Real>::from(v));
      o.id.push_back(id);
      o.liquid.push_back(liquid);
    });
  return o;
}

template <class Real, class Device>
inline void DeviceSubdomainStepper<Real, Device>::appendOwned(Owned&& o)
{
  device_->activate();
  const std::size_t n = n_ + o.x.size();
  reserve(n, n_);
  if (!o.x.empty())
  {
    device_->upload(vec_[xBuffer_] + n_, o.x.data(), o.x.size() * sizeof(Vec3<Real>));
    device_->upload(vec_[vBuffer_] + n_, o.v.data(), o.v.size() * sizeof(Vec3<Real>));
    device_->upload(id_ + n_, o.id.data(), o.id.size() * sizeof(std::int64_t));
    // No step has corrected the new particles: their pressure starts at 0.
    device_->executor().fillZero(pressure_ + n_, o.x.size() * sizeof(Real));
    if (liquid_)
    {
      device_->upload(liquid_ + n_, o.liquid.data(), o.liquid.size());
    }
    device_->synchronize(); // the host vectors die with `o`
  }
  o = Owned{};
  n_ = n;
  cut(xBuffer_, -1); // evaluateAtRest predicts nothing: p = x
  evaluateAtRest();
}

} // namespace pbf::cuda
