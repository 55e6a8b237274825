// The CUDA backend as the rest of the solver sees it: plain C++, no CUDA headers, so the tools
// and tests compile with the host compiler. makeStepper(Backend::CUDA, ...) gives the defaults;
// makeCudaStepper with Options is for the benchmark and the tests.
#pragma once

#include "Parameters.h"
#include "Stepper.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pbf
{

// Defined in CudaDevice.cu; Stepper.cpp declares them too, under PBF_WITH_CUDA.
std::unique_ptr<Stepper> makeCudaStepper(
  Precision precision, const Parameters& parameters, const ParticleBatch& initial);
// False, with the reason, when there is no usable CUDA device (no driver, no device, or a device
// this build's kernels cannot run on).
bool cudaDevicePresent(std::string* why);

namespace cuda
{

enum class NeighborSearch
{
  RowMasks, // per-step neighbour masks (NeighborMasks.h): the default, measured faster
  CellWalk, // walk the 27 cells in every pass, as the CPU backends do
};

struct Options
{
  NeighborSearch search = NeighborSearch::RowMasks;
  // How far beyond h the masks reach, as a fraction of h: larger means more candidates per pass
  // but fewer particles that must rebuild their masks within a step (MovedSinceSort,
  // NeighborMasks.h: each particle keeps the masks of the step's first pass while it and its
  // candidates moved less than the skin). Results do not depend on it. On the H200's benchmark
  // dam break, 0.075 h was the fastest of 0.002-0.1 h (Documentation/Performance.md): 2.3 builds
  // a step of 4 projections instead of 5; thicker skins visit more candidates than they save.
  double skin = 0.075;
  // Replay each step as one CUDA graph (no launch gaps); off: launch the kernels one by one.
  bool graphs = true;
  // Threads per block of the neighbour passes: a multiple of 32 up to 128.
  int block = 128;
  // Test hook, 0 = off: step number N (1-based) also launches a kernel that traps. CUDA reports
  // that as cudaErrorLaunchFailure at the next synchronisation and loses the context for the
  // rest of the process, as on a lost device: the fault tests drive the recovery path with it.
  // Without Options (makeStepper), the environment variable PBF_CUDA_FAULT_AT_STEP sets it.
  std::uint64_t faultAtStep = 0;
};

// The largest Options::block: the neighbour passes' shared rows hold this many threads.
constexpr int kMaxOptionsBlock = 128;

// The checks of Options that every CUDA stepper makes before it touches the device.
inline void validateOptions(const Options& options)
{
  if (!(options.skin > 0.0 && options.skin <= 1.0))
  {
    throw InvalidInput("CUDA skin = " + std::to_string(options.skin) +
      ": must lie in (0, 1] (a fraction of h)");
  }
  if (options.block < 32 || options.block > kMaxOptionsBlock || options.block % 32 != 0)
  {
    throw InvalidInput("CUDA block = " + std::to_string(options.block) +
      ": must be a multiple of 32 up to " + std::to_string(kMaxOptionsBlock));
  }
}

struct Diagnostics
{
  std::string device;             // "NVIDIA H200"
  std::size_t deviceBytes = 0;    // device memory the stepper holds
  std::size_t capacity = 0;       // particles that fit before the next reallocation
  double bytesPerParticle = 0;    // per-particle arrays only, per particle of capacity
  std::uint64_t steps = 0;
  // Particles' mask builds since construction: every particle builds once a step at least (the
  // first pass after the sort); the rest are rebuilds where particles moved more than the skin.
  std::uint64_t maskBuilds = 0;
};

// The CUDA stepper beyond the Stepper interface.
class CudaStepperInterface : public Stepper
{
public:
  virtual Diagnostics diagnostics() const = 0;
  virtual const Options& options() const = 0;
  // Waits for the queued steps; step() itself returns as soon as the work is queued.
  virtual void synchronize() const = 0;
  // The cudaStream_t the stepper queues its work on, for timing with events.
  virtual void* stream() const = 0;

  // The particles where they live on the device, in the stepper's order, as Vec3<Real> and Real
  // of precision(): for work that stays on the GPU (the surface, CudaSurface.h), queued on
  // stream() after the steps. Valid until the next step, append, load or setObstacles.
  struct DeviceState
  {
    const void* x = nullptr;
    const void* v = nullptr;
    const void* density = nullptr;
    std::size_t n = 0;
  };
  virtual DeviceState deviceState() const = 0;
};

// Throws InvalidInput for bad parameters or particles and when the particles do not fit in the
// device's free memory; std::runtime_error for CUDA errors and when no device is usable.
std::unique_ptr<CudaStepperInterface> makeCudaStepper(Precision precision,
  const Parameters& parameters, const ParticleBatch& initial, const Options& options);

// Device time between marks, from CUDA events recorded on a stepper's stream.
class EventTimer
{
public:
  explicit EventTimer(std::size_t maxMarks);
  ~EventTimer();
  EventTimer(const EventTimer&) = delete;
  EventTimer& operator=(const EventTimer&) = delete;

  void mark(const CudaStepperInterface& stepper);
  // Waits for the last mark; milliseconds between consecutive marks.
  std::vector<double> intervalsMs();

private:
  std::vector<void*> events_;
  std::size_t used_ = 0;
};

} // namespace cuda
} // namespace pbf
