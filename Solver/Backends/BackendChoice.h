// Which backend a run gets from what the user asked for. Auto takes CUDA where it can run and
// the CPU (OpenMP) otherwise; CUDA asked for without a usable GPU is an error that says why. In a
// decomposed run every rank takes its local rank's GPU, and the ranks must agree before the first
// exchange (a rank without a GPU must not fail alone while the others wait for it), so CUDA runs
// there only when every rank has a GPU.
#pragma once

#include "Stepper.h"

#include <string>

namespace pbf
{
namespace distributed
{
class Communicator;
}

// The values are the ParaView property's (vtkPBFSimulation::Backends, the proxy's Backend
// entries), which the filter casts.
enum class BackendRequest
{
  Auto = 0,
  CUDA = 1,
  OpenMP = 2,
  Serial = 3
};

struct BackendChoice
{
  Backend backend = Backend::OpenMP;
  // Auto on the CPU: why CUDA is not used (for a notice); empty otherwise.
  std::string noCuda;
};

// `cudaHere`, `whyNot`: this process's probe (pbf::cudaAvailable). `ranks`: the communicator of a
// decomposed run, null otherwise; collective then when `requested` is Auto or CUDA. Throws
// std::runtime_error when CUDA is requested and cannot run.
BackendChoice chooseBackend(BackendRequest requested, bool cudaHere, const std::string& whyNot,
  distributed::Communicator* ranks = nullptr);

} // namespace pbf
