// CudaStepper<Real>: the state lives on the GPU from construction to destruction; a step is one
// CUDA graph launch (StepSchedule.h captured once per particle count) and returns at once;
// read(), statistics(), diagnostics() and, in adaptive mode, lastStep() are the only copies back,
// and only when called.
#pragma once

#include "CudaBackend.h"
#include "CudaReductions.cuh"
#include "CudaRuntime.cuh"
#include "Equations.h"
#include "ParticleChecks.h"
#include "StepSchedule.h"

#include <cuda_runtime.h>

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

template <class Real>
class CudaStepper final : public CudaStepperInterface
{
public:
  CudaStepper(const Parameters& parameters, const ParticleBatch& initial, const Options& options);
  ~CudaStepper() override;
  CudaStepper(const CudaStepper&) = delete;
  CudaStepper& operator=(const CudaStepper&) = delete;

  void step() override;
  void append(const ParticleBatch& batch) override;
  void setTimeStep(double dt) override;
  double timeStep() const override { return dt_; }

  std::size_t size() const override { return n_; }
  Backend backend() const override { return Backend::CUDA; }
  Precision precision() const override
  {
    return sizeof(Real) == sizeof(float) ? Precision::Single : Precision::Double;
  }
  std::string description() const override { return "CUDA, " + deviceName_; }

  void read(Snapshot<float>& out) const override { copyOut(out); }
  void read(Snapshot<double>& out) const override { copyOut(out); }
  void readInto(const SnapshotView<float>& out) const override { copyInto(out); }
  void readInto(const SnapshotView<double>& out) const override { copyInto(out); }
  Statistics statistics() const override;
  // Three maxima on the device and 24 bytes back: cheap enough for every step (nonFinite is 0 or
  // 1, outside 0: the collision step keeps finite positions in the box).
  Health health() const override;
  StepReport lastStep() const override;
  void load(const Snapshot<float>& state) override { loadState(state); }
  void load(const Snapshot<double>& state) override { loadState(state); }

  // Uploads the solids' distance grids and the boundary table (one allocation) and captures the
  // step again with them.
  void setObstacles(const std::vector<DistanceGrid>& obstacles) override;

  Diagnostics diagnostics() const override;
  const Options& options() const override { return options_; }
  void synchronize() const override;
  void* stream() const override { return stream_; }

  // Bytes per particle of capacity that the per-particle arrays take.
  static std::size_t particleBytes(bool masks);

private:
  struct Graph
  {
    cudaGraphExec_t exec = nullptr;
    Roles next;
    const CellKey* sortedKeys = nullptr;
  };

  void selectDevice() const;
  void allocate(std::size_t capacity, std::size_t particles);
  void release();
  void releaseGraphs();
  StepBuffers<Real> buffers() const;
  KernelExecutor executor() const;
  void evaluateAtRest();
  void captureGraphs();
  // Uploads x, v and id of the n_ particles into a fresh allocation.
  void restore(const std::vector<Vec3<Real>>& x, const std::vector<Vec3<Real>>& v,
    const std::vector<std::int64_t>& id);
  template <class Out>
  void copyOut(Snapshot<Out>& out) const;
  template <class Out>
  void copyInto(const SnapshotView<Out>& out) const;
  template <class In>
  void loadState(const Snapshot<In>& state);

  Parameters parameters_;
  Options options_;
  StepConstants<Real> constants_{};
  LatticeCalibration lattice_;
  double dt_ = 0;
  StepTime<Real>* deviceTime_ = nullptr; // constants_.time: its own allocation, whatever the arena
  void* solids_ = nullptr; // constants_.obstacles and .boundary: the solids' views, table, nodes
  int device_ = 0;
  std::string deviceName_;
  cudaStream_t stream_ = nullptr;

  std::size_t n_ = 0;
  std::size_t capacity_ = 0;
  Roles roles_;
  const CellKey* sortedKeys_ = nullptr;
  std::uint64_t steps_ = 0;
  bool stepped_ = false; // lastStep() has a step to report

