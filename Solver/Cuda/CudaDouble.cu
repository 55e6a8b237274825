// Both CUDA steppers in double precision, on the CUDA device policy (CudaDevicePolicy.cuh). One
// translation unit per precision: the two compile in parallel, and the code both steppers share
// (DeviceHealth.h, the stages of StepSchedule.h) is instantiated once per precision, never
// identically in two units (SubdomainSchedule.h says why that matters).
#include "CudaDevicePolicy.cuh"

namespace pbf::cuda
{
template class DeviceStepper<double, CudaDevicePolicy<double>>;
template std::unique_ptr<CudaStepperInterface> makeCudaStepperOf<double>(
  const Parameters&, const ParticleBatch&, const Options&);
template std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepperOf<double>(
  distributed::Communicator&, const Parameters&, const FluidSource&, int, const Options&);
} // namespace pbf::cuda
