// The Device policy of both GPU steppers (DeviceStepper, DeviceSubdomainStepper) on CUDA: a
// compute stream on the device, the kernel executor of StepSchedule.h, cudaMalloc'd arrays, the
// step captured as a CUDA graph, the statistics' reduction, and the transfers of the ghost and
// migration messages (each followed by a stream synchronisation before the exchange reads the
// bytes). The
// ghost refreshes' copies (downloadAside, uploadAside) run on a second stream, ordered against
// the compute stream by events, so that the interior pass does not queue behind the border
// fields' copy to the host nor the next pass behind the neighbours' fields' copy to the device.
// The passes' border launches and the packing of their fields run on a third stream of the
// highest priority, forked from the compute stream before them and joined after the interior
// launch, so that the border particles (a small launch) run beside the interior ones instead of
// before them and their fields leave sooner.
#pragma once

#include "CudaReductions.cuh"
#include "CudaRuntime.cuh"
#include "DeviceStepper.h"
#include "DeviceSubdomainStepper.h"

#include <cuda_runtime.h>

#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

namespace pbf
{
namespace cuda
{

// A predicate for sizing the selection's scratch (public: CUB's kernels name it). A template of
// Real, as everything with device code here, so that the float and the double translation units
// share no kernel (SubdomainSchedule.h says why).
template <class Real>
struct AnyIndex
{
  __host__ __device__ bool operator()(std::uint32_t) const { return true; }
};

template <class Real>
class CudaDevicePolicy
{
public:
  using Exec = KernelExecutor;

  CudaDevicePolicy(int device, int block)
    : device_(device)
    , block_(block)
  {
    std::string why;
    if (!cudaDevicePresent(&why))
    {
      throw std::runtime_error("CUDA backend unavailable: " + why);
    }
    check(cudaSetDevice(device_), "cudaSetDevice");
    cudaDeviceProp properties{};
    check(cudaGetDeviceProperties(&properties, device_), "cudaGetDeviceProperties");
    name_ = std::string(properties.name) + " (device " + std::to_string(device_) + ")";
    check(cudaStreamCreate(&stream_), "cudaStreamCreate");
    check(cudaStreamCreate(&copyStream_), "cudaStreamCreate");
    check(cudaStreamCreateWithFlags(&bodyStream_, cudaStreamNonBlocking), "cudaStreamCreate");
    int least = 0, greatest = 0;
    check(cudaDeviceGetStreamPriorityRange(&least, &greatest), "cudaDeviceGetStreamPriorityRange");
    check(cudaStreamCreateWithPriority(&borderStream_, cudaStreamDefault, greatest),
      "cudaStreamCreateWithPriority");
    for (cudaEvent_t* e : { &event_, &packed_, &uploaded_, &forked_, &joined_ })
    {
      check(cudaEventCreateWithFlags(e, cudaEventDisableTiming), "cudaEventCreate");
    }
  }

  ~CudaDevicePolicy()
  {
    cudaSetDevice(device_);
    cudaStreamSynchronize(stream_);
    cudaStreamSynchronize(copyStream_);
    cudaStreamSynchronize(borderStream_);
    if (temp_)
    {
      cudaFree(temp_);
    }
    cudaEventDestroy(event_);
    cudaEventDestroy(packed_);
    cudaEventDestroy(uploaded_);
    cudaEventDestroy(forked_);
    cudaEventDestroy(joined_);
    cudaStreamDestroy(borderStream_);
    cudaStreamDestroy(bodyStream_);
    cudaStreamDestroy(copyStream_);
    cudaStreamDestroy(stream_);
  }

  CudaDevicePolicy(const CudaDevicePolicy&) = delete;
  CudaDevicePolicy& operator=(const CudaDevicePolicy&) = delete;

  KernelExecutor executor() const { return KernelExecutor(stream_, temp_, tempBytes_, block_); }
  // The border stream's executor: per-particle launches only (no scratch: a sort or selection
  // there would fail, not race the compute stream's).
  KernelExecutor borderExecutor() const { return KernelExecutor(borderStream_, nullptr, 0, block_); }
  // The border stream starts after the work queued so far on the compute stream.
  void forkBorder()
  {
    check(cudaEventRecord(forked_, stream_), "cudaEventRecord");
    check(cudaStreamWaitEvent(borderStream_, forked_, 0), "cudaStreamWaitEvent");
  }
  // The compute stream's work queued from now on waits for the border stream's.
  void joinBorder()
  {
    check(cudaEventRecord(joined_, borderStream_), "cudaEventRecord");
    check(cudaStreamWaitEvent(stream_, joined_, 0), "cudaStreamWaitEvent");
  }

