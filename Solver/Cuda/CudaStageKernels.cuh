// The kernels that run a stage of StepSchedule.h on the GPU, one thread a particle: their launch
// shapes and register caps per stage (Launch), and the kernel that also takes the max of the
// stage's results.
#pragma once

#include "CudaBackend.h"
#include "NeighborMasks.h"
#include "StepBuffers.h"

#include <cuda_runtime.h>

#include <cstdint>

namespace pbf
{
namespace cuda
{

// Launch shapes per stage: the neighbour passes take their block size from Options::block (128 by
// default; 64, 128 and 256 run alike), the others run 128 threads a block.
//
// minBlocks: blocks of kMaxBlock threads that each multiprocessor must hold, which caps the
// registers a thread (65536 / (minBlocks * 128), rounded down to 8). The caps bind in double
// precision, where the passes otherwise take 72-98 registers and run at 4 blocks; single
// precision's kernels stay under every cap. Each cap is the fastest without spills that matter
// (Documentation/Performance.md, "Why the kernels are built this way").
template <class Stage>
struct Launch
{
  static constexpr bool neighborPass = false;
  static constexpr int minBlocks = 1;
};
// The moving solids' rotation (Boundary.h), seldom taken, would make ptxas give the density pass
// 56 registers in single precision (9 blocks instead of 10); the cap keeps it at 48.
template <class Real>
struct Launch<DensityStage<Real>>
{
  static constexpr bool neighborPass = true;
  static constexpr int minBlocks = sizeof(Real) == 4 ? 10 : 7; // <= 48 (single), 72 registers
};
template <>
struct Launch<CorrectionStage>
{
  static constexpr bool neighborPass = true;
  static constexpr int minBlocks = 6; // <= 80 registers (88 bytes of spills in double)
};
// With wall friction the pass also walks each near-wall neighbour's images, and in double
// precision spills under 7 blocks (72 registers) but not under 5 (96); without friction 7 is
// faster. The colour gradient (surface tension) walks the images as friction does, under the
// same cap.
template <bool Friction, bool Colour>
struct Launch<VorticityStage<Friction, Colour>>
{
  static constexpr bool neighborPass = true;
  static constexpr int minBlocks = Friction || Colour ? 5 : 7;
};
template <>
struct Launch<SmoothColourStage>
{
  static constexpr bool neighborPass = true;
  static constexpr int minBlocks = 7;
};
// Surface tension's divergence (SurfaceTension.h) adds a 2x2 moment matrix and a normal to the
// pass's registers: the cap of the friction's pass.
template <bool Tension>
struct Launch<ConfinementStage<Tension>>
{
  static constexpr bool neighborPass = true;
  static constexpr int minBlocks = Tension ? 5 : 7;
};
constexpr int kMaxBlock = kMaxOptionsBlock;
static_assert(kMaxBlock <= kMaskBlock, "forEachNeighbor's shared rows hold kMaskBlock threads");

template <class Stage, class F>
__global__ void __launch_bounds__(kMaxBlock, Launch<Stage>::minBlocks) stageKernel(
  Stage, std::uint32_t n, F f)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n)
  {
    f(i);
  }
}

// The max of a warp's bits, in every lane.
__device__ inline unsigned long long warpMax(unsigned long long bits)
{
  for (int offset = 16; offset > 0; offset >>= 1)
  {
    const unsigned long long other = __shfl_xor_sync(0xffffffffu, bits, offset);
    bits = other > bits ? other : bits;
  }
  return bits;
}

// As stageKernel, and the max of f's non-negative results: a warp max, then one integer atomic
// per warp (neighbour passes) or per block (the rest). The max is the same in any order, so this
// stays deterministic. A per-particle scan is over in a few microseconds, so its atomics on one
// word are its cost: one a warp had made the health scan's speed and compression maxima 30 us
// each at 1.15M particles on an H100 (the finiteness scan, which adds nothing, 8 us). A neighbour
// pass spreads its atomics over hundreds of microseconds, and a barrier before its warps may
// leave costs more than they do (1M benchmark +0.9 % per block).
template <class Stage, class F>
__global__ void __launch_bounds__(kMaxBlock, Launch<Stage>::minBlocks) stageMaxKernel(
  Stage, std::uint32_t n, unsigned long long* maxBits, F f)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  unsigned long long bits = 0;
  if (i < n)
  {
    bits = MaskSchedule::doubleToBits(f(i));
  }
  bits = warpMax(bits);
  if constexpr (Launch<Stage>::neighborPass)
  {
    if ((threadIdx.x & 31u) == 0 && bits != 0)
    {
      atomicMax(maxBits, bits);
    }
  }
  else
  {
    __shared__ unsigned long long blockBits[kMaxBlock / 32];
    const unsigned warp = threadIdx.x / 32u, warps = (blockDim.x + 31u) / 32u;
    if ((threadIdx.x & 31u) == 0)
    {
      blockBits[warp] = bits;
    }
    __syncthreads();
    if (warp == 0)
    {
      bits = threadIdx.x < warps ? blockBits[threadIdx.x] : 0ull;
      bits = warpMax(bits);
      if (threadIdx.x == 0 && bits != 0)
      {
        atomicMax(maxBits, bits);
      }
    }
  }
}

