// The memory of DeviceSubdomainStepper: the particle arrays on the device (DeviceParticleStore.h),
// grown as the owned and ghost particles need and kept across steps, and the device and
// page-locked host buffers of the messages.
// Included at the end of DeviceSubdomainStepper.h; not a header of its own.
#pragma once

namespace pbf::cuda
{

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::releaseParticles()
{
  store_.reset();
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
    // The alternates and the five lists are the migration's and the ghosts' (ParticleArrays).
    ParticleArrays arrays;
    arrays.masks = constants_.schedule.enabled != 0;
    arrays.alternates = true;
    arrays.lists = 5;
    store_ = std::make_unique<DeviceParticleStore<Real, Device>>(
      *device_, arrays, std::size_t(constants_.cellCount) + 1, constants_.keyBits);
  }
  store_->reserve(needed, keep);
  adoptStore();
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
  id_ = p.id;
  idAlt_ = p.idAlt;
  keys_[0] = p.keys[0];
  keys_[1] = p.keys[1];
  masks_ = p.masks;
  sendList_ = p.list[0];
  ghostList_ = p.list[1];
  ownedList_ = p.list[2];
  borderList_ = p.list[3];
  interiorList_ = p.list[4];
  blockSums_ = p.blockSums;
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
