// CudaStepper in double precision.
#include "CudaStepper.cuh"

namespace pbf
{
namespace cuda
{
template class CudaStepper<double>;
template std::unique_ptr<CudaStepperInterface> makeCudaStepperOf<double>(
  const Parameters&, const ParticleBatch&, const Options&);
} // namespace cuda
} // namespace pbf
