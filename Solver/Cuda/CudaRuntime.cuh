// CUDA error handling and the kernel executor that runs StepSchedule.h on a stream.
// The executor's kernels are in CudaStageKernels.cuh and CudaStepReductions.cuh.
#pragma once

#include "CudaBackend.h"
#include "CudaStageKernels.cuh"
#include "CudaStepReductions.cuh"
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

// A captured step's condition for one projection (KernelExecutor::branch); valid false: none.
struct GraphBranch
{
  cudaGraphConditionalHandle handle;
  bool valid;
};

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

  // The health scan (healthKernel): maxBits[0..2] the maxima of f(i).maxima over i in [0, n),
  // counts[b] += 1 for every i whose f(i).bin is b, in [0, bins).
  template <class F>
  void forEachHealth(
    std::uint32_t n, unsigned long long* maxBits, std::uint32_t* counts, int bins, F f)
  {
    if (n == 0)
    {
      return;
    }
    healthKernel<<<(n + kMaxBlock - 1) / kMaxBlock, kMaxBlock, bins * sizeof(std::uint32_t),
      stream_>>>(n, maxBits, counts, bins, f);
    check(cudaGetLastError(), "kernel launch");
  }

  // A neighbour pass as forEachMax whose f(i, part) also fills a Part that each warp adds to its
  // sums (stageMaxSumKernel), over the passes of a step.
  template <class Stage, class Part, class F>
  void forEachMaxSum(Stage stage, std::uint32_t n, unsigned long long* maxBits, Part, WarpSums sums,
    F f)
  {
    static_assert(Launch<Stage>::neighborPass, "a neighbour pass: its warps need no barrier");
    if (n == 0)
    {
      return;
    }
    const int block = neighborBlock_;
    stageMaxSumKernel<Stage, Part><<<(n + block - 1) / block, block, 0, stream_>>>(
      stage, n, maxBits, sums, f);
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
