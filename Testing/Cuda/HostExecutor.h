// Runs StepSchedule.h on the host, stage by stage, so that the CUDA backend's algorithm (buffer
// rotation, fused correction, neighbour masks and their rebuilds) can be checked against the
// serial backend on a machine without a GPU. Particles are visited forwards or backwards: a stage
// that read what another particle of the same stage writes would then give different results.
#pragma once

#include "Cuda/StatisticsScan.h"
#include "Cuda/StepSchedule.h"
#include "DeviceFault.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <cstring>
#include <functional>
#include <numeric>
#include <unordered_map>
#include <vector>

namespace pbf
{
namespace test
{

class HostExecutor
{
public:
  // conditionals: runIfChain may skip its bodies, as in a captured CUDA graph
  // (HostDevicePolicy::launch); without, every body runs and its stages return at once after
  // done, as on a CUDA stream.
  explicit HostExecutor(bool backwards, bool conditionals = false)
    : backwards_(backwards)
    , conditionals_(conditionals)
  {
  }

  template <class Stage, class F>
  void forEach(Stage, std::uint32_t n, F f)
  {
    for (std::uint32_t k = 0; k < n; ++k)
    {
      f(backwards_ ? n - 1 - k : k);
    }
  }

  template <class Stage, class F>
  void forEachMax(Stage, std::uint32_t n, unsigned long long* maxBits, F f)
  {
    for (std::uint32_t k = 0; k < n; ++k)
    {
      const unsigned long long bits = MaskSchedule::doubleToBits(f(backwards_ ? n - 1 - k : k));
      *maxBits = std::max(*maxBits, bits);
    }
  }

  template <class F>
  void forEachHealth(std::uint32_t n, unsigned long long* maxBits, std::uint32_t* counts, int, F f)
  {
    for (std::uint32_t k = 0; k < n; ++k)
    {
      const auto s = f(backwards_ ? n - 1 - k : k);
      for (int m = 0; m < 3; ++m)
      {
        maxBits[m] = std::max(maxBits[m], MaskSchedule::doubleToBits(s.maxima[m]));
      }
      ++counts[s.bin];
    }
  }