// The sum of a warp's values in lane 0, in a fixed tree (lane l adds lane l + 16, then + 8, ...):
// the same on every run.
__device__ inline double warpSum(double value)
{
  for (int offset = 16; offset > 0; offset >>= 1)
  {
    value += __shfl_down_sync(0xffffffffu, value, offset);
  }
  return value;
}

// The bits set in any lane of a warp, in every lane.
__device__ inline unsigned warpOr(unsigned bits)
{
  for (int offset = 16; offset > 0; offset >>= 1)
  {
    bits |= __shfl_xor_sync(0xffffffffu, bits, offset);
  }
  return bits;
}

// As stageMaxKernel, and the sums over each warp of what f put in its Part (WallLoads.h's
// WallLoadPart), added over a step's passes: warp w (lanes 32 w ... 32 w + 31 of the launch) sums
// each group g (a wall) that one of its lanes has, adds it to sums[w kValues + g kGroupValues + k]
// (written afresh where bit g of flags[w] was not set: the step zeroes only the flags) and sets
// that bit. A warp sums only the groups its lanes have: near a face of the tank, one of six. No
// barrier: a warp leaves when it is done, as the neighbour passes' maxima do.
template <class Stage, class Part, class F>
__global__ void __launch_bounds__(kMaxBlock, Launch<Stage>::minBlocks) stageMaxSumKernel(
  Stage, std::uint32_t n, unsigned long long* maxBits, WarpSums sums, F f)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  unsigned long long bits = 0;
  Part part; // default-initialised: what it holds is written only where a lane adds something
  if (i < n)
  {
    bits = MaskSchedule::doubleToBits(f(i, part));
  }
  bits = warpMax(bits);
  const bool lead = (threadIdx.x & 31u) == 0;
  if (lead && bits != 0)
  {
    atomicMax(maxBits, bits);
  }
  const unsigned groups = warpOr(part.groups());
  if (groups == 0)
  {
    return;
  }
  const std::uint32_t warp = i / 32u;
  const unsigned earlier = lead ? sums.flags[warp] : 0u;
  constexpr int values = Part::kGroups * Part::kGroupValues;
  // One group at a time: unrolled, every group's values would be live at once.
#pragma unroll 1
  for (int g = 0; g < Part::kGroups; ++g)
  {
    if (!(groups & (1u << g)))
    {
      continue;
    }
    double value[Part::kGroupValues];
    part.group(g, value);
    double* const out =
      sums.values + static_cast<std::size_t>(warp) * values + g * Part::kGroupValues;
#pragma unroll
    for (int k = 0; k < Part::kGroupValues; ++k)
    {
      const double sum = warpSum(value[k]);
      if (lead)
      {
        out[k] = earlier & (1u << g) ? out[k] + sum : sum;
      }
    }
  }
  if (lead)
  {
    sums.flags[warp] = earlier | groups;
  }
}

// The health scan in one pass (DeviceHealth.h): f(i) gives a particle's three maxima
// (s.maxima, non-negative doubles), taken as stageMaxKernel takes them outside the neighbour
// passes (a warp max, a block max, one integer atomic a block per maximum), and its bin s.bin of
// the `bins` counts, counted in shared memory and added to `counts` once a block. Integer maxima
// and sums: the same in any order.
template <class F>
__global__ void __launch_bounds__(kMaxBlock) healthKernel(
  std::uint32_t n, unsigned long long* maxBits, std::uint32_t* counts, int bins, F f)
{
  __shared__ unsigned long long blockBits[3][kMaxBlock / 32];
  extern __shared__ std::uint32_t blockCounts[];
  for (int b = static_cast<int>(threadIdx.x); b < bins; b += static_cast<int>(blockDim.x))
  {
    blockCounts[b] = 0;
  }
  __syncthreads();
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  unsigned long long bits[3] = { 0, 0, 0 };
  if (i < n)
  {
    const auto s = f(i);
    for (int k = 0; k < 3; ++k)
    {
      bits[k] = MaskSchedule::doubleToBits(s.maxima[k]);
    }
    // The lanes of a warp with one bin add their count once: most of a block's particles share
    // a few bins, and one shared atomic a lane serialises on them.
    const unsigned peers = __match_any_sync(__activemask(), s.bin);
    if ((threadIdx.x & 31u) == static_cast<unsigned>(__ffs(peers) - 1))
    {
      atomicAdd(&blockCounts[s.bin], static_cast<std::uint32_t>(__popc(peers)));
    }
  }
  const unsigned warp = threadIdx.x / 32u, warps = (blockDim.x + 31u) / 32u;
  for (int k = 0; k < 3; ++k)
  {
    bits[k] = warpMax(bits[k]);
    if ((threadIdx.x & 31u) == 0)
    {
      blockBits[k][warp] = bits[k];
    }
  }
  __syncthreads();
  if (warp == 0)
  {
    for (int k = 0; k < 3; ++k)
    {
      unsigned long long b = threadIdx.x < warps ? blockBits[k][threadIdx.x] : 0ull;
      b = warpMax(b);
      if (threadIdx.x == 0 && b != 0)
      {
        atomicMax(&maxBits[k], b);
      }
    }
  }
  for (int b = static_cast<int>(threadIdx.x); b < bins; b += static_cast<int>(blockDim.x))
  {
    if (blockCounts[b] != 0)
    {
      atomicAdd(&counts[b], blockCounts[b]);
    }
  }
}

} // namespace cuda
} // namespace pbf
