// The decomposed CUDA stepper in double precision (one precision per translation unit, so that
// they compile in parallel).
#include "CudaDevicePolicy.cuh"

namespace pbf
{
namespace cuda
{

template std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepperOf<double>(
  distributed::Communicator&, const Parameters&, const ParticleBatch&, int, const Options&);

} // namespace cuda
} // namespace pbf
