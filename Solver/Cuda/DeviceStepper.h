// The single-GPU stepper: the state lives in device memory from construction to destruction; a
// step is StepLoop.h run over DeviceStepLoop.h, queued on the device (replayed as one captured graph
// when Options::graphs) and returns at once; read(), statistics(), health(), diagnostics() and, in
// adaptive mode, lastStep() are the only copies back, and only when called.
//
// Written over a Device policy, as DeviceSubdomainStepper is, so that the same code runs on CUDA
// (CudaDevicePolicy.cuh) and, in the tests, on host memory (Testing/Cuda/HostExecutor.h), where
// it must match the serial backend bit for bit. What it needs of the policy beyond
// DeviceSubdomainStepper's list:
//   allocateOrNull(bytes)                     nullptr when the device is out of memory
//   memoryInfo(free, total)                   the device's free and total bytes
//   tempBytesFor(particles, cells, keyBits)   the scratch reserveTemp would take
//   Graph; capture(graph, enqueue); launch(graph); destroy(graph)
//                                             enqueue(exec) recorded once, replayed by launch
//   scanStatistics(StatisticsScan, partials, result)   kStatisticsValues doubles into result
//   statisticsPartialBytes()                  the partials' size
//   injectFault()                             Options::faultAtStep: a fault at the next wait
//   void* stream() const                      the queue, for timing with events (null: none)
#pragma once

#include "CudaBackend.h"
#include "DeviceHealth.h"
#include "DeviceParticleStore.h"
#include "DeviceSolids.h"
#include "Equations.h"
#include "LiquidDensities.h"
#include "Outflow.h"
#include "ParticleChecks.h"
#include "StatisticsScan.h"
#include "SubdomainSchedule.h"
#include "DeviceStepLoop.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

namespace pbf
{
namespace cuda
{

template <class Real, class Device>
class DeviceStepper final : public CudaStepperInterface
{
public:
  DeviceStepper(const Parameters& parameters, const ParticleBatch& initial, const Options& options,
    std::unique_ptr<Device> device);
  ~DeviceStepper() override;
  DeviceStepper(const DeviceStepper&) = delete;
  DeviceStepper& operator=(const DeviceStepper&) = delete;

  void step() override;
  void append(const ParticleBatch& batch) override;
  std::size_t removeOutflow(const std::vector<Box>& zones) override;
  void setTimeStep(double dt, double pressureElapsed = 0) override;
  double timeStep() const override { return dt_; }

  std::size_t size() const override { return n_; }
  Backend backend() const override { return Backend::CUDA; }
  Precision precision() const override
  {
    return sizeof(Real) == sizeof(float) ? Precision::Single : Precision::Double;
  }
  std::string description() const override { return "CUDA, " + device_->name(); }

  void read(Snapshot<float>& out) const override { copyOut(out); }
  void read(Snapshot<double>& out) const override { copyOut(out); }
  void readInto(const SnapshotView<float>& out) const override { copyInto(out); }
  void readInto(const SnapshotView<double>& out) const override { copyInto(out); }
  Statistics statistics() const override;
  // Three maxima on the device and 24 bytes back (DeviceHealth.h): cheap enough for every step
  // (outside is 0: the collision step keeps finite positions in the box).
  Health health() const override;
  StepReport lastStep() const override;
  void load(const Snapshot<float>& state) override { loadState(state); }
  void load(const Snapshot<double>& state) override { loadState(state); }

  // Uploads the solids' distance grids and the boundary table (one allocation, DeviceSolids.h)
  // and captures the step again with them.
  void setObstacles(
    const std::vector<DistanceGrid>& obstacles, const std::vector<SolidPose>& poses = {}) override;
  void setObstaclePoses(const std::vector<SolidPose>& poses) override;

