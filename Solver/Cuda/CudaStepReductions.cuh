// The step's sums over the particles in a fixed order, so that they are the same on every run:
// adaptive mode's compression (KernelExecutor::reduceCompression) and the solids' loads
// (KernelExecutor::sumLoads), each summed by fixed blocks in a fixed tree, then the blocks' sums
// by one block likewise.
#pragma once

#include "Parameters.h"
#include "StepBuffers.h"

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>

namespace pbf
{
namespace cuda
{

// Adaptive mode's mean compression: fixed blocks of particles summed in a fixed tree, then the
// block sums by one block, so the result is the same on every run.
constexpr int kReduceThreads = 256;

__device__ inline void treeSum(double* shared)
{
  for (int width = kReduceThreads / 2; width > 0; width >>= 1)
  {
    if (static_cast<int>(threadIdx.x) < width)
    {
      shared[threadIdx.x] += shared[threadIdx.x + width];
    }
    __syncthreads();
  }
}

__device__ inline void treeMax(double* shared)
{
  for (int width = kReduceThreads / 2; width > 0; width >>= 1)
  {
    if (static_cast<int>(threadIdx.x) < width)
    {
      shared[threadIdx.x] = fmax(shared[threadIdx.x], shared[threadIdx.x + width]);
    }
    __syncthreads();
  }
}

// With several liquids (liquids > 1), each block sums each liquid's compression and count too:
// the mean is the most compressed liquid's (CpuStepper::compression). Blocks' sums of liquid l at
// blockSums[l blocks + b], counts at [(liquids + l) blocks + b], maxima at [2 liquids blocks + b].
template <class Real>
__device__ void compressionByLiquid(const Real* density, const std::uint8_t* liquid, int liquids,
  std::uint32_t begin, std::uint32_t end, double inverseRestDensity, double* shared,
  double* largest, double* blockSums)
{
  double sum[kMaxLiquids] = {}, count[kMaxLiquids] = {};
  double top = 0.0;
  for (std::uint32_t i = begin + threadIdx.x; i < end; i += kReduceThreads)
  {
    const double c = static_cast<double>(density[i]) * inverseRestDensity - 1.0;
    const double e = c < 0.0 ? 0.0 : c;
    const int mine = liquid[i];
#pragma unroll
    for (int l = 0; l < kMaxLiquids; ++l)
    {
      sum[l] += l == mine ? e : 0.0;
      count[l] += l == mine ? 1.0 : 0.0;
    }
    top = fmax(top, e);
  }
  largest[threadIdx.x] = top;
  __syncthreads();
  treeMax(largest);
  const std::uint32_t blocks = gridDim.x;
#pragma unroll
  for (int l = 0; l < kMaxLiquids; ++l)
  {
    if (l >= liquids)
    {
      break;
    }
    shared[threadIdx.x] = sum[l];
    __syncthreads();
    treeSum(shared);
    if (threadIdx.x == 0)
    {
      blockSums[l * blocks + blockIdx.x] = shared[0];
    }
    __syncthreads();
    shared[threadIdx.x] = count[l];
    __syncthreads();
    treeSum(shared);
    if (threadIdx.x == 0)
    {
      blockSums[(liquids + l) * blocks + blockIdx.x] = shared[0];
    }
    __syncthreads();
  }
  if (threadIdx.x == 0)
  {
    blockSums[2 * liquids * blocks + blockIdx.x] = largest[0];
  }
}

template <class Real>
__global__ void __launch_bounds__(kReduceThreads) compressionBlocksKernel(const Real* density,
  const std::uint8_t* liquid, int liquids, std::uint32_t n, double inverseRestDensity,
  const AdaptiveState* state, double* blockSums)
{
  __shared__ double shared[kReduceThreads];
  if (state->done)
  {
    return;
  }
  const std::uint32_t begin = blockIdx.x * kCompressionBlock;
  const std::uint32_t end = n - begin < kCompressionBlock ? n : begin + kCompressionBlock;
  __shared__ double largest[kReduceThreads];
  if (liquid && liquids > 1)
  {
    compressionByLiquid(
      density, liquid, liquids, begin, end, inverseRestDensity, shared, largest, blockSums);
    return;
  }
  double sum = 0.0, top = 0.0;
  for (std::uint32_t i = begin + threadIdx.x; i < end; i += kReduceThreads)
  {
    const double c = static_cast<double>(density[i]) * inverseRestDensity - 1.0;
    const double e = c < 0.0 ? 0.0 : c; // std::max(c, 0.0), as CpuStepper::compression
    sum += e;
    top = fmax(top, e);
  }
  shared[threadIdx.x] = sum;
  largest[threadIdx.x] = top;
  __syncthreads();
  treeSum(shared);
  treeMax(largest);
  if (threadIdx.x == 0)
  {
    // Sums first, then maxima: blockSums[b] and blockSums[gridDim.x + b].
    blockSums[blockIdx.x] = shared[0];
    blockSums[gridDim.x + blockIdx.x] = largest[0];
  }
}

template <class Real> // only so that each translation unit has its own instance
__global__ void __launch_bounds__(kReduceThreads) compressionFinalKernel(
  std::uint32_t blocks, std::uint32_t n, int liquids, double tolerance, double maxTolerance,
  AdaptiveState* state, const double* blockSums)
{
  __shared__ double shared[kReduceThreads];
  __shared__ double largest[kReduceThreads];
  __shared__ double counts[kReduceThreads];
  if (state->done)
  {
    return;
  }
  // One liquid: the sums at [b], the maxima at [blocks + b]; several: compressionByLiquid's.
  const int sums = liquids > 1 ? liquids : 1;
  double top = 0.0;
  for (std::uint32_t b = threadIdx.x; b < blocks; b += kReduceThreads)
  {
    top = fmax(top, blockSums[(liquids > 1 ? 2 * liquids : 1) * blocks + b]);
  }
  largest[threadIdx.x] = top;
  __syncthreads();
  treeMax(largest);
  double mean = 0.0;
  for (int l = 0; l < sums; ++l)
  {
    double sum = 0.0, count = 0.0;
    for (std::uint32_t b = threadIdx.x; b < blocks; b += kReduceThreads)
    {
      sum += blockSums[l * blocks + b];
      count += liquids > 1 ? blockSums[(liquids + l) * blocks + b] : 0.0;
    }
    shared[threadIdx.x] = sum;
    counts[threadIdx.x] = count;
    __syncthreads();
    treeSum(shared);
    treeSum(counts);
    if (liquids > 1)
    {
      mean = fmax(mean, counts[0] > 0.0 ? shared[0] / counts[0] : 0.0);
      if (threadIdx.x == 0)
      {
        state->liquidSum[l] = shared[0];
        state->liquidCount[l] = counts[0];
      }
    }
    else
    {
      mean = n > 0 ? shared[0] / n : 0.0;
    }
    __syncthreads();
  }
  if (threadIdx.x == 0)
  {
    state->densityError = mean;
    state->maxDensityError = largest[0];
    if (mean <= tolerance && (maxTolerance <= 0.0 || largest[0] <= maxTolerance))
    {
      state->done = 1;
    }
    else
    {
      ++state->iterations;
    }
  }
}

// Each lane's kLoadValues sums added over the block in a fixed tree: shared[v][0] holds value v's.
__device__ inline void treeSumLoads(double (*shared)[kReduceThreads], const double* acc)
{
  for (int v = 0; v < kLoadValues; ++v)
  {
    shared[v][threadIdx.x] = acc[v];
  }
  __syncthreads();
  for (int v = 0; v < kLoadValues; ++v)
  {
    treeSum(shared[v]);
  }
}

// The solids' loads (KernelExecutor::sumLoads): block (b, o) sums load o over the particles of its
// lanes (StepSchedule.h) in a fixed tree; blockSums[(o kLoadBlocks + b) kLoadValues + v].
template <class F>
__global__ void __launch_bounds__(kReduceThreads) loadBlocksKernel(
  std::uint32_t n, const AdaptiveState* state, double* blockSums, F f)
{
  __shared__ double shared[kLoadValues][kReduceThreads];
  if (state && state->done)
  {
    return;
  }
  const int o = static_cast<int>(blockIdx.y);
  double acc[kLoadValues] = {};
  const std::uint32_t stride = static_cast<std::uint32_t>(kLoadBlocks) * kReduceThreads;
  for (std::uint32_t i = blockIdx.x * kReduceThreads + threadIdx.x; i < n; i += stride)
  {
    f(i, o, acc);
    if (i >= n - stride)
    {
      break; // i + stride would wrap around 2^32
    }
  }
  treeSumLoads(shared, acc);
  if (threadIdx.x < kLoadValues)
  {
    blockSums[(static_cast<std::size_t>(o) * gridDim.x + blockIdx.x) * kLoadValues + threadIdx.x] =
      shared[threadIdx.x][0];
  }
}

// Block o adds load o's block sums, in a fixed tree, to loads[o kLoadValues + v]. F, the blocks'
// functor, only gives each translation unit an instance of its own.
template <class F>
__global__ void __launch_bounds__(kReduceThreads) loadFinalKernel(
  const AdaptiveState* state, const double* blockSums, double* loads)
{
  __shared__ double shared[kLoadValues][kReduceThreads];
  if (state && state->done)
  {
    return;
  }
  const std::size_t o = blockIdx.x;
  constexpr std::size_t blocks = kLoadBlocks;
  double acc[kLoadValues] = {};
  for (std::size_t b = threadIdx.x; b < blocks; b += kReduceThreads)
  {
    for (int v = 0; v < kLoadValues; ++v)
    {
      acc[v] += blockSums[(o * blocks + b) * kLoadValues + v];
    }
  }
  treeSumLoads(shared, acc);
  if (threadIdx.x < kLoadValues)
  {
    loads[o * kLoadValues + threadIdx.x] += shared[threadIdx.x][0];
  }
}

} // namespace cuda
} // namespace pbf
