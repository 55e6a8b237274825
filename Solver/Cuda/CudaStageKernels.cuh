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

} // namespace cuda
} // namespace pbf
