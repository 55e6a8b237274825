// The decomposed CUDA stepper in float precision (one precision per translation unit, so that
// they compile in parallel).
#include "CudaDevicePolicy.cuh"

namespace pbf
{
namespace cuda
{

template std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepperOf<float>(
  distributed::Communicator&, const Parameters&, const ParticleBatch&, int, const Options&);

} // namespace cuda
} // namespace pbf
