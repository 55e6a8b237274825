#include "Backends.h"

#include "CpuStepper.h"
#include "Distributed/SubdomainStepper.h"
#include "LocalRank.h"

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
  Precision precision, const Parameters& parameters, const ParticleBatch& everything)
{
  if (backend == Backend::CUDA)
  {
#ifdef PBF_WITH_CUDA
    // Collective: every rank asks for CUDA, and they agree on whether all have a device before
    // any constructs, so that a rank without one does not leave the others waiting for it in
    // the first exchange: then every rank throws.
    const int local = localRank(communicator);
    const int devices = cuda::cudaDeviceCount();
    std::string why;
    const bool mine = devices > 0 && cudaAvailable(&why);
    if (!everyRankHasAGpu(communicator))
    {
      throw std::runtime_error("CUDA backend unavailable on " +
        (mine ? std::string("another rank") :
                "rank " + std::to_string(communicator.rank()) + ": " +
              (why.empty() ? "no CUDA device" : why)) +
        "; a decomposed run needs a GPU on every rank for Backend = CUDA (Auto falls back to "
        "the CPU on every rank)");
    }
    return cuda::makeCudaSubdomainStepper(
      communicator, precision, parameters, everything, local % devices);
#else
    throw std::runtime_error("Backend = CUDA: this build has no CUDA backend (CUDA compiler not "
                             "found at configure time); choose CPU (OpenMP) or Serial");
#endif
  }
  const bool parallel = backend == Backend::OpenMP;
  if (precision == Precision::Single)
  {
    return std::make_unique<SubdomainStepper<float>>(communicator, parallel, parameters, everything);
  }
  return std::make_unique<SubdomainStepper<double>>(communicator, parallel, parameters, everything);
}

bool everyRankHasAGpu(Communicator& communicator)
{
  double mine = 0;
#ifdef PBF_WITH_CUDA
  mine = cudaAvailable() && cuda::cudaDeviceCount() > 0 ? 1.0 : 0.0;
#endif
  bool all = true;
  for (const std::vector<double>& r : allGather(communicator, { mine }))
  {
    all = all && r[0] != 0;
  }
  return all;
}

std::unique_ptr<Stepper> makeSubdomainStepperAuto(Communicator& communicator, Precision precision,
  const Parameters& parameters, const ParticleBatch& everything, Backend cpu)
{
  const Backend backend = everyRankHasAGpu(communicator) ? Backend::CUDA : cpu;
  return makeSubdomainStepper(communicator, backend, precision, parameters, everything);
}

} // namespace distributed
} // namespace pbf
