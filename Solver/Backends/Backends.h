// Where a run's stepper comes from: the one place that knows every backend. Which backend a
// request gets (BackendChoice.h), which GPU a rank takes (LocalRank.h) and the factories of the
// single-process and decomposed steppers live here, above the backends (Cpu/, Cuda/,
// Distributed/) and below Simulation, so that no backend includes another and the layers below
// see only the Stepper interface.
#pragma once

#include "Communicator.h"
#include "FluidSource.h"
#include "Stepper.h"

#include <memory>
#include <string>

namespace pbf
{

// True when this build has the CUDA backend and a CUDA device is present.
bool cudaAvailable(std::string* why = nullptr);

// Throws InvalidInput for bad parameters or positions, std::runtime_error when the backend is
// not available (no CUDA device, or built without CUDA).
std::unique_ptr<Stepper> makeStepper(Backend backend, Precision precision,
  const Parameters& parameters, const ParticleBatch& initial);

namespace distributed
{

// This rank's stepper for a decomposed run: SubdomainStepper of the precision, OpenMP or serial;
// with Backend::CUDA the CUDA sub-domain stepper (Cuda/DeviceSubdomainStepper.h) on the device
// numbered by this rank's local rank (LocalRank.h) modulo the devices it sees. Collective.
// Throws std::runtime_error for CUDA unless every rank has a GPU (chooseBackend decides).
// Every rank counts `fluid` per grid column and keeps its own slab (FluidSource.h), or is handed
// the whole batch `everything`.
std::unique_ptr<Stepper> makeSubdomainStepper(Communicator& communicator, Backend backend,
  Precision precision, const Parameters& parameters, const FluidSource& fluid);
std::unique_ptr<Stepper> makeSubdomainStepper(Communicator& communicator, Backend backend,
  Precision precision, const Parameters& parameters, const ParticleBatch& everything);

// Backend "Auto" for a decomposed run: CUDA when every rank has a usable GPU (chooseBackend),
// otherwise the CPU backend `cpu` on every rank. The CPU and CUDA sub-domain steppers exchange different messages
// (the CUDA one merges rounds), so the ranks of one run must all use the same kind: a rank
// without a GPU takes the whole run to the CPU. Collective.
std::unique_ptr<Stepper> makeSubdomainStepperAuto(Communicator& communicator, Precision precision,
  const Parameters& parameters, const FluidSource& fluid, Backend cpu = Backend::OpenMP);
std::unique_ptr<Stepper> makeSubdomainStepperAuto(Communicator& communicator, Precision precision,
  const Parameters& parameters, const ParticleBatch& everything, Backend cpu = Backend::OpenMP);

} // namespace distributed
} // namespace pbf