  // One allocation holds everything; the pointers below point into it.
  void* arena_ = nullptr;
  std::size_t arenaBytes_ = 0;
  StepBuffers<Real> buffers_{};
  void* temp_ = nullptr;
  std::size_t tempBytes_ = 0;
  double* statisticsPartials_ = nullptr;
  double* statisticsResult_ = nullptr;

  Graph graphs_[2]; // by roles_.x
};

template <class Real>
std::size_t CudaStepper<Real>::particleBytes(bool masks)
{
  return 4 * sizeof(Vec3<Real>) + 4 * sizeof(Real) + sizeof(std::int64_t) + 2 * sizeof(CellKey) +
    (masks ? kNeighborRows * sizeof(std::uint32_t) : 0);
}

template <class Real>
CudaStepper<Real>::CudaStepper(
  const Parameters& parameters, const ParticleBatch& initial, const Options& options)
  : parameters_(parameters)
  , options_(options)
{
  parameters_.validate();
  checkBatch(parameters_, initial);
  validateOptions(options_);
  std::string why;
  if (!cudaDevicePresent(&why))
  {
    throw std::runtime_error("CUDA backend unavailable: " + why);
  }
  check(cudaGetDevice(&device_), "cudaGetDevice");
  cudaDeviceProp properties{};
  check(cudaGetDeviceProperties(&properties, device_), "cudaGetDeviceProperties");
  deviceName_ = properties.name;

  constants_ = makeStepConstants<Real>(
    parameters_, options_.skin, options_.search == NeighborSearch::RowMasks);

  lattice_ = calibrateLattice(parameters_);

  check(cudaStreamCreate(&stream_), "cudaStreamCreate");
  try
  {
    check(cudaMalloc(&deviceTime_, sizeof(StepTime<Real>)), "cudaMalloc");
    constants_.time = deviceTime_;
    setTimeStep(parameters_.timeStep);
    allocate(std::max<std::size_t>(initial.position.size(), 1024), initial.position.size());
    append(initial);
  }
  catch (...)
  {
    release();
    cudaFree(deviceTime_);
    cudaStreamDestroy(stream_);
    throw;
  }
}

template <class Real>
CudaStepper<Real>::~CudaStepper()
{
  cudaSetDevice(device_);
  cudaStreamSynchronize(stream_);
  release();
  cudaFree(deviceTime_);
  cudaFree(solids_);
  cudaStreamDestroy(stream_);
}

template <class Real>
void CudaStepper<Real>::setTimeStep(double dt)
{
  checkTimeStep(dt);
  selectDevice();
  const StepTime<Real> time = StepTime<Real>::make(parameters_, lattice_, dt);
  // Ordered before the next step on the stream; from pageable memory the copy is staged before
  // the call returns, so `time` may go.
  check(cudaMemcpyAsync(deviceTime_, &time, sizeof time, cudaMemcpyHostToDevice, stream_),
    "cudaMemcpyAsync (time step)");
  dt_ = dt;
}

template <class Real>
void CudaStepper<Real>::selectDevice() const
{
  check(cudaSetDevice(device_), "cudaSetDevice");
}

template <class Real>
void CudaStepper<Real>::releaseGraphs()
{
  for (Graph& g : graphs_)
  {
    if (g.exec)
    {
      cudaGraphExecDestroy(g.exec);
    }
    g = Graph{};
  }
}

template <class Real>
void CudaStepper<Real>::release()
{
  releaseGraphs();
  if (arena_)
  {
    cudaFree(arena_);
  }
  arena_ = nullptr;
  arenaBytes_ = 0;
  buffers_ = StepBuffers<Real>{};
  capacity_ = 0;
}

