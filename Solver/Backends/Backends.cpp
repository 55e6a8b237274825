#include "Backends.h"

#include "BackendChoice.h"
#include "CpuStepper.h"
#include "Distributed/SubdomainStepper.h"
#include "LocalRank.h"
#include "ParticleChecks.h"

#include <stdexcept>

#ifdef PBF_WITH_CUDA
#include "Cuda/CudaSubdomain.h"
#endif

namespace pbf
{

#ifdef PBF_WITH_CUDA
// Defined in Cuda/CudaDevice.cu; declared here so that no CUDA header reaches the CPU build.
std::unique_ptr<Stepper> makeCudaStepper(
  Precision precision, const Parameters& parameters, const ParticleBatch& initial);
bool cudaDevicePresent(std::string* why);
#endif

bool cudaAvailable(std::string* why)
{
#ifdef PBF_WITH_CUDA
  return cudaDevicePresent(why);
#else
  if (why)
  {
    *why = "this build has no CUDA backend (CUDA compiler not found at configure time)";
  }
  return false;
#endif
}

std::unique_ptr<Stepper> makeStepper(Backend backend, Precision precision,
  const Parameters& parameters, const ParticleBatch& initial)
{
  switch (backend)
  {
    case Backend::Serial:
    case Backend::OpenMP:
    {
      const bool parallel = backend == Backend::OpenMP;
      if (precision == Precision::Single)
      {
        return std::make_unique<CpuStepper<float>>(parallel, parameters, initial);
      }
      return std::make_unique<CpuStepper<double>>(parallel, parameters, initial);
    }
    case Backend::CUDA:
    {
      std::string why;
      if (!cudaAvailable(&why))
      {
        throw std::runtime_error("CUDA backend unavailable: " + why);
      }
#ifdef PBF_WITH_CUDA
      return makeCudaStepper(precision, parameters, initial);
#endif
    }
  }
  throw std::runtime_error("unknown backend");
}

namespace distributed
{

std::unique_ptr<Stepper> makeSubdomainStepper(Communicator& communicator, Backend backend,
  Precision precision, const Parameters& parameters, const FluidSource& fluid)
{
  if (backend == Backend::CUDA)
  {
    // Collective: every rank asks for CUDA, and they agree on whether all have a device before
    // any constructs (chooseBackend), so that a rank without one does not leave the others
    // waiting for it in the first exchange: then every rank throws.
    std::string why;
    chooseBackend(BackendRequest::CUDA, cudaAvailable(&why), why, &communicator);
#ifdef PBF_WITH_CUDA
    return cuda::makeCudaSubdomainStepper(communicator, precision, parameters, fluid,
      localRank(communicator) % cuda::cudaDeviceCount());
#else
    throw std::logic_error("chooseBackend let CUDA through in a build without it");
#endif
  }
  const bool parallel = backend == Backend::OpenMP;
  if (precision == Precision::Single)
  {
    return std::make_unique<SubdomainStepper<float>>(communicator, parallel, parameters, fluid);
  }
  return std::make_unique<SubdomainStepper<double>>(communicator, parallel, parameters, fluid);
}

std::unique_ptr<Stepper> makeSubdomainStepperAuto(Communicator& communicator, Precision precision,
  const Parameters& parameters, const FluidSource& fluid, Backend cpu)
{
  std::string why;
  const bool cuda = cudaAvailable(&why);
  const BackendChoice choice = chooseBackend(BackendRequest::Auto, cuda, why, &communicator);
  const Backend backend = choice.backend == Backend::CUDA ? Backend::CUDA : cpu;
  return makeSubdomainStepper(communicator, backend, precision, parameters, fluid);
}

std::unique_ptr<Stepper> makeSubdomainStepper(Communicator& communicator, Backend backend,
  Precision precision, const Parameters& parameters, const ParticleBatch& everything)
{
  checkBatch(parameters, everything);
  return makeSubdomainStepper(
    communicator, backend, precision, parameters, BatchSource(everything));
}

std::unique_ptr<Stepper> makeSubdomainStepperAuto(Communicator& communicator, Precision precision,
  const Parameters& parameters, const ParticleBatch& everything, Backend cpu)
{
  checkBatch(parameters, everything);
  return makeSubdomainStepperAuto(communicator, precision, parameters, BatchSource(everything), cpu);
}

} // namespace distributed
} // namespace pbf
