// The particle arrays of a GPU stepper, for both (DeviceStepper, DeviceSubdomainStepper): the
// per-particle part of StepBuffers (four Vec3 buffers, density, lambda, pressure, id, two key buffers, the
// neighbour masks), the arrays only one of them needs (stored volumes and |omega|, and with
// surface tension the colour gradients and normals, for the single GPU; alternates and index
// lists for a sub-domain's migration and ghosts), and adaptive mode's
// block sums, in one allocation of `capacity` particles on the Device policy. The allocation is
// checked against the device's free memory first, so that too many particles is an InvalidInput
// that says what was needed, not a failed allocation.
#pragma once

#include "ParticleChecks.h"
#include "StepSchedule.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace pbf
{
namespace cuda
{

// Which arrays beyond the common ones a store holds.
struct ParticleArrays
{
  bool masks = true;      // kNeighborRows words per particle (NeighborMasks.h)
  bool volumes = false;   // volume and |omega| stored by the passes that compute them
  bool alternates = false; // density, lambda, pressure and id again: the sub-domain's gathers
  bool moved = false;     // a float per particle: per-particle mask rebuilds (MovedSinceSort)
  int lists = 0;          // index lists (uint32 per particle): the sub-domain's selections
  // The scene's named liquids (Parameters::liquids): with any, a byte per particle (and one
  // more with the alternates); with several, adaptive mode's block sums per liquid.
  int liquids = 0;
  // Surface tension (SurfaceTension.h): the colour gradient and its smoothed normal, two Vec3 per
  // particle, written and read within a step (nothing to keep when the store grows).
  bool colour = false;
  // Mirror walls: the correction's warps' sums of the walls' loads (StepBuffers::wallWarps), a
  // word of flags and kWallLoadDoubles doubles per warp of 32 particles (9 bytes a particle),
  // for two passes at once (a sub-domain's border and interior).
  bool walls = false;
};

constexpr int kMaxParticleLists = 5;
// The warps of the walls' sums for `capacity` particles in two passes.
inline std::size_t wallWarpsFor(std::size_t capacity)
{
  return (capacity + 31) / 32 + 2;
}

template <class Real, class Device>
class DeviceParticleStore
{
public:
  DeviceParticleStore(Device& device, ParticleArrays arrays, std::size_t cells, int keyBits)
    : device_(device)
    , arrays_(arrays)
    , cells_(cells)
    , keyBits_(keyBits)
  {
  }
  ~DeviceParticleStore() { release(); }
  DeviceParticleStore(const DeviceParticleStore&) = delete;
  DeviceParticleStore& operator=(const DeviceParticleStore&) = delete;

  static std::size_t bytesPerParticle(const ParticleArrays& a)
  {
    const std::size_t scalars = 3 + (a.volumes ? 2 : 0) + (a.alternates ? 3 : 0);
    return (a.colour ? 6 : 4) * sizeof(Vec3<Real>) + scalars * sizeof(Real) +
      (a.alternates ? 2 : 1) * sizeof(std::int64_t) + 2 * sizeof(CellKey) +
      (a.liquids > 0 ? (a.alternates ? 2 : 1) : 0) * sizeof(std::uint8_t) +
      (a.masks ? kNeighborRows * sizeof(std::uint32_t) : 0) + (a.moved ? sizeof(float) : 0) +
      static_cast<std::size_t>(a.lists) * sizeof(std::uint32_t) +
      (a.walls ? (sizeof(std::uint32_t) + kWallLoadDoubles * sizeof(double) + 31) / 32 : 0);
  }

  // Head room for what the driver allocates beside us: the kernels' stacks, graphs, CUB's
  // per-launch state.
  static constexpr std::size_t kHeadRoom = std::size_t(128) << 20;

  std::size_t capacity() const { return capacity_; }
  const ParticleArrays& arrays() const { return arrays_; }
  // The allocation and the sort's scratch at this capacity.
  std::size_t bytes() const { return bytes_ + tempBytes_; }

  // Room for `needed` particles: when it must grow, to at least half again the capacity (so that
  // growing by steps reallocates O(log N) times) and 1024. The first `keep` particles of every
  // Vec3 buffer and of density, lambda, pressure, id and liquid are kept. The new arrays are
  // filled from the old on the device while both fit beside each other; where they do not (a
  // store that fills most of its device), it grows by a sixteenth only, and if even that does not
  // fit beside the old, the kept particles wait on the host while the old arrays make room. A
  // growth that does not fit at all leaves the store as it was and throws InvalidInput.
  void reserve(std::size_t needed, std::size_t keep)
  {
    if (needed <= capacity_ && capacity_ > 0)
    {
      return;
    }
    std::size_t capacity = std::max({ needed, capacity_ + capacity_ / 2, std::size_t(1024) });
    if (arena_ && !fitsBeside(capacity))
    {
      capacity = std::max(needed, capacity_ + capacity_ / 16);
    }
    if (arena_ && keep > 0 && !fitsBeside(capacity))
    {
      growThroughHost(capacity, needed, keep);
      return;
    }
    Pointers old = p;
    void* oldArena = arena_;
    arena_ = nullptr;
    try
    {
      layOut(capacity, needed);
    }
    catch (...)
    {
      arena_ = oldArena;
      p = old;
      throw;
    }
    if (keep > 0)
    {
      auto exec = device_.executor();
      for (int i = 0; i < 4; ++i)
      {
        exec.copy(p.vec[i], old.vec[i], keep * sizeof(Vec3<Real>));
      }
      exec.copy(p.density, old.density, keep * sizeof(Real));
      exec.copy(p.lambda, old.lambda, keep * sizeof(Real));
      exec.copy(p.pressure, old.pressure, keep * sizeof(Real));
      exec.copy(p.id, old.id, keep * sizeof(std::int64_t));
      if (p.liquid)
      {
        exec.copy(p.liquid, old.liquid, keep);
      }
    }
    device_.synchronize();
    if (oldArena)
    {
      device_.release(oldArena);
    }
  }

  // Exactly `capacity` particles, nothing kept (the caller frees the old arrays first with
  // release(), so that both never take memory together). `particles` names the count in the
  // message when it does not fit.
  void allocate(std::size_t capacity, std::size_t particles)
  {
    release();
    layOut(capacity, particles);
  }

  void release()
  {
    if (arena_)
    {
      device_.release(arena_);
    }
    arena_ = nullptr;
    p = Pointers{};
    capacity_ = 0;
    bytes_ = 0;
  }

  // The alternates become density, lambda and id, and these the alternates: a gather's result
  // taken over without a copy. What reserve() keeps follows.
  void swapAlternates()
  {
    std::swap(p.density, p.densityAlt);
    std::swap(p.lambda, p.lambdaAlt);
    std::swap(p.pressure, p.pressureAlt);
    std::swap(p.id, p.idAlt);
    std::swap(p.liquid, p.liquidAlt);
  }

  // The arrays' per-particle part as the stages see it (the caller adds the fixed arrays).
  StepBuffers<Real> buffers() const
  {
    StepBuffers<Real> b{};
    for (int i = 0; i < 4; ++i)
    {
      b.vec[i] = p.vec[i];
    }
    b.density = p.density;
    b.lambda = p.lambda;
    b.pressure = p.pressure;
    b.volume = p.volume;
    b.omegaLength = p.omegaLength;
    b.id = p.id;
    b.liquid = p.liquid;
    b.keys[0] = p.keys[0];
    b.keys[1] = p.keys[1];
    b.masks = p.masks;
    b.moved = p.moved;
    b.stride = static_cast<std::uint32_t>(capacity_);
    b.blockSums = p.blockSums;
    b.wallWarps = WarpSums{ p.wallFlags, p.wallValues };
    b.colour = p.colour;
    b.normal = p.normal;
    return b;
  }

  struct Pointers
  {
    Vec3<Real>* vec[4] = {};
    Vec3<Real> *colour = nullptr, *normal = nullptr;
    Real *density = nullptr, *lambda = nullptr, *volume = nullptr, *omegaLength = nullptr;
    Real *pressure = nullptr;
    Real *densityAlt = nullptr, *lambdaAlt = nullptr, *pressureAlt = nullptr;
    std::int64_t *id = nullptr, *idAlt = nullptr;
    std::uint8_t *liquid = nullptr, *liquidAlt = nullptr;
    CellKey* keys[2] = {};
    std::uint32_t* masks = nullptr;
    float* moved = nullptr;
    std::uint32_t* list[kMaxParticleLists] = {};
    // Per block of kCompressionBlock: sums, then maxima (with several liquids, per liquid a sum
    // and a count, then maxima: CudaStepReductions.cuh's compressionByLiquid).
    double* blockSums = nullptr;
    std::uint32_t* wallFlags = nullptr; // null without mirror walls (ParticleArrays::walls)
    double* wallValues = nullptr;
  };
  Pointers p;

private:
  // Where each array lies in an arena of `capacity` particles: byte offsets from its start, each
  // 256-byte aligned; 0 for an array the ParticleArrays leave out.
  struct Layout
  {
    std::size_t vec[4] = {};
    std::size_t colour = 0, normal = 0;
    std::size_t density = 0, lambda = 0, volume = 0, omegaLength = 0;
    std::size_t pressure = 0, densityAlt = 0, lambdaAlt = 0, pressureAlt = 0, id = 0, idAlt = 0;
    std::size_t liquid = 0, liquidAlt = 0;
    std::size_t keys[2] = {};
    std::size_t masks = 0, moved = 0;
    std::size_t list[kMaxParticleLists] = {};
    std::size_t blockSums = 0;
    std::size_t wallFlags = 0, wallValues = 0;
    std::size_t total = 0;
  };

  static Layout layoutOf(std::size_t capacity, const ParticleArrays& a)
  {
    Layout l;
    std::size_t offset = 0;
    auto place = [&offset](std::size_t bytes) {
      const std::size_t at = offset;
      offset += (bytes + 255) / 256 * 256;
      return at;
    };
    for (std::size_t& at : l.vec)
    {
      at = place(capacity * sizeof(Vec3<Real>));
    }
    l.colour = a.colour ? place(capacity * sizeof(Vec3<Real>)) : 0;
    l.normal = a.colour ? place(capacity * sizeof(Vec3<Real>)) : 0;
    const std::size_t scalar = capacity * sizeof(Real);
    l.density = place(scalar);
    l.lambda = place(scalar);
    l.pressure = place(scalar);
    l.volume = a.volumes ? place(scalar) : 0;
    l.omegaLength = a.volumes ? place(scalar) : 0;
    l.densityAlt = a.alternates ? place(scalar) : 0;
    l.lambdaAlt = a.alternates ? place(scalar) : 0;
    l.pressureAlt = a.alternates ? place(scalar) : 0;
    l.id = place(capacity * sizeof(std::int64_t));
    l.idAlt = a.alternates ? place(capacity * sizeof(std::int64_t)) : 0;
    l.liquid = a.liquids > 0 ? place(capacity) : 0;
    l.liquidAlt = a.liquids > 0 && a.alternates ? place(capacity) : 0;
    l.keys[0] = place(capacity * sizeof(CellKey));
    l.keys[1] = place(capacity * sizeof(CellKey));
    l.masks = a.masks ? place(kNeighborRows * capacity * sizeof(std::uint32_t)) : 0;
    l.moved = a.moved ? place(capacity * sizeof(float)) : 0;
    for (int k = 0; k < a.lists; ++k)
    {
      l.list[k] = place(capacity * sizeof(std::uint32_t));
    }
    const std::size_t perBlock = a.liquids > 1 ? 2 * static_cast<std::size_t>(a.liquids) + 1 : 2;
    l.blockSums = place(
      perBlock * ((capacity + kCompressionBlock - 1) / kCompressionBlock) * sizeof(double));
    const std::size_t warps = wallWarpsFor(capacity);
    l.wallFlags = a.walls ? place(warps * sizeof(std::uint32_t)) : 0;
    l.wallValues = a.walls ? place(warps * kWallLoadDoubles * sizeof(double)) : 0;
    l.total = offset;
    return l;
  }

  Pointers pointersInto(void* arena, const Layout& l) const
  {
    const ParticleArrays& a = arrays_;
    char* base = static_cast<char*>(arena);
    auto at = [base](std::size_t offsetOf) { return static_cast<void*>(base + offsetOf); };
    Pointers q;
    for (int i = 0; i < 4; ++i)
    {
      q.vec[i] = static_cast<Vec3<Real>*>(at(l.vec[i]));
    }
    q.colour = a.colour ? static_cast<Vec3<Real>*>(at(l.colour)) : nullptr;
    q.normal = a.colour ? static_cast<Vec3<Real>*>(at(l.normal)) : nullptr;
    q.density = static_cast<Real*>(at(l.density));
    q.lambda = static_cast<Real*>(at(l.lambda));
    q.pressure = static_cast<Real*>(at(l.pressure));
    q.volume = a.volumes ? static_cast<Real*>(at(l.volume)) : nullptr;
    q.omegaLength = a.volumes ? static_cast<Real*>(at(l.omegaLength)) : nullptr;
    q.densityAlt = a.alternates ? static_cast<Real*>(at(l.densityAlt)) : nullptr;
    q.lambdaAlt = a.alternates ? static_cast<Real*>(at(l.lambdaAlt)) : nullptr;
    q.pressureAlt = a.alternates ? static_cast<Real*>(at(l.pressureAlt)) : nullptr;
    q.id = static_cast<std::int64_t*>(at(l.id));
    q.idAlt = a.alternates ? static_cast<std::int64_t*>(at(l.idAlt)) : nullptr;
    q.liquid = a.liquids > 0 ? static_cast<std::uint8_t*>(at(l.liquid)) : nullptr;
    q.liquidAlt =
      a.liquids > 0 && a.alternates ? static_cast<std::uint8_t*>(at(l.liquidAlt)) : nullptr;
    q.keys[0] = static_cast<CellKey*>(at(l.keys[0]));
    q.keys[1] = static_cast<CellKey*>(at(l.keys[1]));
    q.masks = a.masks ? static_cast<std::uint32_t*>(at(l.masks)) : nullptr;
    q.moved = a.moved ? static_cast<float*>(at(l.moved)) : nullptr;
    for (int k = 0; k < a.lists; ++k)
    {
      q.list[k] = static_cast<std::uint32_t*>(at(l.list[k]));
    }
    q.blockSums = static_cast<double*>(at(l.blockSums));
    q.wallFlags = a.walls ? static_cast<std::uint32_t*>(at(l.wallFlags)) : nullptr;
    q.wallValues = a.walls ? static_cast<double*>(at(l.wallValues)) : nullptr;
    return q;
  }

  // What the arena (total bytes) and the sort's scratch (temp) need against the device's free
  // memory, as an InvalidInput naming the count when they do not fit.
  std::string memoryNeed(std::size_t particles, std::size_t capacity, std::size_t total,
    std::size_t temp, std::size_t reserve, std::size_t freeBytes, std::size_t totalBytes) const
  {
    auto mib = [](std::size_t bytes) { return std::to_string((bytes + (1u << 19)) >> 20); };
    return "particle count = " + std::to_string(particles) + " (capacity " +
      std::to_string(capacity) + "): the CUDA backend needs " + mib(total + temp) +
      " MiB of GPU memory for its particles (" + std::to_string(bytesPerParticle(arrays_)) +
      " bytes per particle, " + mib(temp) + " MiB of scratch for " + std::to_string(cells_ - 1) +
      " grid cells) plus " + mib(reserve) + " MiB head room, but " + device_.name() + " has " +
      mib(freeBytes) + " MiB free of " + mib(totalBytes) +
      " MiB; use fewer particles, a larger particleSpacing, more ranks or a CPU backend";
  }

  // Whether arrays of `capacity` fit in the device's free memory beside those held now.
  bool fitsBeside(std::size_t capacity) const
  {
    std::size_t freeBytes = 0, totalBytes = 0;
    device_.memoryInfo(freeBytes, totalBytes);
    const std::size_t need = layoutOf(capacity, arrays_).total +
      device_.tempBytesFor(static_cast<std::uint32_t>(std::min<std::size_t>(capacity,
                             std::numeric_limits<std::uint32_t>::max() - 1)),
        cells_, keyBits_) +
      kHeadRoom;
    return need <= freeBytes;
  }

  // The kept particles' arrays on the host while the old arena is released and the new one laid
  // out, then back; where the new one does not fit, the old capacity again, and the error.
  void growThroughHost(std::size_t capacity, std::size_t needed, std::size_t keep)
  {
    std::vector<Vec3<Real>> vec[4];
    std::vector<Real> density(keep), lambda(keep), pressure(keep);
    std::vector<std::int64_t> id(keep);
    std::vector<std::uint8_t> liquid(p.liquid ? keep : 0);
    for (int i = 0; i < 4; ++i)
    {
      vec[i].resize(keep);
      device_.download(vec[i].data(), p.vec[i], keep * sizeof(Vec3<Real>));
    }
    device_.download(density.data(), p.density, keep * sizeof(Real));
    device_.download(lambda.data(), p.lambda, keep * sizeof(Real));
    device_.download(pressure.data(), p.pressure, keep * sizeof(Real));
    device_.download(id.data(), p.id, keep * sizeof(std::int64_t));
    if (p.liquid)
    {
      device_.download(liquid.data(), p.liquid, keep);
    }
    device_.synchronize();
    const std::size_t before = capacity_;
    release();
    std::exception_ptr failure;
    try
    {
      layOut(capacity, needed);
    }
    catch (...)
    {
      failure = std::current_exception();
      layOut(before, keep); // it held them a moment ago
    }
    for (int i = 0; i < 4; ++i)
    {
      device_.upload(p.vec[i], vec[i].data(), keep * sizeof(Vec3<Real>));
    }
    device_.upload(p.density, density.data(), keep * sizeof(Real));
    device_.upload(p.lambda, lambda.data(), keep * sizeof(Real));
    device_.upload(p.pressure, pressure.data(), keep * sizeof(Real));
    device_.upload(p.id, id.data(), keep * sizeof(std::int64_t));
    if (p.liquid)
    {
      device_.upload(p.liquid, liquid.data(), keep);
    }
    device_.synchronize(); // the host vectors die here
    if (failure)
    {
      std::rethrow_exception(failure);
    }
  }

  void layOut(std::size_t capacity, std::size_t particles)
  {
    if (capacity >= std::numeric_limits<std::uint32_t>::max())
    {
      throw InvalidInput("particle count = " + std::to_string(capacity) +
        ": more than 32-bit indices hold");
    }
    const Layout layout = layoutOf(capacity, arrays_);
    const std::size_t total = layout.total;
    const std::size_t temp =
      device_.tempBytesFor(static_cast<std::uint32_t>(capacity), cells_, keyBits_);
    std::size_t freeBytes = 0, totalBytes = 0;
    device_.memoryInfo(freeBytes, totalBytes);
    const std::size_t reserve = kHeadRoom;
    const std::string need =
      memoryNeed(particles, capacity, total, temp, reserve, freeBytes, totalBytes);
    if (total + temp + reserve > freeBytes)
    {
      throw InvalidInput(need);
    }
    void* arena = device_.allocateOrNull(total);
    if (!arena)
    {
      throw InvalidInput(need + " (the allocation failed)");
    }
    try
    {
      device_.reserveTemp(static_cast<std::uint32_t>(capacity), cells_, keyBits_);
    }
    catch (...)
    {
      device_.release(arena);
      throw;
    }
    // Nothing reads these before writing them; zeroed all the same, so that a stale value can
    // never look like a result.
    device_.executor().fillZero(arena, total);
    arena_ = arena;
    p = pointersInto(arena, layout);
    capacity_ = capacity;
    bytes_ = total;
    tempBytes_ = temp;
  }

  Device& device_;
  ParticleArrays arrays_;
  std::size_t cells_; // grid cells + 1: the offsets' scan
  int keyBits_;
  void* arena_ = nullptr;
  std::size_t capacity_ = 0;
  std::size_t bytes_ = 0;
  std::size_t tempBytes_ = 0;
};

} // namespace cuda
} // namespace pbf