// Lays out every array in one allocation, after checking that it fits in the free memory.
template <class Real>
void CudaStepper<Real>::allocate(std::size_t capacity, std::size_t particles)
{
  if (capacity >= std::numeric_limits<std::uint32_t>::max())
  {
    throw InvalidInput("particle count = " + std::to_string(capacity) +
      ": more than 32-bit indices hold");
  }
  const StepConstants<Real>& k = constants_;
  const bool masks = k.schedule.enabled != 0;
  const std::size_t cells = static_cast<std::size_t>(k.cellCount) + 1;
  const std::size_t tempBytes =
    KernelExecutor::tempBytesFor(static_cast<std::uint32_t>(capacity), cells, k.keyBits);

  std::size_t offset = 0;
  auto place = [&offset](std::size_t bytes) {
    const std::size_t at = offset;
    offset += (bytes + 255) / 256 * 256;
    return at;
  };
  std::size_t vecAt[4];
  for (std::size_t& at : vecAt)
  {
    at = place(capacity * sizeof(Vec3<Real>));
  }
  const std::size_t densityAt = place(capacity * sizeof(Real));
  const std::size_t lambdaAt = place(capacity * sizeof(Real));
  const std::size_t volumeAt = place(capacity * sizeof(Real));
  const std::size_t omegaLengthAt = place(capacity * sizeof(Real));
  const std::size_t idAt = place(capacity * sizeof(std::int64_t));
  const std::size_t keysAt[2] = { place(capacity * sizeof(CellKey)),
    place(capacity * sizeof(CellKey)) };
  const std::size_t masksAt = place(masks ? kNeighborRows * capacity * sizeof(std::uint32_t) : 0);
  const std::size_t particleEnd = offset;
  const std::size_t offsetsAt = place(cells * sizeof(std::uint32_t));
  const std::size_t movedAt = place(static_cast<std::size_t>(k.iterations) * 8);
  const std::size_t buildsAt = place(8);
  const std::size_t adaptiveAt = place(sizeof(AdaptiveState));
  // Two per block: the sums, then the maxima.
  const std::size_t blockSumsAt =
    place(2 * ((capacity + kCompressionBlock - 1) / kCompressionBlock) * sizeof(double));
  const std::size_t partialsAt = place(kStatisticsBlocks * kStatisticsValues * sizeof(double));
  const std::size_t resultAt = place(kStatisticsValues * sizeof(double));
  const std::size_t tempAt = place(tempBytes);
  const std::size_t total = offset;

  std::size_t freeBytes = 0, totalBytes = 0;
  check(cudaMemGetInfo(&freeBytes, &totalBytes), "cudaMemGetInfo");
  // Head room for what the driver allocates beside us: the kernels' stacks, graphs, CUB's
  // per-launch state.
  const std::size_t reserve = std::size_t(128) << 20;
  auto mib = [](std::size_t bytes) { return std::to_string((bytes + (1u << 19)) >> 20); };
  const std::string need = "particle count = " + std::to_string(particles) + " (capacity " +
    std::to_string(capacity) + "): the CUDA backend needs " + mib(total) + " MiB of GPU memory (" +
    std::to_string(particleBytes(masks)) + " bytes per particle, " + mib(total - particleEnd) +
    " MiB for " + std::to_string(k.cellCount) + " grid cells and scratch) plus " + mib(reserve) +
    " MiB head room, but " + deviceName_ + " has " + mib(freeBytes) + " MiB free of " +
    mib(totalBytes) + " MiB; use fewer particles, a larger particleSpacing or a CPU backend";
  if (total + reserve > freeBytes)
  {
    throw InvalidInput(need);
  }
  void* arena = nullptr;
  const cudaError_t error = cudaMalloc(&arena, total);
  if (error == cudaErrorMemoryAllocation)
  {
    cudaGetLastError();
    throw InvalidInput(need + " (cudaMalloc failed)");
  }
  check(error, "cudaMalloc");

  arena_ = arena;
  arenaBytes_ = total;
  capacity_ = capacity;
  char* base = static_cast<char*>(arena);
  StepBuffers<Real>& b = buffers_;
  for (int i = 0; i < 4; ++i)
  {
    b.vec[i] = reinterpret_cast<Vec3<Real>*>(base + vecAt[i]);
  }
  b.density = reinterpret_cast<Real*>(base + densityAt);
  b.lambda = reinterpret_cast<Real*>(base + lambdaAt);
  b.volume = reinterpret_cast<Real*>(base + volumeAt);
  b.omegaLength = reinterpret_cast<Real*>(base + omegaLengthAt);
  b.id = reinterpret_cast<std::int64_t*>(base + idAt);
  b.keys[0] = reinterpret_cast<CellKey*>(base + keysAt[0]);
  b.keys[1] = reinterpret_cast<CellKey*>(base + keysAt[1]);
  b.masks = masks ? reinterpret_cast<std::uint32_t*>(base + masksAt) : nullptr;
  b.stride = static_cast<std::uint32_t>(capacity);
  b.cellOffsets = reinterpret_cast<std::uint32_t*>(base + offsetsAt);
  b.maxMoved = reinterpret_cast<unsigned long long*>(base + movedAt);
  b.maskBuilds = reinterpret_cast<unsigned long long*>(base + buildsAt);
  b.adaptive = reinterpret_cast<AdaptiveState*>(base + adaptiveAt);
  b.blockSums = reinterpret_cast<double*>(base + blockSumsAt);
  statisticsPartials_ = reinterpret_cast<double*>(base + partialsAt);
  statisticsResult_ = reinterpret_cast<double*>(base + resultAt);
  temp_ = base + tempAt;
  tempBytes_ = tempBytes;
  // Nothing reads memory before writing it, except the counter; zero it all the same so that a
  // stale value can never look like a result.
  check(cudaMemsetAsync(arena, 0, total, stream_), "cudaMemsetAsync");
}