  Diagnostics diagnostics() const override;
  const Options& options() const override { return options_; }
  void synchronize() const override;
  void* stream() const override { return device_->stream(); }
  DeviceState deviceState() const override
  {
    return { buffers_.vec[roles_.x], buffers_.vec[roles_.v], buffers_.density, n_ };
  }


private:
  struct Graph
  {
    typename Device::Graph graph{};
    Roles next;
    const CellKey* sortedKeys = nullptr;
    bool captured = false;
  };

  // The arrays of the particle count and of the grid: the store's, and the fixed ones.
  void allocate(std::size_t capacity, std::size_t particles);
  void allocateFixed();
  void release();
  void releaseGraphs();
  void evaluateAtRest();
  // Drops the captured steps: the second step() from now captures the one its roles need
  // (captureGraph).
  void captureGraphs();
  void captureGraph(int x);
  // Uploads x, v, id, liquid and pressure of the n_ particles into a fresh allocation.
  void restore(const std::vector<Vec3<Real>>& x, const std::vector<Vec3<Real>>& v,
    const std::vector<std::int64_t>& id, const std::vector<std::uint8_t>& liquid,
    const std::vector<Real>& pressure);
  // After the particles changed (append, load, solids): density and lambda at rest, the step
  // captured again, and a wait (the host arrays that went up may die).
  void settle();
  template <class Out>
  void copyOut(Snapshot<Out>& out) const;
  template <class Out>
  void copyInto(const SnapshotView<Out>& out) const;
  template <class In>
  void loadState(const Snapshot<In>& state);

  Parameters parameters_;
  Options options_;
  std::unique_ptr<Device> device_;
  StepConstants<Real> constants_{};
  LatticeCalibration lattice_;
  double dt_ = 0;
  StepTime<Real>* deviceTime_ = nullptr; // constants_.time, in the fixed arrays
  void* solids_ = nullptr; // constants_.obstacles and .boundary: the solids' views, table, nodes
  std::vector<DistanceGridView<Real>> solidViews_; // as sampled, for placeSolids
  unsigned long long* healthBits_ = nullptr; // health(): kHealthWords (DeviceHealth.h)
  std::uint32_t* keptCount_ = nullptr;       // removeOutflow's selection count

  std::size_t n_ = 0;
  Roles roles_;
  const CellKey* sortedKeys_ = nullptr;
  std::uint64_t steps_ = 0;
  bool stepped_ = false; // lastStep() has a step to report

  std::unique_ptr<DeviceParticleStore<Real, Device>> store_;
  // The arrays that do not grow with the particles (the cell offsets, the step's counters and
  // the statistics' partial sums), in one allocation.
  void* fixed_ = nullptr;
  std::size_t fixedBytes_ = 0;
  StepBuffers<Real> fixedBuffers_{}; // the fixed arrays alone
  StepBuffers<Real> buffers_{}; // the store's arrays and the fixed ones, as the stages see them
  double* statisticsPartials_ = nullptr;
  double* statisticsResult_ = nullptr;

