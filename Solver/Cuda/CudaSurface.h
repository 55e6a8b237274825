// The fluid's surface on the GPU: the same mesh as extractSurface (Surface/SurfaceExtraction.h),
// bit for bit, from particles on the host or already on the device (a CUDA stepper's own, so a
// frame's surface costs no upload). Plain C++: the tools, the tests and the filter include it with
// the host compiler.
//
// The steps (Cuda/CudaSurface.cu): the particles sorted into cells of h with CUB's radix sort
// (by position within a cell, as on the CPU); the blocks of 8^3 grid cells within h of a particle
// marked in a bitmap and listed; each block's 729 nodes sampled by one thread block, which keeps
// the block only if the level passes through it; the kept blocks sampled again into memory, their
// cells counted (triangles, and the crossing edges each cell owns), scanned, then cut into
// triangles whose vertices are numbered from the scans (no sort of vertices); optional Laplacian
// smoothing; normals, velocity and density at the vertices. Every sum has one order, no float
// atomics: two runs give the same bits, and the CPU's.
#pragma once

#include "Parameters.h"
#include "SurfaceExtraction.h"
#include "Vec3.h"

#include <cstddef>
#include <memory>

namespace pbf
{
namespace cuda
{

// Particles in device memory (v and rho may be null).
template <class Real>
struct DeviceParticles
{
  const Vec3<Real>* x = nullptr;
  const Vec3<Real>* v = nullptr;
  const Real* rho = nullptr;
  std::size_t n = 0;
};

// The last extraction's time: the mesh made on the device (CUDA events), then its copy into the
// host's SurfaceMesh (wall time: through page-locked memory, then into the vectors).
struct SurfaceTimes
{
  double extractMs = 0;
  double downloadMs = 0;
};

// Holds its device arrays between calls (they grow, never shrink), so that a frame after the
// first allocates nothing. One extraction at a time.
class SurfaceExtractor
{
public:
  // Throws std::runtime_error when no CUDA device is usable.
  explicit SurfaceExtractor(int device = 0);
  ~SurfaceExtractor();
  SurfaceExtractor(const SurfaceExtractor&) = delete;
  SurfaceExtractor& operator=(const SurfaceExtractor&) = delete;

  // The solids (host views) clip the surface as on the CPU; their fields are copied up each call.
  // Host arrays: uploaded, extracted, downloaded. Throws as extractSurface does (bad options,
  // non-finite positions), and InvalidInput when the device's memory is too small.
  template <class Real>
  SurfaceMesh extract(const Vec3<Real>* x, const Vec3<Real>* v, const Real* rho, std::size_t n,
    const Parameters& parameters, const SurfaceOptions& options, const SurfaceSolids& solids = {});

  // Device arrays, read in order after the work already queued on `stream` (a cudaStream_t; null:
  // the extractor's own stream, after a device-wide wait).
  template <class Real>
  SurfaceMesh extract(const DeviceParticles<Real>& particles, const Parameters& parameters,
    const SurfaceOptions& options, void* stream = nullptr, const SurfaceSolids& solids = {});

  const SurfaceTimes& lastTimes() const;
  // The device memory the extractor holds now [bytes].
  std::size_t deviceBytes() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace cuda
} // namespace pbf