template <class Real>
StepBuffers<Real> CudaStepper<Real>::buffers() const
{
  return buffers_;
}

template <class Real>
KernelExecutor CudaStepper<Real>::executor() const
{
  return KernelExecutor(stream_, temp_, tempBytes_, options_.block);
}

template <class Real>
void CudaStepper<Real>::evaluateAtRest()
{
  KernelExecutor exec = executor();
  enqueueEvaluateAtRest(
    exec, buffers_, constants_, static_cast<std::uint32_t>(n_), roles_, &sortedKeys_);
}

template <class Real>
void CudaStepper<Real>::captureGraphs()
{
  releaseGraphs();
  if (!options_.graphs || n_ == 0)
  {
    return;
  }
  // Both assignments of x and v, so that an odd number of solver iterations, which swaps them
  // every step, replays without capturing again.
  for (int x = 0; x < 2; ++x)
  {
    Roles roles;
    roles.x = x;
    roles.v = 1 - x;
    KernelExecutor exec = executor();
    cudaGraph_t graph = nullptr;
    check(cudaStreamBeginCapture(stream_, cudaStreamCaptureModeThreadLocal),
      "cudaStreamBeginCapture");
    Graph& g = graphs_[x];
    try
    {
      g.next = enqueueStep(
        exec, buffers_, constants_, static_cast<std::uint32_t>(n_), roles, &g.sortedKeys);
    }
    catch (...)
    {
      cudaStreamEndCapture(stream_, &graph);
      if (graph)
      {
        cudaGraphDestroy(graph);
      }
      throw;
    }
    check(cudaStreamEndCapture(stream_, &graph), "cudaStreamEndCapture");
    const cudaError_t error = cudaGraphInstantiate(&g.exec, graph, 0);
    cudaGraphDestroy(graph);
    check(error, "cudaGraphInstantiate");
  }
}

