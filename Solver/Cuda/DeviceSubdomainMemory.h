// The memory of DeviceSubdomainStepper: the particle arrays on the device, grown as the owned and
// ghost particles need and kept across steps, and the page-locked host buffers of the messages.
// Included at the end of DeviceSubdomainStepper.h; not a header of its own.
#pragma once

#include "DeviceSubdomainStepper.h"

namespace pbf::cuda
{

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::releaseParticles()
{
  for (void* p : particleArrays_)
  {
    device_->release(p);
  }
  particleArrays_.clear();
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
  if (needed <= capacity_ && capacity_ > 0)
  {
    return;
  }
  if (needed >= std::numeric_limits<std::uint32_t>::max())
  {
    throw InvalidInput(
      "particle count = " + std::to_string(needed) + ": more than 32-bit indices hold");
  }
  const std::size_t capacity = std::max({ needed, capacity_ + capacity_ / 2, std::size_t(1024) });
  std::vector<void*> arrays;
  auto make = [&](std::size_t bytesPerParticle)
  {
    void* p = device_->allocate(capacity * bytesPerParticle);
    arrays.push_back(p);
    return p;
  };
  Vec3<Real>* vec[4];
  for (auto& v : vec)
  {
    v = static_cast<Vec3<Real>*>(make(sizeof(Vec3<Real>)));
  }
  auto* density = static_cast<Real*>(make(sizeof(Real)));
  auto* lambda = static_cast<Real*>(make(sizeof(Real)));
  auto* densityAlt = static_cast<Real*>(make(sizeof(Real)));
  auto* lambdaAlt = static_cast<Real*>(make(sizeof(Real)));
  auto* id = static_cast<std::int64_t*>(make(sizeof(std::int64_t)));
  auto* idAlt = static_cast<std::int64_t*>(make(sizeof(std::int64_t)));
  auto* keys0 = static_cast<CellKey*>(make(sizeof(CellKey)));
  auto* keys1 = static_cast<CellKey*>(make(sizeof(CellKey)));
  auto* masks = static_cast<std::uint32_t*>(
    make(constants_.schedule.enabled ? kNeighborRows * sizeof(std::uint32_t) : 1));
  auto* sendList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
  auto* ghostList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
  auto* ownedList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
  auto* borderList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
  auto* interiorList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
  // Adaptive mode's partial sums and maxima: two per block of 4096, a fraction of a byte per
  // particle (whole bytes here, to keep make() per particle).
  auto* blockSums = static_cast<double*>(make(1));
  device_->reserveTemp(count(capacity), std::size_t(constants_.cellCount) + 1, constants_.keyBits);
  auto exec = device_->executor();
  if (keep > 0)
  {
    for (int i = 0; i < 4; ++i)
    {
      exec.copy(vec[i], vec_[i], keep * sizeof(Vec3<Real>));
    }
    exec.copy(density, density_, keep * sizeof(Real));
    exec.copy(lambda, lambda_, keep * sizeof(Real));
    exec.copy(id, id_, keep * sizeof(std::int64_t));
  }
  device_->synchronize();
  for (void* p : particleArrays_)
  {
    device_->release(p);
  }
  particleArrays_ = arrays;
  for (int i = 0; i < 4; ++i)
  {
    vec_[i] = vec[i];
  }
  density_ = density;
  lambda_ = lambda;
  densityAlt_ = densityAlt;
  lambdaAlt_ = lambdaAlt;
  id_ = id;
  idAlt_ = idAlt;
  keys_[0] = keys0;
  keys_[1] = keys1;
  masks_ = masks;
  sendList_ = sendList;
  ghostList_ = ghostList;
  ownedList_ = ownedList;
  borderList_ = borderList;
  interiorList_ = interiorList;
  blockSums_ = blockSums;
  capacity_ = capacity;
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
