// CUDA error handling and the kernel executor that runs StepSchedule.h on a stream.
#pragma once

#include "CudaBackend.h"
#include "DeviceFault.h"
#include "StepSchedule.h"

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <cub/device/device_select.cuh>
#include <thrust/iterator/counting_iterator.h>
#include <cuda/functional>
#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbf
{
namespace cuda
{

// The reason the CUDA context of this process was lost, empty while it is usable. The context is
// process-wide state in CUDA itself; this mirrors it so that later requests fail fast and clearly.
inline std::string& contextLostReason()
{
  static std::string reason;
  return reason;
}

// CUDA errors become DeviceFault exceptions naming the call; the process is never aborted.
inline void check(cudaError_t error, const char* what)
{
  if (error != cudaSuccess)
  {
    // Clear a non-sticky error so that the next call does not report it again. A sticky one (a
    // kernel faulted or trapped, the device fell off the bus) comes back from every later call:
    // the synchronisation below tells the two apart.
    cudaGetLastError();
    const bool lost = cudaDeviceSynchronize() != cudaSuccess;
    std::string text = std::string("CUDA error in ") + what + ": " + cudaGetErrorName(error) +
      " (" + cudaGetErrorString(error) + ")";
    if (lost)
    {
      if (contextLostReason().empty())
      {
        contextLostReason() = text;
      }
      text += "; the CUDA context of this process is lost: the GPU cannot be used again until "
              "the application restarts";
    }
    throw DeviceFault(text, lost);
  }
}

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

// A captured step's condition for one projection (KernelExecutor::branch); valid false: none.
struct GraphBranch
{
  cudaGraphConditionalHandle handle;
  bool valid;
};

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

// A captured step's next projection runs only if this reduction did not end the solve. A kernel
// of its own, launched only into graphs, so that the stage-by-stage step calls no device runtime
// function: that is the step compute-sanitizer's racecheck checks (2025.3.1 dies with SIGSEGV
// on a graph with conditional nodes; Utilities/gpu/run.sh sets PBF_CUDA_GRAPHS=0 for it).
template <class Real> // only so that each translation unit has its own instance
__global__ void setBranchKernel(const AdaptiveState* state, cudaGraphConditionalHandle next)
{
  cudaGraphSetConditional(next, state->done ? 0u : 1u);
}

// Runs the schedule's stages as kernels on one stream. Nothing here synchronises or allocates,
// so a step can be captured into a CUDA graph.
// An executor given a bodyStream records into the graph being captured on `stream`
// (CudaDevicePolicy::capture): runIfChain then makes conditional nodes and captures their bodies
// on bodyStream (a stream of its own: a capturing stream cannot capture into another graph).
class KernelExecutor
{
public:
  KernelExecutor(cudaStream_t stream, void* temp, std::size_t tempBytes, int neighborBlock,
    cudaStream_t bodyStream = nullptr)
    : stream_(stream)
    , temp_(temp)
    , tempBytes_(tempBytes)
    , neighborBlock_(neighborBlock)
    , bodyStream_(bodyStream)
  {
  }

  using Branch = GraphBranch;
  static Branch noBranch() { return { 0, false }; }

  // A condition of the graph being captured, off at each launch until a kernel sets it; none
  // when the stream is not being captured (runIfChain then runs its bodies unconditionally).
  Branch branch()
  {
    const Capture at = capture();
    if (!at.graph)
    {
      return noBranch();
    }
    Branch b{ 0, true };
    check(cudaGraphConditionalHandleCreate(&b.handle, at.graph, 0, cudaGraphCondAssignDefault),
      "cudaGraphConditionalHandleCreate");
    return b;
  }

  // body(executor, k) for k in [first, end), each as the body of an if-node on branches[k] that
  // sits inside the body before it (at most kChainDepth deep; then the next if-node follows the
  // outermost one). A condition that is not set then skips every later body at once: in a
  // sequence each skipped if-node cost the graph about 3 us. Every body at once when there is no
  // graph.
  template <class Body>
  void runIfChain(const Branch* branches, int first, int end, Body&& body)
  {
    for (int chainStart = first; chainStart < end; chainStart += kChainDepth)
    {
      const int chainEnd = chainStart + kChainDepth < end ? chainStart + kChainDepth : end;
      const Capture at = branches[chainStart].valid ? capture() : Capture{};
      if (!at.graph)
      {
        for (int k = chainStart; k < chainEnd; ++k)
        {
          body(*this, k);
        }
        continue;
      }
      // The outermost if-node follows what the stream captured so far; each later one follows
      // the last nodes of the body that holds it.
      cudaGraph_t graph = at.graph;
      std::vector<cudaGraphNode_t> after(at.dependencies, at.dependencies + at.count);
      for (int k = chainStart; k < chainEnd; ++k)
      {
        cudaGraphNodeParams params{};
        params.type = cudaGraphNodeTypeConditional;
        params.conditional.handle = branches[k].handle;
        params.conditional.type = cudaGraphCondTypeIf;
        params.conditional.size = 1;
        cudaGraphNode_t node = nullptr;
        check(cudaGraphAddNode(&node, graph, after.data(), nullptr, after.size(), &params),
          "cudaGraphAddNode");
        if (k == chainStart)
        {
          check(cudaStreamUpdateCaptureDependencies(stream_, &node, nullptr, 1,
                  cudaStreamSetCaptureDependencies),
            "cudaStreamUpdateCaptureDependencies");
        }
        graph = params.conditional.phGraph_out[0];
        check(cudaStreamBeginCaptureToGraph(bodyStream_, graph, nullptr, nullptr, 0,
                cudaStreamCaptureModeThreadLocal),
          "cudaStreamBeginCaptureToGraph");
        KernelExecutor e(bodyStream_, temp_, tempBytes_, neighborBlock_);
        try
        {
          body(e, k);
          cudaStreamCaptureStatus status{};
          const cudaGraphNode_t* last = nullptr;
          const cudaGraphEdgeData* edges = nullptr;
          std::size_t count = 0;
          check(cudaStreamGetCaptureInfo(
                  bodyStream_, &status, nullptr, nullptr, &last, &edges, &count),
            "cudaStreamGetCaptureInfo (conditional body)");
          after.assign(last, last + count);
        }
        catch (...)
        {
          cudaStreamEndCapture(bodyStream_, &graph);
          throw;
        }
        check(cudaStreamEndCapture(bodyStream_, &graph), "cudaStreamEndCapture (conditional body)");
      }
    }
  }

  template <class Stage, class F>
  void forEach(Stage stage, std::uint32_t n, F f)
  {
    if (n == 0)
    {
      return;
    }
    const int block = Launch<Stage>::neighborPass ? neighborBlock_ : kMaxBlock;
    stageKernel<<<(n + block - 1) / block, block, 0, stream_>>>(stage, n, f);
    check(cudaGetLastError(), "kernel launch");
  }

  template <class Stage, class F>
  void forEachMax(Stage stage, std::uint32_t n, unsigned long long* maxBits, F f)
  {
    if (n == 0)
    {
      return;
    }
    const int block = Launch<Stage>::neighborPass ? neighborBlock_ : kMaxBlock;
    stageMaxKernel<<<(n + block - 1) / block, block, 0, stream_>>>(stage, n, maxBits, f);
    check(cudaGetLastError(), "kernel launch");
  }

  SortedPairs sortByKey(CellKey* keys, CellKey* keysAlt, std::uint32_t* values,
    std::uint32_t* valuesAlt, std::uint32_t n, int keyBits)
  {
    cub::DoubleBuffer<CellKey> k(keys, keysAlt);
    cub::DoubleBuffer<std::uint32_t> v(values, valuesAlt);
    std::size_t bytes = tempBytes_;
    check(cub::DeviceRadixSort::SortPairs(temp_, bytes, k, v, n, 0, keyBits, stream_),
      "cub::DeviceRadixSort::SortPairs");
    return { k.Current(), v.Current() };
  }

  void maxScan(std::uint32_t* data, std::size_t count)
  {
    std::size_t bytes = tempBytes_;
    check(cub::DeviceScan::InclusiveScan(temp_, bytes, data, data, ::cuda::maximum<>{},
            static_cast<std::int64_t>(count), stream_),
      "cub::DeviceScan::InclusiveScan");
  }

  template <class Real>
  void reduceCompression(const Real* density, const std::uint8_t* liquid, std::uint32_t n,
    AdaptiveState* state, double* blockSums, const StepConstants<Real>& k, double tolerance,
    Branch next = noBranch())
  {
    const std::uint32_t blocks = (n + kCompressionBlock - 1) / kCompressionBlock;
    const int liquids = liquid ? k.liquids : 1;
    if (blocks > 0)
    {
      compressionBlocksKernel<Real><<<blocks, kReduceThreads, 0, stream_>>>(
        density, liquid, liquids, n, k.inverseRestDensity, state, blockSums);
      check(cudaGetLastError(), "kernel launch (compression)");
    }
    compressionFinalKernel<Real><<<1, kReduceThreads, 0, stream_>>>(
      blocks, n, liquids, tolerance, k.maxTolerance, state, blockSums);
    check(cudaGetLastError(), "kernel launch (compression)");
    if (next.valid)
    {
      setBranchKernel<Real><<<1, 1, 0, stream_>>>(state, next.handle);
      check(cudaGetLastError(), "kernel launch (branch)");
    }
  }

  template <class F>
  void sumLoads(std::uint32_t n, int count, const AdaptiveState* state, double* blockSums,
    double* loads, F f)
  {
    if (count <= 0)
    {
      return;
    }
    loadBlocksKernel<<<dim3(kLoadBlocks, static_cast<unsigned>(count)), kReduceThreads, 0,
      stream_>>>(n, state, blockSums, f);
    check(cudaGetLastError(), "kernel launch (loads)");
    loadFinalKernel<F><<<static_cast<unsigned>(count), kReduceThreads, 0, stream_>>>(
      state, blockSums, loads);
    check(cudaGetLastError(), "kernel launch (loads)");
  }

  // The indices i in [0, n) with pred(i), ascending, into out; their number into *count (device
  // memory). CUB's selection keeps the input order, so the result is deterministic.
  template <class Pred>
  void selectIf(std::uint32_t n, Pred pred, std::uint32_t* out, std::uint32_t* count)
  {
    if (n == 0)
    {
      fillZero(count, sizeof(std::uint32_t));
      return;
    }
    const thrust::counting_iterator<std::uint32_t> first(0);
    std::size_t bytes = 0;
    check(cub::DeviceSelect::If(nullptr, bytes, first, out, count, static_cast<std::int64_t>(n),
            pred, stream_),
      "cub::DeviceSelect::If (size query)");
    if (bytes > tempBytes_)
    {
      throw std::logic_error("selectIf: scratch of " + std::to_string(tempBytes_) +
        " bytes, needs " + std::to_string(bytes));
    }
    bytes = tempBytes_;
    check(cub::DeviceSelect::If(temp_, bytes, first, out, count, static_cast<std::int64_t>(n),
            pred, stream_),
      "cub::DeviceSelect::If");
  }

  void fillZero(void* pointer, std::size_t bytes)
  {
    check(cudaMemsetAsync(pointer, 0, bytes, stream_), "cudaMemsetAsync");
  }

  void copy(void* destination, const void* source, std::size_t bytes)
  {
    check(cudaMemcpyAsync(destination, source, bytes, cudaMemcpyDeviceToDevice, stream_),
      "cudaMemcpyAsync");
  }

  // Scratch the sort and the scan need, for up to `particles` particles and `cells` cells.
  static std::size_t tempBytesFor(std::uint32_t particles, std::size_t cells, int keyBits)
  {
    std::size_t sortBytes = 0, scanBytes = 0;
    cub::DoubleBuffer<CellKey> k(nullptr, nullptr);
    cub::DoubleBuffer<std::uint32_t> v(nullptr, nullptr);
    check(cub::DeviceRadixSort::SortPairs(nullptr, sortBytes, k, v, particles, 0, keyBits),
      "cub::DeviceRadixSort::SortPairs (size query)");
    std::uint32_t* none = nullptr;
    check(cub::DeviceScan::InclusiveScan(nullptr, scanBytes, none, none, ::cuda::maximum<>{},
            static_cast<std::int64_t>(cells)),
      "cub::DeviceScan::InclusiveScan (size query)");
    return sortBytes > scanBytes ? sortBytes : scanBytes;
  }

private:
  // The graph this executor records into and the nodes the next one depends on; no graph when it
  // does not record (CudaDevicePolicy::capture gives a recording executor the body stream): a
  // step queued stage by stage asks the stream nothing.
  struct Capture
  {
    cudaGraph_t graph = nullptr;
    const cudaGraphNode_t* dependencies = nullptr;
    std::size_t count = 0;
  };
  Capture capture() const
  {
    Capture at;
    if (!bodyStream_)
    {
      return at;
    }
    cudaStreamCaptureStatus status{};
    const cudaGraphEdgeData* edges = nullptr;
    unsigned long long id = 0;
    check(cudaStreamGetCaptureInfo(
            stream_, &status, &id, &at.graph, &at.dependencies, &edges, &at.count),
      "cudaStreamGetCaptureInfo");
    return status == cudaStreamCaptureStatusActive ? at : Capture{};
  }

  // How deep runIfChain nests its if-nodes before it starts the next chain (the conditional
  // bodies' nesting has no documented limit; this keeps it far from any).
  static constexpr int kChainDepth = 32;

  cudaStream_t stream_;
  void* temp_;
  std::size_t tempBytes_;
  int neighborBlock_;
  cudaStream_t bodyStream_;
};

} // namespace cuda
} // namespace pbf