template <class Real>
void CudaStepper<Real>::step()
{
  if (n_ == 0)
  {
    return;
  }
  selectDevice();
  if (options_.graphs)
  {
    const Graph& g = graphs_[roles_.x];
    check(cudaGraphLaunch(g.exec, stream_), "cudaGraphLaunch");
    roles_ = g.next;
    sortedKeys_ = g.sortedKeys;
  }
  else
  {
    KernelExecutor exec = executor();
    roles_ = enqueueStep(
      exec, buffers_, constants_, static_cast<std::uint32_t>(n_), roles_, &sortedKeys_);
  }
  ++steps_;
  stepped_ = true;
  if (options_.faultAtStep != 0 && steps_ == options_.faultAtStep)
  {
    injectedFault<Real><<<1, 1, 0, stream_>>>();
  }
}

template <class Real>
void CudaStepper<Real>::restore(const std::vector<Vec3<Real>>& x,
  const std::vector<Vec3<Real>>& v, const std::vector<std::int64_t>& id)
{
  if (n_ == 0)
  {
    return;
  }
  check(cudaMemcpyAsync(buffers_.vec[roles_.x], x.data(), n_ * sizeof(Vec3<Real>),
          cudaMemcpyHostToDevice, stream_),
    "cudaMemcpyAsync");
  check(cudaMemcpyAsync(buffers_.vec[roles_.v], v.data(), n_ * sizeof(Vec3<Real>),
          cudaMemcpyHostToDevice, stream_),
    "cudaMemcpyAsync");
  check(cudaMemcpyAsync(buffers_.id, id.data(), n_ * sizeof(std::int64_t),
          cudaMemcpyHostToDevice, stream_),
    "cudaMemcpyAsync");
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
}

template <class Real>
void CudaStepper<Real>::append(const ParticleBatch& batch)
{
  checkBatch(parameters_, batch);
  selectDevice();
  const std::size_t added = batch.position.size();
  const std::size_t n = n_ + added;
  if (n >= std::numeric_limits<std::uint32_t>::max())
  {
    throw InvalidInput("particle count = " + std::to_string(n) + ": more than 32-bit indices hold");
  }
  if (n > capacity_)
  {
    // Grow by half again, so that emitters reallocate O(log N) times. x, v and id survive
    // through the host; everything else is recomputed from them.
    std::vector<Vec3<Real>> x(n_), v(n_);
    std::vector<std::int64_t> id(n_);
    if (n_ > 0)
    {
      check(cudaMemcpyAsync(x.data(), buffers_.vec[roles_.x], n_ * sizeof(Vec3<Real>),
              cudaMemcpyDeviceToHost, stream_),
        "cudaMemcpyAsync");
      check(cudaMemcpyAsync(v.data(), buffers_.vec[roles_.v], n_ * sizeof(Vec3<Real>),
              cudaMemcpyDeviceToHost, stream_),
        "cudaMemcpyAsync");
      check(cudaMemcpyAsync(id.data(), buffers_.id, n_ * sizeof(std::int64_t),
              cudaMemcpyDeviceToHost, stream_),
        "cudaMemcpyAsync");
    }
    check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
    const std::size_t oldCapacity = capacity_;
    const std::size_t capacity = std::max(n, capacity_ + capacity_ / 2);
    release();
    try
    {
      try
      {
        allocate(capacity, n);
      }
      catch (const InvalidInput&)
      {
        if (capacity == n)
        {
          throw;
        }
        allocate(n, n); // without the growth margin
      }
    }
    catch (const InvalidInput&)
    {
      // Keep the particles we had: the memory they used was just freed.
      allocate(oldCapacity, n_);
      roles_ = Roles{};
      restore(x, v, id);
      if (n_ > 0)
      {
        evaluateAtRest();
      }
      captureGraphs();
      check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
      throw;
    }
    roles_ = Roles{};
    restore(x, v, id);
  }
  if (added > 0)
  {
    std::vector<Vec3<Real>> x(added), v(added);
    for (std::size_t i = 0; i < added; ++i)
    {
      x[i] = Vec3<Real>::from(batch.position[i]);
      v[i] = Vec3<Real>::from(batch.velocity[i]);
    }
    check(cudaMemcpyAsync(buffers_.vec[roles_.x] + n_, x.data(), added * sizeof(Vec3<Real>),
            cudaMemcpyHostToDevice, stream_),
      "cudaMemcpyAsync");
    check(cudaMemcpyAsync(buffers_.vec[roles_.v] + n_, v.data(), added * sizeof(Vec3<Real>),
            cudaMemcpyHostToDevice, stream_),
      "cudaMemcpyAsync");
    check(cudaMemcpyAsync(buffers_.id + n_, batch.id.data(), added * sizeof(std::int64_t),
            cudaMemcpyHostToDevice, stream_),
      "cudaMemcpyAsync");
    // The host vectors die at the end of this scope: wait for the copies.
    check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
  }
  n_ = n;
  if (n_ > 0)
  {
    evaluateAtRest();
  }
  captureGraphs();
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
}

