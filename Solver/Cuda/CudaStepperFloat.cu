// CudaStepper in single precision.
#include "CudaStepper.cuh"

namespace pbf
{
namespace cuda
{
template class CudaStepper<float>;
template std::unique_ptr<CudaStepperInterface> makeCudaStepperOf<float>(
  const Parameters&, const ParticleBatch&, const Options&);
} // namespace cuda
} // namespace pbf
