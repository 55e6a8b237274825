// The CUDA backend's entry points: device detection, the factory, and event timing.
#include "CudaBackend.h"
#include "CudaRuntime.cuh"

#include <cuda_runtime.h>

#include <cstdlib>
#include <memory>
#include <string>

namespace pbf
{
namespace cuda
{

template <class Real>
std::unique_ptr<CudaStepperInterface> makeCudaStepperOf(
  const Parameters& parameters, const ParticleBatch& initial, const Options& options);

namespace
{
// Probes whether the device can run this build's kernels (built for one architecture).
__global__ void probeKernel() {}
} // namespace

std::unique_ptr<CudaStepperInterface> makeCudaStepper(Precision precision,
  const Parameters& parameters, const ParticleBatch& initial, const Options& options)
{
  if (precision == Precision::Single)
  {
    return makeCudaStepperOf<float>(parameters, initial, options);
  }
  return makeCudaStepperOf<double>(parameters, initial, options);
}

EventTimer::EventTimer(std::size_t maxMarks)
{
  events_.reserve(maxMarks);
  for (std::size_t i = 0; i < maxMarks; ++i)
  {
    cudaEvent_t event = nullptr;
    try
    {
      check(cudaEventCreate(&event), "cudaEventCreate");
    }
    catch (...)
    {
      for (void* e : events_)
      {
        cudaEventDestroy(static_cast<cudaEvent_t>(e));
      }
      throw;
    }
    events_.push_back(event);
  }
}

EventTimer::~EventTimer()
{
  for (void* e : events_)
  {
    cudaEventDestroy(static_cast<cudaEvent_t>(e));
  }
}

void EventTimer::mark(const CudaStepperInterface& stepper)
{
  if (used_ == events_.size())
  {
    throw std::runtime_error("EventTimer: more marks than the " +
      std::to_string(events_.size()) + " it was made for");
  }
  check(cudaEventRecord(static_cast<cudaEvent_t>(events_[used_]),
          static_cast<cudaStream_t>(stepper.stream())),
    "cudaEventRecord");
  ++used_;
}

std::vector<double> EventTimer::intervalsMs()
{
  std::vector<double> ms;
  if (used_ == 0)
  {
    return ms;
  }
  check(cudaEventSynchronize(static_cast<cudaEvent_t>(events_[used_ - 1])),
    "cudaEventSynchronize");
  for (std::size_t i = 1; i < used_; ++i)
  {
    float t = 0;
    check(cudaEventElapsedTime(&t, static_cast<cudaEvent_t>(events_[i - 1]),
            static_cast<cudaEvent_t>(events_[i])),
      "cudaEventElapsedTime");
    ms.push_back(t);
  }
  return ms;
}

} // namespace cuda

bool cudaDevicePresent(std::string* why)
{
  auto fail = [why](const std::string& reason) {
    if (why)
    {
      *why = reason;
    }
    return false;
  };
  if (!cuda::contextLostReason().empty())
  {
    return fail("an earlier " + cuda::contextLostReason() +
      " lost the CUDA context of this process; restart the application to use the GPU again");
  }
  int count = 0;
  cudaError_t error = cudaGetDeviceCount(&count);
  if (error != cudaSuccess)
  {
    cudaGetLastError();
    return fail(std::string("cudaGetDeviceCount: ") + cudaGetErrorName(error) + " (" +
      cudaGetErrorString(error) + ")");
  }
  if (count == 0)
  {
    return fail("cudaGetDeviceCount found no CUDA device");
  }
  int device = 0;
  cudaGetDevice(&device);
  cudaFuncAttributes attributes{};
  error = cudaFuncGetAttributes(&attributes, cuda::probeKernel);
  if (error != cudaSuccess)
  {
    cudaGetLastError();
    cudaDeviceProp properties{};
    cudaGetDeviceProperties(&properties, device);
    return fail(std::string(properties.name) + " (compute capability " +
      std::to_string(properties.major) + "." + std::to_string(properties.minor) +
      ") cannot run this build's kernels: " + cudaGetErrorString(error) +
      "; rebuild with CMAKE_CUDA_ARCHITECTURES including it");
  }
  return true;
}

std::unique_ptr<Stepper> makeCudaStepper(
  Precision precision, const Parameters& parameters, const ParticleBatch& initial)
{
  cuda::Options options;
  // The fault tests' hook (Options::faultAtStep) for callers that cannot pass Options, such as
  // the VTK filter in the pipeline fault test.
  if (const char* at = std::getenv("PBF_CUDA_FAULT_AT_STEP"))
  {
    options.faultAtStep = std::strtoull(at, nullptr, 10);
  }
  // PBF_CUDA_GRAPHS=0 launches the kernels one by one (Options::graphs): the same kernels, for
  // compute-sanitizer's racecheck, which dies on a graph with conditional nodes (run.sh).
  if (const char* graphs = std::getenv("PBF_CUDA_GRAPHS"))
  {
    options.graphs = std::string(graphs) != "0";
  }
  return cuda::makeCudaStepper(precision, parameters, initial, options);
}

} // namespace pbf
