// The reductions of CudaStepper over its particles: statistics() (sums and maxima for the
// diagnostics) and health() (the divergence check's scan), each reduced per block and then by one
// block in a fixed order, so that the result does not depend on scheduling: no float atomics.
#pragma once

#include "Equations.h"

#include <cuda_runtime.h>

#include <cstdint>

namespace pbf
{
namespace cuda
{

// statistics(): sums and maxima over particles, reduced per block and then by one block in a
// fixed order, so the result does not depend on scheduling.
constexpr int kStatisticsValues = 9;
constexpr int kStatisticsBlocks = 512;
constexpr int kStatisticsThreads = 256;
enum StatisticsValue
{
  kErrorSum,
  kErrorMax,
  kNeighborSum,
  kSpeedMax,
  kKinetic,
  kMomentumX,
  kMomentumY,
  kMomentumZ,
  kNonFinite, // max of 0/1
};

__device__ inline bool statisticsIsMax(int value)
{
  return value == kErrorMax || value == kSpeedMax || value == kNonFinite;
}

__device__ inline void reduceBlock(double (*shared)[kStatisticsThreads], double* acc, double* out)
{
  const int t = threadIdx.x;
  for (int v = 0; v < kStatisticsValues; ++v)
  {
    shared[v][t] = acc[v];
  }
  __syncthreads();
  for (int width = kStatisticsThreads / 2; width > 0; width >>= 1)
  {
    if (t < width)
    {
      for (int v = 0; v < kStatisticsValues; ++v)
      {
        const double a = shared[v][t];
        const double b = shared[v][t + width];
        shared[v][t] = statisticsIsMax(v) ? (b > a ? b : a) : a + b;
      }
    }
    __syncthreads();
  }
  if (t < kStatisticsValues)
  {
    out[t] = shared[t][0];
  }
}

// The same quantities as CpuStepper::statistics(), in double. Neighbours are counted on `sorted`,
// the positions sorted into a grid of their own (enqueueSortedCopy), as the CPU counts them.
template <class Real>
__global__ void __launch_bounds__(kStatisticsThreads) statisticsKernel(const Vec3<Real>* x,
  const Vec3<Real>* v, const Real* density, const Vec3<Real>* sorted, GridView<Real> grid,
  std::uint32_t n, double h2, double mass, double restDensity, double* partials)
{
  __shared__ double shared[kStatisticsValues][kStatisticsThreads];
  double acc[kStatisticsValues] = {};
  const std::uint32_t stride = gridDim.x * blockDim.x;
  for (std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += stride)
  {
    const double error = fmax(static_cast<double>(density[i]) / restDensity - 1.0, 0.0);
    acc[kErrorSum] += error;
    acc[kErrorMax] = fmax(acc[kErrorMax], error);
    const Vec3d si = Vec3d::from(sorted[i]);
    double neighbors = 0;
    forEachNeighbor(grid, i, [&](std::uint32_t j) {
      const Vec3d r = si - Vec3d::from(sorted[j]);
      // Rounded like the host's dot (no FMA): lattice pairs sit at exactly h, and the count must
      // not depend on how r^2 rounds there.
      const double r2 =
        __dadd_rn(__dadd_rn(__dmul_rn(r.x, r.x), __dmul_rn(r.y, r.y)), __dmul_rn(r.z, r.z));
      neighbors += (j != i && r2 < h2) ? 1.0 : 0.0;
    });
    acc[kNeighborSum] += neighbors;
    const Vec3d xi = Vec3d::from(x[i]);
    const Vec3d vi = Vec3d::from(v[i]);
    const double speed2 = dot(vi, vi);
    acc[kSpeedMax] = fmax(acc[kSpeedMax], sqrt(speed2));
    acc[kKinetic] += 0.5 * mass * speed2;
    acc[kMomentumX] += vi.x * mass;
    acc[kMomentumY] += vi.y * mass;
    acc[kMomentumZ] += vi.z * mass;
    if (!isfinite(xi.x + xi.y + xi.z + vi.x + vi.y + vi.z))
    {
      acc[kNonFinite] = 1.0;
    }
  }
  reduceBlock(shared, acc, partials + static_cast<std::size_t>(blockIdx.x) * kStatisticsValues);
}

// Options::faultAtStep's kernel: a trap, which CUDA treats as a fatal device fault.
template <class Real>
__global__ void injectedFault()
{
  __trap();
}

// A template only so that each precision's translation unit has its own instance.
template <class Real>
__global__ void __launch_bounds__(kStatisticsThreads) statisticsFinalKernel(
  const double* partials, int blocks, double* result)
{
  __shared__ double shared[kStatisticsValues][kStatisticsThreads];
  double acc[kStatisticsValues] = {};
  for (int b = threadIdx.x; b < blocks; b += blockDim.x)
  {
    for (int v = 0; v < kStatisticsValues; ++v)
    {
      const double value = partials[static_cast<std::size_t>(b) * kStatisticsValues + v];
      acc[v] = statisticsIsMax(v) ? fmax(acc[v], value) : acc[v] + value;
    }
  }
  reduceBlock(shared, acc, result);
}

// health(): the divergence check's scan and the automatic time step's fastest particle, every
// step, so it is three maxima over particles and nothing else: the largest speed^2, the largest
// rho_i / rho_0 - 1 and whether anything is not finite. Maxima do not depend on the order.
constexpr int kHealthValues = 3;
constexpr int kHealthBlocks = 264; // two per SM of an H100 or H200

template <class Real>
__global__ void __launch_bounds__(kStatisticsThreads) healthKernel(const Vec3<Real>* x,
  const Vec3<Real>* v, const Real* density, std::uint32_t n, double inverseRestDensity,
  double* partials)
{
  __shared__ double shared[kHealthValues][kStatisticsThreads];
  double acc[kHealthValues] = { 0.0, -1.0, 0.0 };
  for (std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x)
  {
    const Vec3d vi = Vec3d::from(v[i]);
    const Vec3d xi = Vec3d::from(x[i]);
    const double speed2 = dot(vi, vi);
    const bool finite = isfinite(xi.x + xi.y + xi.z + vi.x + vi.y + vi.z);
    acc[0] = finite ? fmax(acc[0], speed2) : acc[0];
    acc[1] = fmax(acc[1], double(density[i]) * inverseRestDensity - 1.0);
    acc[2] = finite ? acc[2] : 1.0;
  }
  const int t = threadIdx.x;
  for (int k = 0; k < kHealthValues; ++k)
  {
    shared[k][t] = acc[k];
  }
  __syncthreads();
  for (int width = kStatisticsThreads / 2; width > 0; width >>= 1)
  {
    if (t < width)
    {
      for (int k = 0; k < kHealthValues; ++k)
      {
        shared[k][t] = fmax(shared[k][t], shared[k][t + width]);
      }
    }
    __syncthreads();
  }
  if (t < kHealthValues)
  {
    partials[blockIdx.x * kHealthValues + t] = shared[t][0];
  }
}

// One thread: the blocks' maxima in order.
__global__ inline void healthFinalKernel(const double* partials, int blocks, double* result)
{
  double acc[kHealthValues] = { 0.0, -1.0, 0.0 };
  for (int b = 0; b < blocks; ++b)
  {
    for (int k = 0; k < kHealthValues; ++k)
    {
      acc[k] = fmax(acc[k], partials[b * kHealthValues + k]);
    }
  }
  for (int k = 0; k < kHealthValues; ++k)
  {
    result[k] = acc[k];
  }
}

} // namespace cuda
} // namespace pbf