template <class Real>
void CudaStepper<Real>::synchronize() const
{
  selectDevice();
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
}

// Straight from the device into the caller's arrays: no host temporaries, no pass over the
// particles on the CPU (page-locked destinations are copied at the full bus speed).
template <class Real>
template <class Out>
void CudaStepper<Real>::copyInto(const SnapshotView<Out>& out) const
{
  if constexpr (!std::is_same<Out, Real>::value)
  {
    Stepper::readInto(out); // converts through read()
  }
  else
  {
    selectDevice();
    const std::size_t n = n_;
    const auto copy = [this, n](void* to, const void* from, std::size_t size) {
      if (to && n > 0)
      {
        check(cudaMemcpyAsync(to, from, n * size, cudaMemcpyDeviceToHost, stream_),
          "cudaMemcpyAsync");
      }
    };
    copy(out.position, buffers_.vec[roles_.x], sizeof(Vec3<Real>));
    copy(out.velocity, buffers_.vec[roles_.v], sizeof(Vec3<Real>));
    copy(out.density, buffers_.density, sizeof(Real));
    copy(out.lambda, buffers_.lambda, sizeof(Real));
    copy(out.id, buffers_.id, sizeof(std::int64_t));
    check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
  }
}

template <class Real>
template <class Out>
void CudaStepper<Real>::copyOut(Snapshot<Out>& out) const
{
  if constexpr (std::is_same<Out, Real>::value)
  {
    // Same precision (checkpoints): straight into the snapshot's vectors.
    out.position.resize(n_);
    out.velocity.resize(n_);
    out.density.resize(n_);
    out.lambda.resize(n_);
    out.id.resize(n_);
    copyInto(SnapshotView<Real>{ out.position.data(), out.velocity.data(), out.density.data(),
      out.lambda.data(), out.id.data() });
    return;
  }
  selectDevice();
  const std::size_t n = n_;
  std::vector<Vec3<Real>> x(n), v(n);
  std::vector<Real> density(n), lambda(n);
  out.id.resize(n);
  if (n > 0)
  {
    const auto copy = [this](void* to, const void* from, std::size_t bytes) {
      check(cudaMemcpyAsync(to, from, bytes, cudaMemcpyDeviceToHost, stream_), "cudaMemcpyAsync");
    };
    copy(x.data(), buffers_.vec[roles_.x], n * sizeof(Vec3<Real>));
    copy(v.data(), buffers_.vec[roles_.v], n * sizeof(Vec3<Real>));
    copy(density.data(), buffers_.density, n * sizeof(Real));
    copy(lambda.data(), buffers_.lambda, n * sizeof(Real));
    copy(out.id.data(), buffers_.id, n * sizeof(std::int64_t));
  }
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
  out.position.resize(n);
  out.velocity.resize(n);
  out.density.resize(n);
  out.lambda.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    out.position[i] = Vec3<Out>::from(x[i]);
    out.velocity[i] = Vec3<Out>::from(v[i]);
    out.density[i] = static_cast<Out>(density[i]);
    out.lambda[i] = static_cast<Out>(lambda[i]);
  }
}

