// CudaDevicePolicy's scanStatistics (StatisticsScan.h): the sums and maxima of a stepper's
// statistics(), reduced per block and then by one block in a fixed order, so that the result does
// not depend on scheduling: no float atomics. And the kernel of Options::faultAtStep.
#pragma once

#include "Equations.h"
#include "StatisticsScan.h"

#include <cuda_runtime.h>

#include <cstdint>

namespace pbf
{
namespace cuda
{

constexpr int kStatisticsBlocks = 512;
constexpr int kStatisticsThreads = 256;

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
__global__ void __launch_bounds__(kStatisticsThreads) statisticsKernel(
  StatisticsScan<Real> s, double* partials)
{
  const Vec3<Real>* x = s.x;
  const Vec3<Real>* v = s.v;
  const Real* density = s.density;
  const Vec3<Real>* sorted = s.sorted;
  const GridView<Real> grid = s.grid;
  const std::uint32_t n = s.n;
  const double h2 = s.h2;
  const double restDensity = s.restDensity;
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
    const double mass = s.massOf(i);
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

} // namespace cuda
} // namespace pbf