  void* allocate(std::size_t bytes)
  {
    void* p = nullptr;
    const cudaError_t error = cudaMalloc(&p, bytes);
    if (error == cudaErrorMemoryAllocation)
    {
      cudaGetLastError();
      throw InvalidInput("particle count: the CUDA backend could not allocate " +
        std::to_string(bytes >> 20) + " MiB more on " + name_ +
        "; use fewer particles, more ranks or a CPU backend");
    }
    check(error, "cudaMalloc");
    return p;
  }
  // nullptr when the device is out of memory (the caller says what it needed).
  void* allocateOrNull(std::size_t bytes)
  {
    void* p = nullptr;
    const cudaError_t error = cudaMalloc(&p, bytes);
    if (error == cudaErrorMemoryAllocation)
    {
      cudaGetLastError();
      return nullptr;
    }
    check(error, "cudaMalloc");
    return p;
  }
  void release(void* p) { cudaFree(p); }
  void memoryInfo(std::size_t& freeBytes, std::size_t& totalBytes)
  {
    check(cudaMemGetInfo(&freeBytes, &totalBytes), "cudaMemGetInfo");
  }
  void* stream() const { return stream_; }

  // The step as a CUDA graph: enqueue(exec) is recorded once on the compute stream (nothing runs)
  // and launch replays it with the arguments it was recorded with.
  struct Graph
  {
    cudaGraphExec_t exec = nullptr;
  };
  template <class Enqueue>
  void capture(Graph& g, Enqueue&& enqueue)
  {
    destroy(g);
    // Its conditional nodes' bodies are captured on the body stream (KernelExecutor::runIfChain).
    KernelExecutor exec(stream_, temp_, tempBytes_, block_, bodyStream_);
    cudaGraph_t graph = nullptr;
    check(cudaStreamBeginCapture(stream_, cudaStreamCaptureModeThreadLocal),
      "cudaStreamBeginCapture");
    try
    {
      enqueue(exec);
    }
    catch (...)
    {
      cudaStreamEndCapture(stream_, &graph);
      if (graph)
      {
        cudaGraphDestroy(graph);
      }
      throw;
    }
    check(cudaStreamEndCapture(stream_, &graph), "cudaStreamEndCapture");
    const cudaError_t error = cudaGraphInstantiate(&g.exec, graph, 0);
    cudaGraphDestroy(graph);
    check(error, "cudaGraphInstantiate");
  }
  void launch(const Graph& g) { check(cudaGraphLaunch(g.exec, stream_), "cudaGraphLaunch"); }
  void destroy(Graph& g)
  {
    if (g.exec)
    {
      cudaGraphExecDestroy(g.exec);
    }
    g.exec = nullptr;
  }

  // Per block, then one block in a fixed order (CudaReductions.cuh).
  static std::size_t statisticsPartialBytes()
  {
    return std::size_t(kStatisticsBlocks) * kStatisticsValues * sizeof(double);
  }
  void scanStatistics(const StatisticsScan<Real>& s, double* partials, double* result)
  {
    statisticsKernel<Real><<<kStatisticsBlocks, kStatisticsThreads, 0, stream_>>>(s, partials);
    check(cudaGetLastError(), "kernel launch (statistics)");
    statisticsFinalKernel<Real><<<1, kStatisticsThreads, 0, stream_>>>(
      partials, kStatisticsBlocks, result);
    check(cudaGetLastError(), "kernel launch (statistics)");
  }
  // Options::faultAtStep: a trapped kernel, reported at the next synchronisation.
  void injectFault() { injectedFault<Real><<<1, 1, 0, stream_>>>(); }
  void* allocateHost(std::size_t bytes)
  {
    void* p = nullptr;
    check(cudaMallocHost(&p, bytes), "cudaMallocHost");
    return p;
  }
  void releaseHost(void* p) { cudaFreeHost(p); }

