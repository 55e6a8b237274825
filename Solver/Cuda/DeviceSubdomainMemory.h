// The memory of DeviceSubdomainStepper: the particle arrays on the device (DeviceParticleStore.h),
// grown as the owned and ghost particles need and kept across steps, the fixed-size arrays, the
// device and page-locked host buffers of the messages, and the owned particles' state to and
// from the host.
// Included at the end of DeviceSubdomainStepper.h; not a header of its own.
#pragma once

namespace pbf::cuda
{

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::allocateFixed()
{
  const auto ranks = static_cast<std::size_t>(communicator_.size());

  maxMoved_ = allocateFixed<unsigned long long>(
    static_cast<std::size_t>(std::max(constants_.iterations, 1)));
  maskBuilds_ = allocateFixed<unsigned long long>(1);
  borderMaskBuilds_ = allocateFixed<unsigned long long>(1);
  columnCounts_ = allocateFixed<std::uint32_t>(
    2 * static_cast<std::size_t>(columns_.nx) * subdomain::kCounterCopies);
  ownerCounts_ = allocateFixed<std::uint32_t>((ranks + 1) * subdomain::kCounterCopies);
  slabFirst_ = allocateFixed<int>(ranks + 1);
  selected_ = allocateFixed<std::uint32_t>(8);
  deviceTime_ = allocateFixed<StepTime<Real>>(1);
  constants_.time = deviceTime_;
  adaptive_ = allocateFixed<AdaptiveState>(1);
  if (parameters_.sumsWallLoads())
  {
    wallLoads_ = allocateFixed<double>(kWallLoadDoubles);
    wallBlockSums_ = allocateFixed<double>(std::size_t(kLoadBlocks) * kWallLoadDoubles);
  }
  healthBits_ = allocateFixed<unsigned long long>(kHealthWords);
  listCounts_ = static_cast<std::uint32_t*>(device_->allocateHost(8 * sizeof(std::uint32_t)));
  // The owner counts' copies, then the ghosts sent to each side.
  setupCounts_ = static_cast<std::uint32_t*>(
    device_->allocateHost(((ranks + 1) * subdomain::kCounterCopies + 2) * sizeof(std::uint32_t)));
  auto exec = device_->executor();
  exec.fillZero(maskBuilds_, sizeof(unsigned long long));
  exec.fillZero(borderMaskBuilds_, sizeof(unsigned long long));
}

template <class Real, class Device>
typename DeviceSubdomainStepper<Real, Device>::HostState
DeviceSubdomainStepper<Real, Device>::hostState() const
{
  device_->activate();
  HostState s;
  s.x.resize(n_);
  s.v.resize(n_);
  s.density.resize(n_);
  s.lambda.resize(n_);
  s.pressure.resize(n_);
  s.id.resize(n_);
  s.liquid.resize(liquid_ ? n_ : 0);
  if (n_ > 0)
  {
    device_->download(s.x.data(), vec_[xBuffer_], n_ * sizeof(Vec3<Real>));
    device_->download(s.v.data(), vec_[vBuffer_], n_ * sizeof(Vec3<Real>));
    device_->download(s.density.data(), density_, n_ * sizeof(Real));
    device_->download(s.lambda.data(), lambda_, n_ * sizeof(Real));
    device_->download(s.pressure.data(), pressure_, n_ * sizeof(Real));
    device_->download(s.id.data(), id_, n_ * sizeof(std::int64_t));
    if (liquid_)
    {
      device_->download(s.liquid.data(), liquid_, n_);
    }
  }
  device_->synchronize();
  return s;
}

template <class Real, class Device>
template <class In>
void DeviceSubdomainStepper<Real, Device>::loadState(const Snapshot<In>& state)
{
  HostState s;
  loadFromSnapshot(parameters_, state,
    HostParticles<Real>{ s.x, s.v, s.density, s.lambda, s.pressure, s.id, s.liquid });
  device_->activate();
  device_->synchronize();
  const std::size_t n = s.id.size();
  n_ = 0;
  reserve(n, 0);
  xBuffer_ = 0;
  vBuffer_ = 1;
  if (n > 0)
  {
    device_->upload(vec_[xBuffer_], s.x.data(), n * sizeof(Vec3<Real>));
    device_->upload(vec_[vBuffer_], s.v.data(), n * sizeof(Vec3<Real>));
    device_->upload(density_, s.density.data(), n * sizeof(Real));
    device_->upload(lambda_, s.lambda.data(), n * sizeof(Real));
    device_->upload(pressure_, s.pressure.data(), n * sizeof(Real));
    device_->upload(id_, s.id.data(), n * sizeof(std::int64_t));
    if (liquid_)
    {
      device_->upload(liquid_, s.liquid.data(), n);
    }
  }
  device_->synchronize();
  n_ = n;
}

// The kept owned particles listed by a stable selection, then gathered as keepOwned gathers
// them (x and v into the free buffers, the scalars into the alternates). Between steps the store
// holds the owned particles only, so this is the single GPU's removal on this rank's share.
template <class Real, class Device>
std::size_t DeviceSubdomainStepper<Real, Device>::removeOutflow(const std::vector<Box>& zones)
{
  const OutflowZones<Real> outflows = OutflowZones<Real>::make(zones);
  std::size_t mine = 0;
  distributed::together(communicator_, [&] {
    if (zones.empty() || n_ == 0)
    {
      return;
    }
    device_->activate();
    auto exec = device_->executor();
    const std::uint32_t n = count(n_);
    exec.selectIf(n, OutsideOutflows<Real>{ vec_[xBuffer_], outflows }, ownedList_, selected_);
    std::uint32_t kept = 0;
    device_->download(&kept, selected_, sizeof kept);
    device_->synchronize();
    if (kept == n)
    {
      return;
    }
    const int toX = freeBuffer(xBuffer_, vBuffer_, -1);
    const int toV = otherBuffer(xBuffer_, vBuffer_, toX);
    subdomain::gather<Real>(exec, kept, ownedList_, vec_[xBuffer_], vec_[toX]);
    subdomain::gather<Real>(exec, kept, ownedList_, vec_[vBuffer_], vec_[toV]);
    subdomain::gather<Real>(exec, kept, ownedList_, density_, densityAlt_);
    subdomain::gather<Real>(exec, kept, ownedList_, lambda_, lambdaAlt_);
    subdomain::gather<Real>(exec, kept, ownedList_, pressure_, pressureAlt_);
    subdomain::gather<Real>(exec, kept, ownedList_, id_, idAlt_);
    if (liquid_)
    {
      subdomain::gather<Real>(exec, kept, ownedList_, liquid_, liquidAlt_);
    }
    store_->swapAlternates();
    adoptStore();
    xBuffer_ = toX;
    vBuffer_ = toV;
    n_ = kept;
    device_->synchronize();
    mine = n - kept;
  });
  double removed = 0;
  for (const std::vector<double>& r :
    distributed::allGather(communicator_, { static_cast<double>(mine) }))
  {
    removed += r[0];
  }
  return static_cast<std::size_t>(removed);
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::reserveBorderLists(std::size_t count)
{
  if (count <= borderCapacity_ && borderLists_)
  {
    return;
  }
  const std::size_t capacity = std::max({ count, borderCapacity_ + borderCapacity_ / 2,
    std::size_t(1024) });
  device_->synchronize(); // queued work may still read the old lists
  if (borderLists_)
  {
    device_->release(borderLists_);
  }
  borderLists_ = static_cast<std::uint32_t*>(
    device_->allocate(3 * capacity * sizeof(std::uint32_t)));
  borderCapacity_ = capacity;
  sendList_ = borderLists_;
  ghostList_ = borderLists_ + capacity;
  borderList_ = borderLists_ + 2 * capacity;
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::releaseParticles()
{
  store_.reset();
  if (borderLists_)
  {
    device_->release(borderLists_);
  }
  borderLists_ = nullptr;
  borderCapacity_ = 0;
  if (pack_)
  {
    device_->release(pack_);
  }
  if (recv_)
  {
    device_->release(recv_);
  }
  pack_ = recv_ = nullptr;
  packBytes_ = recvBytes_ = 0;
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::reserve(std::size_t needed, std::size_t keep)
{
  if (!store_)
  {
    // The alternates and the owned and interior lists are the migration's and the passes'
    // (ParticleArrays); the border lists are apart (reserveBorderLists).
    ParticleArrays arrays;
    arrays.masks = constants_.schedule.enabled != 0;
    arrays.alternates = true;
    arrays.lists = 2;
    arrays.liquids = static_cast<int>(parameters_.liquids.size());
    arrays.colour = constants_.c.surfaceTension;
    arrays.walls = parameters_.sumsWallLoads();
    store_ = std::make_unique<DeviceParticleStore<Real, Device>>(
      *device_, arrays, std::size_t(constants_.cellCount) + 1, constants_.keyBits);
  }
  store_->reserve(needed, keep);
  adoptStore();
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::setWindow()
{
  const int me = communicator_.rank();
  const int last = communicator_.size() - 1;
  const int first = slabs_.first[static_cast<std::size_t>(me)];
  const int end = slabs_.first[static_cast<std::size_t>(me) + 1];
  // The slab's columns and the ghosts' (one beyond each border with a neighbour), less the
  // empty ones at either end: every particle sorted this step lies in one that holds a
  // predicted position (the cut's counts), so a key never clamps.
  int lo = me > 0 ? first - 1 : first;
  int hi = me < last ? end + 1 : end;
  while (lo < hi - 1 && predictedAll_[static_cast<std::size_t>(lo)] == 0)
  {
    ++lo;
  }
  while (hi - 1 > lo && predictedAll_[static_cast<std::size_t>(hi - 1)] == 0)
  {
    --hi;
  }
  GridGeometry<Real>& g = constants_.geometry;
  g.firstColumn = lo;
  g.nx = hi - lo;
  constants_.cellCount = g.cellCount();
  const std::size_t cells = std::size_t(constants_.cellCount) + 1;
  if (cells > cellCapacity_)
  {
    // A sixteenth more than asked: the window widens by a column or so as the fluid spreads.
    const std::size_t room = std::min<std::size_t>(
      cells + cells / 16, std::size_t(columns_.cellCount()) + 1);
    auto* grown = static_cast<std::uint32_t*>(device_->allocate(room * sizeof(std::uint32_t)));
    if (cellOffsets_)
    {
      device_->synchronize(); // the last step's launches may still read them
      device_->release(cellOffsets_);
      fixedBytes_ -= cellCapacity_ * sizeof(std::uint32_t);
    }
    cellOffsets_ = grown;
    cellCapacity_ = room;
    fixedBytes_ += room * sizeof(std::uint32_t);
  }
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::adoptStore()
{
  const typename DeviceParticleStore<Real, Device>::Pointers& p = store_->p;
  for (int i = 0; i < 4; ++i)
  {
    vec_[i] = p.vec[i];
  }
  density_ = p.density;
  lambda_ = p.lambda;
  densityAlt_ = p.densityAlt;
  lambdaAlt_ = p.lambdaAlt;
  pressure_ = p.pressure;
  pressureAlt_ = p.pressureAlt;
  id_ = p.id;
  idAlt_ = p.idAlt;
  liquid_ = p.liquid;
  liquidAlt_ = p.liquidAlt;
  colour_ = p.colour;
  normal_ = p.normal;
  keys_[0] = p.keys[0];
  keys_[1] = p.keys[1];
  masks_ = p.masks;
  ownedList_ = p.list[0];
  interiorList_ = p.list[1];
  blockSums_ = p.blockSums;
  wallFlags_ = p.wallFlags;
  wallValues_ = p.wallValues;
  capacity_ = store_->capacity();
}

template <class Real, class Device>
unsigned char* DeviceSubdomainStepper<Real, Device>::hostBuffer(HostBuffer& b, std::size_t bytes)
{
  if (bytes > b.size || !b.data)
  {
    const std::size_t size = std::max({ bytes, b.size + b.size / 2, std::size_t(4096) });
    device_->synchronize();
    if (b.data)
    {
      device_->releaseHost(b.data);
    }
    b.data = static_cast<unsigned char*>(device_->allocateHost(size));
    b.size = size;
  }
  return b.data;
}

template <class Real, class Device>
unsigned char* DeviceSubdomainStepper<Real, Device>::growBytes(
  unsigned char*& buffer, std::size_t& have, std::size_t bytes)
{
  if (bytes > have || !buffer)
  {
    const std::size_t size = std::max({ bytes, have + have / 2, std::size_t(4096) });
    device_->synchronize();
    if (buffer)
    {
      device_->release(buffer);
    }
    buffer = static_cast<unsigned char*>(device_->allocate(size));
    have = size;
  }
  return buffer;
}

} // namespace pbf::cuda