template <class Real>
StepReport CudaStepper<Real>::lastStep() const
{
  StepReport report;
  if (!stepped_)
  {
    return report;
  }
  if (constants_.tolerance <= 0)
  {
    // Fixed mode computes no reduction inside a step, as on the CPU.
    report.iterations = constants_.iterations;
    report.densityError = std::numeric_limits<double>::quiet_NaN();
    return report;
  }
  selectDevice();
  AdaptiveState state{};
  check(cudaMemcpyAsync(&state, buffers_.adaptive, sizeof state, cudaMemcpyDeviceToHost, stream_),
    "cudaMemcpyAsync");
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
  report.iterations = state.iterations;
  report.densityError = state.densityError;
  return report;
}

// As CpuStepper::loadState: the snapshot's order is kept, and the next step predicts, re-sorts
// (stably, from this order) and recomputes everything else.
template <class Real>
template <class In>
void CudaStepper<Real>::loadState(const Snapshot<In>& state)
{
  if (sizeof(In) != sizeof(Real))
  {
    throw InvalidInput(std::string("checkpoint precision = ") +
      (sizeof(In) == sizeof(float) ? "single" : "double") + ": the stepper runs in " +
      toString(precision()) + " precision");
  }
  const std::size_t n = state.id.size();
  if (state.position.size() != n || state.velocity.size() != n || state.density.size() != n ||
    state.lambda.size() != n)
  {
    throw InvalidInput("checkpoint arrays differ in length (" + std::to_string(n) + " ids)");
  }
  selectDevice();
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
  if (n > capacity_)
  {
    n_ = 0; // the old state is gone either way; empty if the allocation throws
    release();
    allocate(n, n);
  }
  roles_ = Roles{};
  n_ = n;
  if (n > 0)
  {
    const auto upload = [this](void* to, const void* from, std::size_t bytes) {
      check(cudaMemcpyAsync(to, from, bytes, cudaMemcpyHostToDevice, stream_), "cudaMemcpyAsync");
    };
    // In is Real here (checked above), so the arrays go up as they are.
    upload(buffers_.vec[roles_.x], state.position.data(), n * sizeof(Vec3<Real>));
    upload(buffers_.vec[roles_.v], state.velocity.data(), n * sizeof(Vec3<Real>));
    upload(buffers_.density, state.density.data(), n * sizeof(Real));
    upload(buffers_.lambda, state.lambda.data(), n * sizeof(Real));
    upload(buffers_.id, state.id.data(), n * sizeof(std::int64_t));
  }
  captureGraphs();
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
}

template <class Real>
Diagnostics CudaStepper<Real>::diagnostics() const
{
  selectDevice();
  Diagnostics d;
  d.device = deviceName_;
  d.deviceBytes = arenaBytes_;
  d.capacity = capacity_;
  d.bytesPerParticle = static_cast<double>(particleBytes(constants_.schedule.enabled != 0));
  d.steps = steps_;
  unsigned long long builds = 0;
  if (buffers_.maskBuilds)
  {
    check(cudaMemcpyAsync(&builds, buffers_.maskBuilds, sizeof builds, cudaMemcpyDeviceToHost,
            stream_),
      "cudaMemcpyAsync");
    check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
  }
  d.maskBuilds = builds;
  return d;
}

} // namespace cuda
} // namespace pbf

namespace pbf
{
namespace cuda
{

// Instantiated in CudaStepperFloat.cu and CudaStepperDouble.cu, one precision per translation
// unit so that they compile in parallel.
template <class Real>
std::unique_ptr<CudaStepperInterface> makeCudaStepperOf(
  const Parameters& parameters, const ParticleBatch& initial, const Options& options)
{
  return std::make_unique<CudaStepper<Real>>(parameters, initial, options);
}

} // namespace cuda
} // namespace pbf

// The member functions on the reductions and on the solids.
#include "CudaStepperScans.cuh"
#include "CudaStepperSolids.cuh"
