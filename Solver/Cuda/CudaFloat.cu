// Both CUDA steppers in float precision, on the CUDA device policy (CudaDevicePolicy.cuh). One
// translation unit per precision: the two compile in parallel, and the code both steppers share
// (DeviceHealth.h, the stages of StepSchedule.h) is instantiated once per precision, never
// identically in two units (SubdomainSchedule.h says why that matters).
#include "CudaDevicePolicy.cuh"

namespace pbf::cuda
{
template class DeviceStepper<float, CudaDevicePolicy<float>>;
template std::unique_ptr<CudaStepperInterface> makeCudaStepperOf<float>(
  const Parameters&, const ParticleBatch&, const Options&);
template std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepperOf<float>(
  distributed::Communicator&, const Parameters&, const FluidSource&, int, const Options&);
} // namespace pbf::cuda