  // A stable sort, like CUB's radix sort; the results go to the alternate buffers.
  cuda::SortedPairs sortByKey(CellKey* keys, CellKey* keysAlt, std::uint32_t* values,
    std::uint32_t* valuesAlt, std::uint32_t n, int)
  {
    std::vector<std::uint32_t> index(n);
    std::iota(index.begin(), index.end(), 0u);
    std::stable_sort(index.begin(), index.end(),
      [keys](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
    for (std::uint32_t k = 0; k < n; ++k)
    {
      keysAlt[k] = keys[index[k]];
      valuesAlt[k] = values[index[k]];
    }
    return { keysAlt, valuesAlt };
  }

  void maxScan(std::uint32_t* data, std::size_t count)
  {
    for (std::size_t i = 1; i < count; ++i)
    {
      data[i] = std::max(data[i], data[i - 1]);
    }
  }

  // Adaptive mode's mean compression summed exactly as CpuStepper::meanDensityError sums it
  // (blocks of 4096 in order), so that the decisions match the serial backend bit for bit.
  // A captured step's conditions, as CUDA's conditional nodes: off until a reduction sets one,
  // and a body runs only when its condition is on (every launch makes them anew).
  using Branch = int;
  static Branch noBranch() { return -1; }
  Branch branch()
  {
    if (!conditionals_)
    {
      return noBranch();
    }
    branches_.push_back(0);
    return static_cast<Branch>(branches_.size() - 1);
  }
  // As nested conditional nodes: the first body whose condition is not set ends the chain.
  template <class Body>
  void runIfChain(const Branch* branches, int first, int end, Body&& body)
  {
    for (int k = first; k < end; ++k)
    {
      const Branch b = branches[k];
      if (b >= 0 && !branches_[static_cast<std::size_t>(b)])
      {
        return;
      }
      body(*this, k);
    }
  }

  template <class Real>
  void reduceCompression(const Real* density, const std::uint8_t* liquid, std::uint32_t n,
    cuda::AdaptiveState* state, double*, const cuda::StepConstants<Real>& k, double tolerance,
    Branch next = noBranch())
  {
    if (state->done)
    {
      return;
    }
    // Per liquid with several (the most compressed liquid's mean), as the kernels.
    const int liquids = liquid ? k.liquids : 1;
    double total[kMaxLiquids] = {}, count[kMaxLiquids] = {}, top = 0.0;
    for (std::uint32_t begin = 0; begin < n; begin += 4096)
    {
      double sum[kMaxLiquids] = {}, within[kMaxLiquids] = {};
      for (std::uint32_t i = begin; i < std::min(n, begin + 4096); ++i)
      {
        const double e = std::max(double(density[i]) * k.inverseRestDensity - 1.0, 0.0);
        const int l = liquids > 1 ? liquid[i] : 0;
        sum[l] += e;
        within[l] += 1.0;
        top = std::max(top, e);
      }
      for (int l = 0; l < liquids; ++l)
      {
        total[l] += sum[l];
        count[l] += within[l];
      }
    }
    state->densityError = 0.0;
    for (int l = 0; l < liquids; ++l)
    {
      const double mean = liquids > 1 ? (count[l] > 0 ? total[l] / count[l] : 0.0)
                                      : (n > 0 ? total[0] / double(n) : 0.0);
      state->densityError = std::max(state->densityError, mean);
      state->liquidSum[l] = total[l];
      state->liquidCount[l] = count[l];
    }
    state->maxDensityError = top;
    if (state->densityError <= tolerance && (k.maxTolerance <= 0 || top <= k.maxTolerance))
    {
      state->done = 1;
    }
    else
    {
      ++state->iterations;
    }
    if (next >= 0)
    {
      branches_[static_cast<std::size_t>(next)] = state->done ? 0 : 1;
    }
  }

  // The solids' loads summed as the kernels sum them (CudaRuntime.cuh's loadBlocksKernel): per
  // load, kLoadBlocks blocks of 256 lanes, each lane's particles in order, the lanes of a block
  // added in a tree, then the blocks' sums as 256 lanes in a tree.
  template <class F>
  void sumLoads(std::uint32_t n, int count, const cuda::AdaptiveState* state, double*,
    double* loads, F f)
  {
    if (state && state->done)
    {
      return;
    }
    constexpr std::size_t threads = 256;
    constexpr std::size_t blocks = cuda::kLoadBlocks;
    constexpr int values = cuda::kLoadValues;
    const auto tree = [](std::vector<double>& lanes) {
      for (std::size_t width = threads / 2; width > 0; width >>= 1)
      {
        for (std::size_t t = 0; t < width; ++t)
        {
          lanes[t] += lanes[t + width];
        }
      }
      return lanes[0];
    };
    for (int o = 0; o < count; ++o)
    {
      std::vector<double> acc(blocks * threads * values, 0.0);
      for (std::uint32_t i = 0; i < n; ++i)
      {
        f(i, o, &acc[(i % (blocks * threads)) * values]);
      }
      std::vector<double> blockSums(blocks * values);
      for (std::size_t b = 0; b < blocks; ++b)
      {
        for (int v = 0; v < values; ++v)
        {
          std::vector<double> lanes(threads);
          for (std::size_t t = 0; t < threads; ++t)
          {
            lanes[t] = acc[(b * threads + t) * values + v];
          }
          blockSums[b * values + v] = tree(lanes);
        }
      }
      for (int v = 0; v < values; ++v)
      {
        std::vector<double> lanes(threads, 0.0);
        for (std::size_t b = 0; b < blocks; ++b)
        {
          lanes[b % threads] += blockSums[b * values + v];
        }
        loads[o * values + v] += tree(lanes);
      }
    }
  }

  // As forEachMax, each warp of 32 particles' Part groups added as stageMaxSumKernel adds them
  // (lane l adds lane l + 16, then + 8, ...) to the warp's sums of the step.
  template <class Stage, class Part, class F>
  void forEachMaxSum(
    Stage, std::uint32_t n, unsigned long long* maxBits, Part, cuda::WarpSums sums, F f)
  {
    std::vector<Part> parts(n);
    for (std::uint32_t k = 0; k < n; ++k)
    {
      const std::uint32_t i = backwards_ ? n - 1 - k : k;
      *maxBits = std::max(*maxBits, MaskSchedule::doubleToBits(f(i, parts[i])));
    }
    constexpr int values = Part::kGroups * Part::kGroupValues;
    for (std::uint32_t w = 0; w * 32 < n; ++w)
    {
      const std::uint32_t end = std::min(n, w * 32 + 32);
      unsigned groups = 0;
      for (std::uint32_t i = w * 32; i < end; ++i)
      {
        groups |= parts[i].groups();
      }
      for (int g = 0; g < Part::kGroups; ++g)
      {
        if (!(groups & (1u << g)))
        {
          continue;
        }
        double lanes[32][Part::kGroupValues] = {};
        for (std::uint32_t i = w * 32; i < end; ++i)
        {
          parts[i].group(g, lanes[i - w * 32]);
        }
        for (int k = 0; k < Part::kGroupValues; ++k)
        {
          double tree[32];
          for (int l = 0; l < 32; ++l)
          {
            tree[l] = lanes[l][k];
          }
          for (int offset = 16; offset > 0; offset >>= 1)
          {
            for (int l = 0; l < offset; ++l)
            {
              tree[l] += tree[l + offset];
            }
          }
          double& sum = sums.values[static_cast<std::size_t>(w) * values + g * Part::kGroupValues + k];
          sum = sums.flags[w] & (1u << g) ? sum + tree[0] : tree[0];
        }
      }
      sums.flags[w] |= groups;
    }
  }

  template <class Pred>
  void selectIf(std::uint32_t n, Pred pred, std::uint32_t* out, std::uint32_t* count)
  {
    std::uint32_t selected = 0;
    for (std::uint32_t i = 0; i < n; ++i)
    {
      if (pred(i))
      {
        out[selected++] = i;
      }
    }
    *count = selected;
  }

  void fillZero(void* pointer, std::size_t bytes) { std::memset(pointer, 0, bytes); }
  void copy(void* destination, const void* source, std::size_t bytes)
  {
    std::memmove(destination, source, bytes);
  }

private:
  bool backwards_;
  bool conditionals_;
  std::vector<char> branches_;
};

// The Device policy of both GPU steppers (cuda::DeviceStepper, cuda::DeviceSubdomainStepper) on
// host memory: their steps run here stage by stage, with the transfers as plain copies.
class HostDevicePolicy
{
public:
  using Exec = HostExecutor;
  explicit HostDevicePolicy(bool backwards = false)
    : backwards_(backwards)
  {
  }
  HostExecutor executor() const { return HostExecutor(backwards_); }
  HostExecutor borderExecutor() const { return HostExecutor(backwards_); }
  void forkBorder() {}
  void joinBorder() {}
  // Device memory as a budget (setFreeMemory): what is allocated is no longer free.
  void* allocate(std::size_t bytes)
  {
    void* p = std::calloc(bytes > 0 ? bytes : 1, 1);
    sizes_[p] = bytes;
    allocated_ += bytes;
    return p;
  }
  void release(void* pointer)
  {
    const auto found = sizes_.find(pointer);
    if (found != sizes_.end())
    {
      allocated_ -= found->second;
      sizes_.erase(found);
    }
    std::free(pointer);
  }
  void* allocateHost(std::size_t bytes) { return std::malloc(bytes > 0 ? bytes : 1); }
  void releaseHost(void* pointer) { std::free(pointer); }
  void download(void* host, const void* device, std::size_t bytes) { std::memcpy(host, device, bytes); }
  void upload(void* device, const void* host, std::size_t bytes) { std::memcpy(device, host, bytes); }
  // A CUDA error surfaces at a synchronisation: the tests make the n-th one from now throw the
  // DeviceFault that CudaRuntime.cuh would (n = 0: the next).
  void synchronize()
  {
    if (faultIn_ >= 0 && faultIn_-- == 0)
    {
      throw DeviceFault("injected device fault (test): an illegal memory access", false);
    }
    ++synchronizations_;
  }
  void faultAtSynchronization(long n) { faultIn_ = n; }
  long synchronizations() const { return synchronizations_; }
  void recordEvent() {}
  void waitEvent() {}
  void downloadAside(void* host, const void* device, std::size_t bytes)
  {
    if (bytes > 0)
    {
      std::memcpy(host, device, bytes);
    }
  }
  void uploadAside(void* device, const void* host, std::size_t bytes)
  {
    if (bytes > 0)
    {
      std::memcpy(device, host, bytes);
    }
  }
  void reserveTemp(std::uint32_t, std::size_t, int) {}
  static std::size_t tempBytesFor(std::uint32_t, std::size_t, int) { return 0; }
  void activate() {}
  std::string name() const { return "host executor"; }

  void* allocateOrNull(std::size_t bytes) { return allocate(bytes); }
  // As much memory as a test says (64 GiB free unless told).
  void memoryInfo(std::size_t& freeBytes, std::size_t& totalBytes) const
  {
    freeBytes = freeBytes_ > allocated_ ? freeBytes_ - allocated_ : 0;
    totalBytes = freeBytes_;
  }
  // The device's whole memory (what memoryInfo calls free before anything is allocated).
  void setFreeMemory(std::size_t bytes) { freeBytes_ = bytes; }
  std::size_t allocatedBytes() const { return allocated_; }
  void* stream() const { return nullptr; }

  // A captured step keeps its closure, with the arguments of the capture, and launch runs it:
  // what a CUDA graph does with its kernels' arguments.
  struct Graph
  {
    std::function<void(HostExecutor&)> replay;
  };
  template <class Enqueue>
  void capture(Graph& g, Enqueue&& enqueue)
  {
    g.replay = std::forward<Enqueue>(enqueue);
    ++captures_;
  }
  void launch(const Graph& g)
  {
    HostExecutor exec(backwards_, true);
    g.replay(exec);
  }
  void destroy(Graph& g) { g.replay = nullptr; }
  long captures() const { return captures_; }

  static std::size_t statisticsPartialBytes() { return 0; }
  // The sums and maxima of CudaReductions.cuh's kernels, in particle order.
  template <class Real>
  void scanStatistics(const cuda::StatisticsScan<Real>& s, double*, double* result)
  {
    double acc[cuda::kStatisticsValues] = {};
    for (std::uint32_t i = 0; i < s.n; ++i)
    {
      const double error = std::max(double(s.density[i]) / s.restDensity - 1.0, 0.0);
      acc[cuda::kErrorSum] += error;
      acc[cuda::kErrorMax] = std::max(acc[cuda::kErrorMax], error);
      const Vec3d si = Vec3d::from(s.sorted[i]);
      forEachNeighbor(s.grid, i, [&](std::uint32_t j) {
        const Vec3d r = si - Vec3d::from(s.sorted[j]);
        acc[cuda::kNeighborSum] += (j != i && dot(r, r) < s.h2) ? 1.0 : 0.0;
      });
      const Vec3d xi = Vec3d::from(s.x[i]);
      const Vec3d vi = Vec3d::from(s.v[i]);
      const double speed2 = dot(vi, vi);
      const double mass = s.massOf(i);
      acc[cuda::kSpeedMax] = std::max(acc[cuda::kSpeedMax], std::sqrt(speed2));
      acc[cuda::kKinetic] += 0.5 * mass * speed2;
      acc[cuda::kMomentumX] += vi.x * mass;
      acc[cuda::kMomentumY] += vi.y * mass;
      acc[cuda::kMomentumZ] += vi.z * mass;
      if (!std::isfinite(xi.x + xi.y + xi.z + vi.x + vi.y + vi.z))
      {
        acc[cuda::kNonFinite] = 1.0;
      }
    }
    std::memcpy(result, acc, sizeof acc);
  }
  // Options::faultAtStep: the next synchronisation reports a device fault.
  void injectFault() { faultIn_ = 0; }

private:
  std::size_t freeBytes_ = std::size_t(64) << 30;
  std::size_t allocated_ = 0;
  std::unordered_map<void*, std::size_t> sizes_;
  long captures_ = 0;
  bool backwards_;
  long faultIn_ = -1;
  long synchronizations_ = 0;
};

// Takes two steps (the first waits more often: the first cut) and counts the synchronisations of
// the second; when `faulty`, the device then faults in the middle of the next step. Returns the
// synchronisations per step.
template <class Stepper>
long faultMidNextStep(Stepper& stepper, HostDevicePolicy& device, bool faulty)
{
  stepper.step();
  const long before = device.synchronizations();
  stepper.step();
  const long perStep = device.synchronizations() - before;
  if (faulty)
  {
    device.faultAtSynchronization(perStep / 2);
  }
  return perStep;
}

} // namespace test
} // namespace pbf
