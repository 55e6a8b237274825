// Entry points of the decomposed CUDA stepper: the precision switch and the device count.
#include "CudaSubdomain.h"

#include "CudaDevicePolicy.cuh"

#include <cuda_runtime.h>

namespace pbf
{
namespace cuda
{

// Compiled in CudaFloat.cu and CudaDouble.cu.
extern template std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepperOf<float>(
  distributed::Communicator&, const Parameters&, const FluidSource&, int, const Options&);
extern template std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepperOf<double>(
  distributed::Communicator&, const Parameters&, const FluidSource&, int, const Options&);

std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepper(
  distributed::Communicator& communicator, Precision precision, const Parameters& parameters,
  const FluidSource& fluid, int device, const Options& options)
{
  if (precision == Precision::Single)
  {
    return makeCudaSubdomainStepperOf<float>(communicator, parameters, fluid, device, options);
  }
  return makeCudaSubdomainStepperOf<double>(communicator, parameters, fluid, device, options);
}

std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepper(
  distributed::Communicator& communicator, Precision precision, const Parameters& parameters,
  const ParticleBatch& everything, int device, const Options& options)
{
  checkBatch(parameters, everything);
  return makeCudaSubdomainStepper(
    communicator, precision, parameters, BatchSource(everything), device, options);
}

int cudaDeviceCount()
{
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess)
  {
    cudaGetLastError();
    return 0;
  }
  return count;
}

} // namespace cuda
} // namespace pbf
