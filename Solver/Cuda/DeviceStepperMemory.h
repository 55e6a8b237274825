// DeviceStepper's memory: the particles' arrays in the store (DeviceParticleStore.h), grown by half
// again when particles are added, the fixed arrays beside them, and the copies of the state in
// and out.
// Included at the end of DeviceStepper.h; not a header of its own (it does
// not include it: the class whose members it defines comes from there).
#pragma once

namespace pbf
{
namespace cuda
{

template <class Real, class Device>
void DeviceStepper<Real, Device>::release()
{
  releaseGraphs();
  if (store_)
  {
    store_->release();
  }
  buffers_ = fixedBuffers_;
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::allocateFixed()
{
  const StepConstants<Real>& k = constants_;
  std::size_t offset = 0;
  auto place = [&offset](std::size_t bytes) {
    const std::size_t at = offset;
    offset += (bytes + 255) / 256 * 256;
    return at;
  };
  const std::size_t timeAt = place(sizeof(StepTime<Real>));
  const std::size_t healthAt = place(kHealthWords * sizeof(unsigned long long));
  const std::size_t offsetsAt = place((static_cast<std::size_t>(k.cellCount) + 1) * sizeof(std::uint32_t));
  const bool masks = k.schedule.enabled != 0;
  const std::size_t cellMovedAt =
    masks ? place(static_cast<std::size_t>(k.cellCount) * sizeof(std::uint32_t)) : 0;
  const std::size_t movedAt = place(static_cast<std::size_t>(std::max(k.iterations, 1)) * 8);
  const std::size_t buildsAt = place(8);
  const std::size_t keptAt = place(sizeof(std::uint32_t));
  const std::size_t adaptiveAt = place(sizeof(AdaptiveState));
  const std::size_t partialsAt = place(device_->statisticsPartialBytes());
  const std::size_t resultAt = place(kStatisticsValues * sizeof(double));
  const bool walls = parameters_.sumsWallLoads();
  const std::size_t wallLoadsAt = walls ? place(kWallLoadDoubles * sizeof(double)) : 0;
  const std::size_t wallBlockSumsAt =
    walls ? place(std::size_t(kLoadBlocks) * kWallLoadDoubles * sizeof(double)) : 0;
  fixed_ = device_->allocate(offset);
  fixedBytes_ = offset;
  char* base = static_cast<char*>(fixed_);
  deviceTime_ = reinterpret_cast<StepTime<Real>*>(base + timeAt);
  constants_.time = deviceTime_;
  healthBits_ = reinterpret_cast<unsigned long long*>(base + healthAt);
  keptCount_ = reinterpret_cast<std::uint32_t*>(base + keptAt);
  statisticsPartials_ = reinterpret_cast<double*>(base + partialsAt);
  statisticsResult_ = reinterpret_cast<double*>(base + resultAt);
  StepBuffers<Real>& b = fixedBuffers_;
  b.cellOffsets = reinterpret_cast<std::uint32_t*>(base + offsetsAt);
  b.cellMoved = masks ? reinterpret_cast<std::uint32_t*>(base + cellMovedAt) : nullptr;
  b.maxMoved = reinterpret_cast<unsigned long long*>(base + movedAt);
  b.maskBuilds = reinterpret_cast<unsigned long long*>(base + buildsAt);
  b.adaptive = reinterpret_cast<AdaptiveState*>(base + adaptiveAt);
  b.wallLoads = walls ? reinterpret_cast<double*>(base + wallLoadsAt) : nullptr;
  b.wallBlockSums = walls ? reinterpret_cast<double*>(base + wallBlockSumsAt) : nullptr;
  buffers_ = fixedBuffers_;
  // The mask-build counter is read before it is written; the rest is zeroed so that a stale value
  // can never look like a result.
  device_->executor().fillZero(fixed_, offset);
}

// The store's arrays for `capacity` particles (checked against the free memory there), with the
// fixed arrays beside them.
template <class Real, class Device>
void DeviceStepper<Real, Device>::allocate(std::size_t capacity, std::size_t particles)
{
  store_->allocate(capacity, particles);
  StepBuffers<Real> b = store_->buffers();
  b.cellOffsets = fixedBuffers_.cellOffsets;
  b.cellMoved = fixedBuffers_.cellMoved;
  b.maxMoved = fixedBuffers_.maxMoved;
  b.maskBuilds = fixedBuffers_.maskBuilds;
  b.adaptive = fixedBuffers_.adaptive;
  b.wallLoads = fixedBuffers_.wallLoads;
  b.wallBlockSums = fixedBuffers_.wallBlockSums;
  buffers_ = b;
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::restore(const std::vector<Vec3<Real>>& x,
  const std::vector<Vec3<Real>>& v, const std::vector<std::int64_t>& id,
  const std::vector<std::uint8_t>& liquid, const std::vector<Real>& pressure)
{
  if (n_ == 0)
  {
    return;
  }
  device_->upload(buffers_.vec[roles_.x], x.data(), n_ * sizeof(Vec3<Real>));
  device_->upload(buffers_.vec[roles_.v], v.data(), n_ * sizeof(Vec3<Real>));
  device_->upload(buffers_.id, id.data(), n_ * sizeof(std::int64_t));
  device_->upload(buffers_.pressure, pressure.data(), n_ * sizeof(Real));
  if (buffers_.liquid)
  {
    device_->upload(buffers_.liquid, liquid.data(), n_);
  }
  device_->synchronize();
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::append(const ParticleBatch& batch)
{
  checkBatch(parameters_, batch);
  device_->activate();
  const std::size_t added = batch.position.size();
  const std::size_t n = n_ + added;
  if (n >= std::numeric_limits<std::uint32_t>::max())
  {
    throw InvalidInput("particle count = " + std::to_string(n) + ": more than 32-bit indices hold");
  }
  if (n > store_->capacity())
  {
    // Grow by half again, so that emitters reallocate O(log N) times. x, v, id, liquid and the
    // pressure's mean survive through the host, so that the old and the new arrays never take
    // memory together; everything else is recomputed from them.
    std::vector<Vec3<Real>> x(n_), v(n_);
    std::vector<std::int64_t> id(n_);
    std::vector<std::uint8_t> liquid(buffers_.liquid ? n_ : 0);
    std::vector<Real> pressure(n_);
    if (n_ > 0)
    {
      device_->download(x.data(), buffers_.vec[roles_.x], n_ * sizeof(Vec3<Real>));
      device_->download(v.data(), buffers_.vec[roles_.v], n_ * sizeof(Vec3<Real>));
      device_->download(id.data(), buffers_.id, n_ * sizeof(std::int64_t));
      device_->download(pressure.data(), buffers_.pressure, n_ * sizeof(Real));
      if (buffers_.liquid)
      {
        device_->download(liquid.data(), buffers_.liquid, n_);
      }
    }
    device_->synchronize();
    const std::size_t oldCapacity = store_->capacity();
    const std::size_t capacity = std::max(n, oldCapacity + oldCapacity / 2);
    release();
    try
    {
      try
      {
        allocate(capacity, n);
      }
      catch (const InvalidInput&)
      {
        if (capacity == n)
        {
          throw;
        }
        allocate(n, n); // without the growth margin
      }
    }
    catch (const InvalidInput&)
    {
      // Keep the particles we had: the memory they used was just freed.
      allocate(oldCapacity, n_);
      roles_ = Roles{};
      restore(x, v, id, liquid, pressure);
      settle();
      throw;
    }
    roles_ = Roles{};
    restore(x, v, id, liquid, pressure);
  }
  if (added > 0)
  {
    std::vector<Vec3<Real>> x(added), v(added);
    for (std::size_t i = 0; i < added; ++i)
    {
      x[i] = Vec3<Real>::from(batch.position[i]);
      v[i] = Vec3<Real>::from(batch.velocity[i]);
    }
    device_->upload(buffers_.vec[roles_.x] + n_, x.data(), added * sizeof(Vec3<Real>));
    device_->upload(buffers_.vec[roles_.v] + n_, v.data(), added * sizeof(Vec3<Real>));
    device_->upload(buffers_.id + n_, batch.id.data(), added * sizeof(std::int64_t));
    // No step has corrected the new particles: their pressure starts at 0.
    device_->executor().fillZero(buffers_.pressure + n_, added * sizeof(Real));
    // A batch without liquids is of liquid 0 (checkBatch).
    const std::vector<std::uint8_t> zeros(buffers_.liquid && batch.liquid.empty() ? added : 0, 0);
    if (buffers_.liquid)
    {
      device_->upload(buffers_.liquid + n_,
        batch.liquid.empty() ? zeros.data() : batch.liquid.data(), added);
    }
    // The host vectors die at the end of this scope: wait for the copies.
    device_->synchronize();
  }
  n_ = n;
  settle();
}

// The kept particles' indices by a stable selection (into a key buffer: the next step sorts
// again), then every array of the state gathered through them: x and v into the two free Vec3
// buffers and copied back as buffers 0 and 1 (the roles the captured graphs start from), the
// scalars through a free array and copied back. One small wait for the count, which sizes what
// follows; the step is captured again only when a particle went.
template <class Real, class Device>
std::size_t DeviceStepper<Real, Device>::removeOutflow(const std::vector<Box>& zones)
{
  const OutflowZones<Real> outflows = OutflowZones<Real>::make(zones);
  if (zones.empty() || n_ == 0)
  {
    return 0;
  }
  device_->activate();
  auto exec = device_->executor();
  const auto n = static_cast<std::uint32_t>(n_);
  std::uint32_t* kept = buffers_.keys[0];
  exec.selectIf(n, OutsideOutflows<Real>{ buffers_.vec[roles_.x], outflows }, kept, keptCount_);
  std::uint32_t count = 0;
  device_->download(&count, keptCount_, sizeof count);
  device_->synchronize();
  if (count == n)
  {
    return 0;
  }
  const auto gather = [&exec, kept, count](const auto* from, auto* to) {
    subdomain::gather<Real>(exec, count, kept, from, to);
  };
  // Roles are {x, 1 - x} between steps (captureGraphs), so buffers 2 and 3 are free.
  Vec3<Real>* const* vec = buffers_.vec;
  gather(vec[roles_.x], vec[2]);
  gather(vec[roles_.v], vec[3]);
  exec.copy(vec[0], vec[2], count * sizeof(Vec3<Real>));
  exec.copy(vec[1], vec[3], count * sizeof(Vec3<Real>));
  roles_ = Roles{};
  auto* ids = reinterpret_cast<std::int64_t*>(vec[2]);
  gather(buffers_.id, ids);
  exec.copy(buffers_.id, ids, count * sizeof(std::int64_t));
  if (buffers_.liquid)
  {
    auto* liquids = reinterpret_cast<std::uint8_t*>(vec[3]);
    gather(buffers_.liquid, liquids);
    exec.copy(buffers_.liquid, liquids, count);
  }
  Real* const scalars[3] = { buffers_.density, buffers_.lambda, buffers_.pressure };
  for (Real* scalar : scalars)
  {
    gather(scalar, buffers_.volume);
    exec.copy(scalar, buffers_.volume, count * sizeof(Real));
  }
  n_ = count;
  captureGraphs();
  device_->synchronize();
  return n - count;
}

// Straight from the device into the caller's arrays: no host temporaries, no pass over the
// particles on the CPU (page-locked destinations are copied at the full bus speed).
template <class Real, class Device>
template <class Out>
void DeviceStepper<Real, Device>::copyInto(const SnapshotView<Out>& out) const
{
  if constexpr (!std::is_same<Out, Real>::value)
  {
    Stepper::readInto(out); // converts through read()
  }
  else
  {
    device_->activate();
    const std::size_t n = n_;
    const auto copy = [this, n](void* to, const void* from, std::size_t size) {
      if (to && n > 0)
      {
        device_->download(to, from, n * size);
      }
    };
    copy(out.position, buffers_.vec[roles_.x], sizeof(Vec3<Real>));
    copy(out.velocity, buffers_.vec[roles_.v], sizeof(Vec3<Real>));
    copy(out.density, buffers_.density, sizeof(Real));
    copy(out.lambda, buffers_.lambda, sizeof(Real));
    copy(out.pressure, buffers_.pressure, sizeof(Real));
    copy(out.id, buffers_.id, sizeof(std::int64_t));
    if (buffers_.liquid)
    {
      // The densities in each particle's liquid's units (toLiquidDensities), which need the
      // liquids even where the caller does not ask for them.
      std::vector<std::uint8_t> own(out.liquid ? 0 : n);
      std::uint8_t* liquid = out.liquid ? out.liquid : own.data();
      copy(liquid, buffers_.liquid, 1);
      device_->synchronize();
      if (out.density)
      {
        toLiquidDensities(parameters_, liquid, out.density, n);
      }
    }
    device_->synchronize();
  }
}

template <class Real, class Device>
template <class Out>
void DeviceStepper<Real, Device>::copyOut(Snapshot<Out>& out) const
{
  out.position.resize(n_);
  out.velocity.resize(n_);
  out.density.resize(n_);
  out.lambda.resize(n_);
  out.pressure.resize(n_);
  out.id.resize(n_);
  out.liquid.resize(buffers_.liquid ? n_ : 0);
  if constexpr (std::is_same<Out, Real>::value)
  {
    // Same precision (checkpoints): straight into the snapshot's vectors.
    copyInto(SnapshotView<Real>{ out.position.data(), out.velocity.data(), out.density.data(),
      out.lambda.data(), out.pressure.data(), out.id.data(),
      buffers_.liquid ? out.liquid.data() : nullptr });
  }
  else
  {
    Snapshot<Real> same;
    copyOut(same);
    for (std::size_t i = 0; i < n_; ++i)
    {
      out.position[i] = Vec3<Out>::from(same.position[i]);
      out.velocity[i] = Vec3<Out>::from(same.velocity[i]);
      out.density[i] = static_cast<Out>(same.density[i]);
      out.lambda[i] = static_cast<Out>(same.lambda[i]);
      out.pressure[i] = static_cast<Out>(same.pressure[i]);
    }
    out.id = std::move(same.id);
    out.liquid = std::move(same.liquid);
  }
}

// As CpuStepper::loadState: the snapshot's order is kept, and the next step predicts, re-sorts
// (stably, from this order) and recomputes everything else.
template <class Real, class Device>
template <class In>
void DeviceStepper<Real, Device>::loadState(const Snapshot<In>& state)
{
  if (sizeof(In) != sizeof(Real))
  {
    throw InvalidInput(std::string("checkpoint precision = ") +
      (sizeof(In) == sizeof(float) ? "single" : "double") + ": the stepper runs in " +
      toString(precision()) + " precision");
  }
  const std::size_t n = state.id.size();
  if (state.position.size() != n || state.velocity.size() != n || state.density.size() != n ||
    state.lambda.size() != n || state.pressure.size() != n)
  {
    throw InvalidInput("checkpoint arrays differ in length (" + std::to_string(n) + " ids)");
  }
  checkLiquids(parameters_, state.liquid, n, "checkpoint");
  // Back to the reference's units (fromLiquidDensities); a checkpoint without liquids in a scene
  // that names them is of liquid 0.
  std::vector<In> density = state.density;
  std::vector<std::uint8_t> liquid = state.liquid;
  if (!parameters_.liquids.empty())
  {
    liquid.resize(n, 0);
    fromLiquidDensities(parameters_, liquid, density);
  }
  device_->activate();
  device_->synchronize();
  if (n > store_->capacity())
  {
    n_ = 0; // the old state is gone either way; empty if the allocation throws
    release();
    allocate(n, n);
  }
  roles_ = Roles{};
  n_ = n;
  if (n > 0)
  {
    // In is Real here (checked above), so the arrays go up as they are.
    device_->upload(buffers_.vec[roles_.x], state.position.data(), n * sizeof(Vec3<Real>));
    device_->upload(buffers_.vec[roles_.v], state.velocity.data(), n * sizeof(Vec3<Real>));
    device_->upload(buffers_.density, density.data(), n * sizeof(Real));
    device_->upload(buffers_.lambda, state.lambda.data(), n * sizeof(Real));
    device_->upload(buffers_.pressure, state.pressure.data(), n * sizeof(Real));
    device_->upload(buffers_.id, state.id.data(), n * sizeof(std::int64_t));
    if (buffers_.liquid)
    {
      device_->upload(buffers_.liquid, liquid.data(), n);
    }
  }
  captureGraphs();
  device_->synchronize();
}

} // namespace cuda
} // namespace pbf