  void download(void* host, const void* device, std::size_t bytes)
  {
    check(cudaMemcpyAsync(host, device, bytes, cudaMemcpyDeviceToHost, stream_), "cudaMemcpyAsync");
  }
  // From pageable memory the bytes are staged before this returns, so the caller may reuse them.
  void upload(void* device, const void* host, std::size_t bytes)
  {
    check(cudaMemcpyAsync(device, host, bytes, cudaMemcpyHostToDevice, stream_), "cudaMemcpyAsync");
  }
  // Both streams: after it, no copy of either is in flight.
  void synchronize()
  {
    check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
    check(cudaStreamSynchronize(copyStream_), "cudaStreamSynchronize");
    check(cudaStreamSynchronize(borderStream_), "cudaStreamSynchronize");
  }
  void recordEvent() { check(cudaEventRecord(event_, stream_), "cudaEventRecord"); }
  // Device -> page-locked host on the copy stream, after the work queued so far on the border
  // stream (where the fields are packed); the event that waitEvent waits for marks its end. The
  // compute stream goes on.
  void downloadAside(void* host, const void* device, std::size_t bytes)
  {
    check(cudaEventRecord(packed_, borderStream_), "cudaEventRecord");
    check(cudaStreamWaitEvent(copyStream_, packed_, 0), "cudaStreamWaitEvent");
    if (bytes > 0)
    {
      check(cudaMemcpyAsync(host, device, bytes, cudaMemcpyDeviceToHost, copyStream_),
        "cudaMemcpyAsync");
    }
    check(cudaEventRecord(event_, copyStream_), "cudaEventRecord");
  }
  // Page-locked host -> device on the copy stream (behind the last downloadAside); the work
  // queued on the compute stream from now on waits for it.
  void uploadAside(void* device, const void* host, std::size_t bytes)
  {
    if (bytes > 0)
    {
      check(cudaMemcpyAsync(device, host, bytes, cudaMemcpyHostToDevice, copyStream_),
        "cudaMemcpyAsync");
    }
    check(cudaEventRecord(uploaded_, copyStream_), "cudaEventRecord");
    check(cudaStreamWaitEvent(stream_, uploaded_, 0), "cudaStreamWaitEvent");
  }
  void waitEvent() { check(cudaEventSynchronize(event_), "cudaEventSynchronize"); }
  void activate() { check(cudaSetDevice(device_), "cudaSetDevice"); }
  std::string name() const { return name_; }

  // Scratch for the radix sorts, the offsets' scan and the selections at this capacity.
  static std::size_t tempBytesFor(std::uint32_t particles, std::size_t cells, int keyBits)
  {
    const std::size_t need = KernelExecutor::tempBytesFor(particles, cells, keyBits);
    std::size_t selectBytes = 0;
    std::uint32_t* none = nullptr;
    const thrust::counting_iterator<std::uint32_t> first(0);
    check(cub::DeviceSelect::If(nullptr, selectBytes, first, none, none,
            static_cast<std::int64_t>(particles), AnyIndex<Real>{}),
      "cub::DeviceSelect::If (size query)");
    // Room for the predicates' own instantiations, whose sizes the selection re-checks.
    return std::max(need, selectBytes) + 4096;
  }
  void reserveTemp(std::uint32_t particles, std::size_t cells, int keyBits)
  {
    const std::size_t need = tempBytesFor(particles, cells, keyBits);
    if (need <= tempBytes_)
    {
      return;
    }
    synchronize();
    if (temp_)
    {
      cudaFree(temp_);
      temp_ = nullptr;
      tempBytes_ = 0;
    }
    temp_ = allocate(need);
    tempBytes_ = need;
  }

private:
  int device_;
  int block_;
  std::string name_;
  cudaStream_t stream_ = nullptr;
  cudaStream_t copyStream_ = nullptr;
  cudaStream_t borderStream_ = nullptr;
  cudaStream_t bodyStream_ = nullptr; // where conditional bodies are captured (KernelExecutor)
  cudaEvent_t event_ = nullptr, packed_ = nullptr, uploaded_ = nullptr;
  cudaEvent_t forked_ = nullptr, joined_ = nullptr;
  void* temp_ = nullptr;
  std::size_t tempBytes_ = 0;
};

// The two steppers on this policy, instantiated once per precision (CudaFloat.cu, CudaDouble.cu).
template <class Real>
std::unique_ptr<CudaStepperInterface> makeCudaStepperOf(
  const Parameters& parameters, const ParticleBatch& initial, const Options& options)
{
  // The inputs first: bad ones are named even where no device is present.
  Parameters checked = parameters;
  checked.validate();
  checkBatch(checked, initial);
  validateOptions(options);
  std::string why;
  if (!cudaDevicePresent(&why))
  {
    throw std::runtime_error("CUDA backend unavailable: " + why);
  }
  int device = 0;
  check(cudaGetDevice(&device), "cudaGetDevice");
  return std::make_unique<DeviceStepper<Real, CudaDevicePolicy<Real>>>(
    parameters, initial, options, std::make_unique<CudaDevicePolicy<Real>>(device, options.block));
}

template <class Real>
std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepperOf(
  distributed::Communicator& communicator, const Parameters& parameters,
  const FluidSource& fluid, int device, const Options& options)
{
  validateOptions(options);
  return std::make_unique<DeviceSubdomainStepper<Real, CudaDevicePolicy<Real>>>(communicator,
    parameters, fluid, std::make_unique<CudaDevicePolicy<Real>>(device, options.block),
    options.skin,
    options.search == NeighborSearch::RowMasks);
}

} // namespace cuda
} // namespace pbf
