// The decomposed run's CUDA stepper as the rest of the solver sees it: plain C++, no CUDA
// headers (Distributed/SubdomainStepper.cpp calls it under PBF_WITH_CUDA).
#pragma once

#include "CudaBackend.h"
#include "Communicator.h"
#include "Distributed/SubdomainStepper.h"

#include <memory>

namespace pbf
{
namespace cuda
{

// One rank's DeviceSubdomainStepper on CUDA device `device`. Collective, like every
// decomposed stepper's constructor. Throws InvalidInput for bad input (adaptive iterations
// included: not available here), DeviceFault for CUDA errors, std::runtime_error when no device
// is usable.
// Every rank is handed the whole batch.
std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepper(
  distributed::Communicator& communicator, Precision precision, const Parameters& parameters,
  const ParticleBatch& everything, int device, const Options& options = Options{});
// Every rank counts the fluid per column and keeps its own slab (FluidSource.h).
std::unique_ptr<distributed::DecomposedStepper> makeCudaSubdomainStepper(
  distributed::Communicator& communicator, Precision precision, const Parameters& parameters,
  const FluidSource& fluid, int device, const Options& options = Options{});

// CUDA devices this process sees (0 without a driver or device).
int cudaDeviceCount();

} // namespace cuda
} // namespace pbf