  Graph graphs_[2]; // by roles_.x
  std::uint64_t stepsAtThisCount_ = 0; // steps since the graphs were dropped
};

template <class Real, class Device>
DeviceStepper<Real, Device>::DeviceStepper(const Parameters& parameters,
  const ParticleBatch& initial, const Options& options, std::unique_ptr<Device> device)
  : parameters_(parameters)
  , options_(options)
  , device_(std::move(device))
{
  parameters_.validate();
  checkBatch(parameters_, initial);
  validateOptions(options_);
  constants_ = makeStepConstants<Real>(
    parameters_, options_.skin, options_.search == NeighborSearch::RowMasks);
  lattice_ = calibrateLattice(parameters_);
  device_->activate();
  ParticleArrays arrays;
  arrays.masks = constants_.schedule.enabled != 0;
  arrays.moved = arrays.masks;
  arrays.volumes = true;
  arrays.liquids = static_cast<int>(parameters_.liquids.size());
  arrays.colour = constants_.c.surfaceTension;
  arrays.walls = parameters_.sumsWallLoads();
  store_ = std::make_unique<DeviceParticleStore<Real, Device>>(
    *device_, arrays, std::size_t(constants_.cellCount) + 1, constants_.keyBits);
  try
  {
    allocateFixed();
    setTimeStep(parameters_.timeStep);
    allocate(std::max<std::size_t>(initial.position.size(), 1024), initial.position.size());
    append(initial);
  }
  catch (...)
  {
    release();
    store_.reset();
    if (fixed_)
    {
      device_->release(fixed_);
    }
    throw;
  }
}

template <class Real, class Device>
DeviceStepper<Real, Device>::~DeviceStepper()
{
  try
  {
    device_->activate();
    device_->synchronize();
  }
  catch (...)
  {
  }
  release();
  store_.reset();
  device_->release(fixed_);
  if (solids_)
  {
    device_->release(solids_);
  }
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::setTimeStep(double dt, double pressureElapsed)
{
  checkTimeStep(dt);
  device_->activate();
  const StepTime<Real> time = StepTime<Real>::make(parameters_, lattice_, dt, pressureElapsed);
  // Ordered before the next step; the policy stages the bytes before it returns, so `time` may go.
  device_->upload(deviceTime_, &time, sizeof time);
  dt_ = dt;
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::releaseGraphs()
{
  for (Graph& g : graphs_)
  {
    device_->destroy(g.graph);
    g = Graph{};
  }
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::evaluateAtRest()
{
  auto exec = device_->executor();
  enqueueEvaluateAtRest(
    exec, buffers_, constants_, static_cast<std::uint32_t>(n_), roles_, &sortedKeys_);
}

// A captured step keeps the buffers, constants and count of now, as a CUDA graph keeps its
// kernels' arguments, so anything that changes them drops the graphs. The first step after that
// is queued stage by stage; the second captures the step (one assignment of x and v at a time: an
// odd number of solver iterations swaps them every step and then uses both). A capture costs
// more than queueing a few steps, so a scene whose outflows remove particles at every step never
// pays for one.
template <class Real, class Device>
void DeviceStepper<Real, Device>::captureGraphs()
{
  releaseGraphs();
  stepsAtThisCount_ = 0;
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::captureGraph(int x)
{
  Roles roles;
  roles.x = x;
  roles.v = 1 - x;
  Graph* g = &graphs_[x];
  const StepBuffers<Real> buffers = buffers_;
  const StepConstants<Real> constants = constants_;
  const auto n = static_cast<std::uint32_t>(n_);
  device_->capture(g->graph, [=](auto& exec) {
    g->next = enqueueStep(exec, buffers, constants, n, roles, &g->sortedKeys);
  });
  g->captured = true;
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::settle()
{
  if (n_ > 0)
  {
    evaluateAtRest();
  }
  captureGraphs();
  device_->synchronize();
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::step()
{
  if (n_ == 0)
  {
    return;
  }
  device_->activate();
  if (options_.graphs && (graphs_[roles_.x].captured || stepsAtThisCount_ > 0))
  {
    Graph& g = graphs_[roles_.x];
    if (!g.captured)
    {
      captureGraph(roles_.x);
    }
    device_->launch(g.graph);
    roles_ = g.next;
    sortedKeys_ = g.sortedKeys;
  }
  else
  {
    auto exec = device_->executor();
    roles_ = enqueueStep(
      exec, buffers_, constants_, static_cast<std::uint32_t>(n_), roles_, &sortedKeys_);
  }
  ++steps_;
  ++stepsAtThisCount_;
  stepped_ = true;
  if (options_.faultAtStep != 0 && steps_ == options_.faultAtStep)
  {
    device_->injectFault();
  }
}

template <class Real, class Device>
void DeviceStepper<Real, Device>::synchronize() const
{
  device_->activate();
  device_->synchronize();
}

} // namespace cuda
} // namespace pbf

// The member functions on the memory, and on the scans and the solids.
#include "DeviceStepperMemory.h"
#include "DeviceStepperScans.h"
