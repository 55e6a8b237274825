// One rank's share of a domain-decomposed run with the particles kept on a GPU: the
// algorithm and the ghost protocol of distributed::SubdomainStepper (read that first), with the
// stages of StepSchedule.h and SubdomainSchedule.h. Written over a Device policy, so the same
// code runs on CUDA (CudaSubdomainStepper.cu) and, for the tests, on the host
// (Testing/Cuda/HostExecutor.h).
//
// A step, in the order the work is queued. The host waits for the device only before an
// exchange with the other ranks (whose bytes go device -> page-locked host memory ->
// Communicator -> device); the lists' lengths are checked at the first of those waits after the
// sort, not by a wait of their own:
//   1. predict; cut: column histograms of x and of the predicted positions x* (integer
//      atomics), one wait, one allGather of both, Slabs::balanced from x's; the slab borders go
//      up to the device. After the migration a rank holds every particle of its columns, so the
//      x* counts give, on the host and without another wait: the leavers per destination (this
//      rank's counts), the arrivals per sender (each rank's, from the allGather) and every ghost
//      message's length (the global counts). The device's own counts are copied back without a
//      wait and checked at the next one; a mismatch fails the step.
//   2. migrate by the predicted column: owner per particle; the leavers listed per destination
//      by stable selections, packed and copied out (a wait for that copy only: their holes are
//      filled by the kept particles beyond the kept count while the host exchanges them,
//      point-to-point, the lengths known), the arrivals copied in behind. (The CPU stepper
//      migrates by x and then again by x*; one migration by x* ends with the same owners.)
//   3. ghosts: the predicted positions (only: a ghost's id is never read) of this slab's first
//      and last columns go to the neighbours (one wait for their bytes, then the exchange with
//      the neighbours only, from and into page-locked memory where the Communicator exchanges
//      in place), and theirs are appended.
//   4. one stable radix sort by cell of owned + ghosts (StepSchedule's sortAndGather). Then the
//      lists, by selection over the sorted keys: what each neighbour mirrors (this slab's border
//      columns) and where its ghosts are (the columns beyond). Both sides list a border column in
//      the order (cell, sender's order before the sort), since the receiver appended the ghosts in
//      the order they were sent: the k-th value sent is the k-th ghost slot, with no index ever
//      exchanged.
//   5. the passes run over the owned particles, each as two launches: the border particles (the
//      columns a neighbour mirrors) first, whose fields are then packed and copied out, and the
//      interior ones while the host exchanges them; the upload and scatter into the ghost slots
//      are queued before the next pass. The refreshes' copies (down and up) run on the device
//      policy's copy stream (downloadAside, uploadAside), so the interior pass does not wait for
//      the border fields' copy to the host, and the neighbours' fields go up while it runs.
//      The border launches and the packing run on the policy's border stream (forkBorder,
//      joinBorder), beside the interior launch. The refreshes' messages go from and into the
//      page-locked staging directly where the Communicator exchanges in place (MPI; otherwise
//      they, and the ghosts' seeds, go through byte vectors). Density pass, refresh density+lambda (one
//      round); the fused correction, refresh positions (and velocities after the last one);
//      vorticity+XSPH, refresh omega; confinement; then the owned particles are gathered back,
//      in cell order.
//      Ghosts are not computed (nothing reads their own results; interior particles never read
//      ghosts, so the scatter cannot race the interior pass).
//
// Neighbour masks across ranks: rebuilt at every pass (see the constructor): a ghost moves by
// its owner's corrections, which a pass over the border cannot wait for.
//
// Adaptive iterations (densityErrorTolerance > 0) are not implemented here: the constructor
// throws InvalidInput naming the field.
#pragma once

#include "Distributed/Communicator.h"
#include "Distributed/RankFailure.h"
#include "Distributed/RankReductions.h"
#include "Distributed/Slabs.h"
#include "Distributed/SubdomainStepper.h"
#include "HostParticles.h"
#include "ParticleChecks.h"
#include "StepSchedule.h"
#include "SubdomainSchedule.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace pbf
{
namespace cuda
{

// Device policy (a class with):
//   using Exec; Exec executor();              StepSchedule's executor plus selectIf
//   void* allocate(bytes); void release(p);   device memory
//   download(host, device, bytes); upload(device, host, bytes); synchronize();
//   void* allocateHost(bytes); releaseHost(p); page-locked host memory
//   recordEvent(); waitEvent();              mark the queue, wait for the mark (one event)
//   Exec borderExecutor(); forkBorder(); joinBorder();  the border launches' queue: forked from
//                                             the compute queue, joined back into it
//   downloadAside(host, device, bytes);       device -> page-locked host after the queued work,
//                                             off the compute queue; marks the event at its end
//   uploadAside(device, host, bytes);         page-locked host -> device off the compute queue;
//                                             the compute work queued afterwards waits for it
//   reserveTemp(particles, cells, keyBits);   scratch of the sort, scan and selection
//   activate();                               make it current (cudaSetDevice)
//   std::string name() const;
template <class Real, class Device>
class DeviceSubdomainStepper final : public distributed::DecomposedStepper
{
public:
  DeviceSubdomainStepper(distributed::Communicator& communicator, const Parameters& parameters,
    const ParticleBatch& everything, std::unique_ptr<Device> device, double skin = 0.02,
    bool masks = true)
  try : communicator_(communicator)
    , parameters_(parameters)
    , device_(std::move(device))
  {
    parameters_.validate();
    checkBatch(parameters_, everything);
    constants_ = makeStepConstants<Real>(parameters_, skin, masks);
    lattice_ = calibrateLattice(parameters_);
    inPlace_ = communicator_.exchangesInPlace();
    // The masks are rebuilt at every pass: a ghost moves by its owner's corrections, which this
    // rank learns only with the positions, and a pass runs its border particles before the
    // interior ones have their max |delta p|. The single-GPU schedule rebuilds at every pass of
    // the dam break anyway at these sizes (pbf_bench: 5.00 builds per step of 4 iterations), so
    // the bound buys nothing here. A zero skin makes MaskSchedule::stillValid false at once.
    constants_.schedule.skin = 0.0;
    const auto ranks = static_cast<std::size_t>(communicator_.size());
    out_.resize(ranks);
    hostFirst_.resize(ranks + 1);
    hostCounts_.resize(
      2 * static_cast<std::size_t>(constants_.geometry.nx) * subdomain::kCounterCopies);
    ownerExpected_.resize(ranks + 1);
    in_.resize(ranks);
    inSizes_.resize(ranks);
    sendAt_.resize(ranks);
    sendSizes_.resize(ranks);
    receiveAt_.resize(ranks);
    device_->activate();
    allocateFixed();
    setTimeStep(parameters_.timeStep);
    // Every rank holds the whole initial fluid: the balanced cut follows from it on every rank
    // alike, so each keeps its share at once and nothing migrates (a cut from uniform slabs
    // would first gather most of a dam break on one rank and then move it: gigabytes at 64M).
    std::vector<std::uint64_t> perColumn(static_cast<std::size_t>(constants_.geometry.nx), 0);
    for (const Vec3d& q : everything.position)
    {
      ++perColumn[static_cast<std::size_t>(
        subdomain::columnOf(constants_.geometry, Vec3<Real>::from(q)))];
    }
    slabs_ = distributed::Slabs::balanced(perColumn, communicator_.size());
    uploadSlabs();
    append(everything);
  }
  catch (...)
  {
    // A rank that cannot hold its share (its device's memory, say) stops every rank.
    distributed::failTogether(communicator, std::current_exception());
  }

  ~DeviceSubdomainStepper() override
  {
    try
    {
      device_->activate();
      device_->synchronize();
    }
    catch (...)
    {
    }
    releaseParticles();
    for (void* p : fixed_)
    {
      device_->release(p);
    }
    for (HostBuffer* b : { &hostPack_, &hostRecv_ })
    {
      if (b->data)
      {
        device_->releaseHost(b->data);
      }
    }
    if (listCounts_)
    {
      device_->releaseHost(listCounts_);
    }
    if (setupCounts_)
    {
      device_->releaseHost(setupCounts_);
    }
  }

  DeviceSubdomainStepper(const DeviceSubdomainStepper&) = delete;
  DeviceSubdomainStepper& operator=(const DeviceSubdomainStepper&) = delete;

  // The public calls that the ranks make together fail together (distributed/RankFailure.h): a
  // device fault on one rank stops every rank with the same error.
  void step() override
  {
    distributed::together(communicator_, [&] { stepAlone(); });
  }
  void setTimeStep(double dt) override
  {
    distributed::together(communicator_, [&] { setTimeStepAlone(dt); });
  }
  void append(const ParticleBatch& batch) override
  {
    distributed::together(communicator_, [&] { appendAlone(batch); });
  }
  void read(Snapshot<float>& out) const override
  {
    distributed::together(communicator_, [&] { copyToSnapshot(hostState().view(), out); });
  }
  void read(Snapshot<double>& out) const override
  {
    distributed::together(communicator_, [&] { copyToSnapshot(hostState().view(), out); });
  }
  Statistics statistics() const override
  {
    return distributed::together(communicator_, [&] {
      const HostState s = hostState();
      return distributed::reduceStatistics(communicator_, parameters_, s.view());
    });
  }
  Health health() const override
  {
    return distributed::together(communicator_, [&] { return healthAlone(); });
  }
  void load(const Snapshot<float>& state) override
  {
    distributed::together(communicator_, [&] { loadState(state); });
  }
  void load(const Snapshot<double>& state) override
  {
    distributed::together(communicator_, [&] { loadState(state); });
  }

  void stepAlone()
  {
    device_->activate();
    const auto stepStart = Clock::now();
    exchange_ = distributed::ExchangeReport{};
    report_ = StepReport{};
    {
      // x, v and the predicted positions in the free buffer. The prediction does not depend on
      // the cut, so it runs first and the cut's one wait also brings back the predicted
      // positions' column counts, from which the migration's and the ghosts' counts follow.
      const int p = freeBuffer(x_, v_, -1);
      auto exec = device_->executor();
      subdomain::predict(exec, constants_, count(n_), vec_[x_], vec_[v_], vec_[p]);
      cut(x_, p);
      Roles4 r{ x_, p, v_, otherBuffer(x_, p, v_) };
      r = migrate(r);
      r = receiveGhosts(r);
      const CellKey* keys = sortByCell(r);
      exchange_.beforePassesMilliseconds = since(stepStart);
      // Now vec[r.x] = x, vec[r.p] = x*, vec[r.v] = v in cell order; vec[r.free] is free.
      solve(r, keys);
    }
    if (constants_.tolerance <= 0)
    {
      report_.iterations = constants_.iterations;
      report_.densityError = std::numeric_limits<double>::quiet_NaN();
    }
  }

  // Every rank sets the same dt (Simulation chooses it from reduced maxima).
  void setTimeStepAlone(double dt)
  {
    checkTimeStep(dt);
    device_->activate();
    const StepTime<Real> time = StepTime<Real>::make(parameters_, lattice_, dt);
    device_->upload(deviceTime_, &time, sizeof time);
    device_->synchronize(); // `time` dies here
    dt_ = dt;
  }
  double timeStep() const override { return dt_; }

  // Every rank passes the whole batch; each keeps the particles of its slab.
  void appendAlone(const ParticleBatch& batch)
  {
    checkBatch(parameters_, batch);
    device_->activate();
    std::vector<Vec3<Real>> x, v;
    std::vector<std::int64_t> id;
    const GridGeometry<Real>& g = constants_.geometry;
    for (std::size_t i = 0; i < batch.position.size(); ++i)
    {
      const Vec3<Real> q = Vec3<Real>::from(batch.position[i]);
      if (slabs_.owner(subdomain::columnOf(g, q)) == communicator_.rank())
      {
        x.push_back(q);
        v.push_back(Vec3<Real>::from(batch.velocity[i]));
        id.push_back(batch.id[i]);
      }
    }
    const std::size_t n = n_ + x.size();
    reserve(n, n_);
    if (!x.empty())
    {
      device_->upload(vec_[x_] + n_, x.data(), x.size() * sizeof(Vec3<Real>));
      device_->upload(vec_[v_] + n_, v.data(), v.size() * sizeof(Vec3<Real>));
      device_->upload(id_ + n_, id.data(), id.size() * sizeof(std::int64_t));
      device_->synchronize(); // the host vectors die here
    }
    n_ = n;
    cut(x_, -1); // evaluateAtRest predicts nothing: p = x
    evaluateAtRest();
  }

  std::size_t size() const override { return n_; }
  Backend backend() const override { return Backend::CUDA; }
  Precision precision() const override
  {
    return sizeof(Real) == sizeof(float) ? Precision::Single : Precision::Double;
  }
  std::string description() const override
  {
    const auto r = static_cast<std::size_t>(communicator_.rank());
    return "CUDA, " + device_->name() + ", rank " + std::to_string(r) + " of " +
      std::to_string(communicator_.size()) + " (grid columns " + std::to_string(slabs_.first[r]) +
      "-" + std::to_string(slabs_.first[r + 1] - 1) + " of " + std::to_string(slabs_.columns()) +
      " along x)";
  }

  // The divergence check's scan and the automatic step's fastest particle, every step: three
  // maxima over the owned particles on the device (largest speed^2, largest compression, any
  // non-finite value), 24 bytes back, then reduced over the ranks so that every rank reaches the
  // same verdict (distributed::reduceHealth's rule). nonFinite counts the ranks with one; outside
  // is 0: the collision step keeps finite positions in the box.
  Health healthAlone() const
  {
    device_->activate();
    auto exec = device_->executor();
    exec.fillZero(healthBits_, 3 * sizeof(unsigned long long));
    const std::uint32_t n = count(n_);
    const Vec3<Real>* x = vec_[x_];
    const Vec3<Real>* v = vec_[v_];
    const Real* density = density_;
    const double inverseRho0 = 1.0 / parameters_.restDensity;
    exec.forEachMax(GatherStage{}, n, healthBits_, [=] PBF_HD(std::uint32_t i) -> double {
      const Vec3<Real> vi = v[i];
      const double speed2 = double(vi.x) * vi.x + double(vi.y) * vi.y + double(vi.z) * vi.z;
      return speed2 < 1e300 ? speed2 : 0.0; // NaN and infinity are the third maximum's
    });
    exec.forEachMax(GatherStage{}, n, healthBits_ + 1, [=] PBF_HD(std::uint32_t i) -> double {
      const double e = double(density[i]) * inverseRho0 - 1.0;
      return e > 0.0 && e < 1e300 ? e : 0.0;
    });
    exec.forEachMax(GatherStage{}, n, healthBits_ + 2, [=] PBF_HD(std::uint32_t i) -> double {
      const Vec3<Real> xi = x[i], vi = v[i];
      const double sum = double(xi.x) + xi.y + xi.z + vi.x + vi.y + vi.z;
      return sum - sum == 0.0 ? 0.0 : 1.0; // finite exactly when sum - sum is 0
    });
    unsigned long long bits[3] = { 0, 0, 0 };
    device_->download(bits, healthBits_, sizeof bits);
    device_->synchronize();
    Health all;
    for (const std::vector<double>& r : distributed::allGather(communicator_,
           { MaskSchedule::bitsToDouble(bits[0]), MaskSchedule::bitsToDouble(bits[1]),
             MaskSchedule::bitsToDouble(bits[2]) }))
    {
      all.maxSpeed = std::max(all.maxSpeed, std::sqrt(r[0]));
      all.maxDensityError = std::max(all.maxDensityError, r[1]);
      all.nonFinite += r[2] > 0.0 ? 1 : 0;
    }
    return all;
  }
  StepReport lastStep() const override { return report_; }
  void synchronize() const override
  {
    device_->activate();
    device_->synchronize();
  }

  std::vector<std::uint64_t> particlesPerRank() const override
  {
    return distributed::countsPerRank(communicator_, n_);
  }
  const distributed::Slabs& slabs() const override { return slabs_; }
  const distributed::ExchangeReport& lastExchange() const override { return exchange_; }
  int rank() const override { return communicator_.rank(); }
  int ranks() const override { return communicator_.size(); }
  // Mask builds since construction (diagnostics).
  std::uint64_t maskBuilds() const
  {
    unsigned long long builds = 0;
    device_->activate();
    device_->download(&builds, maskBuilds_, sizeof builds);
    device_->synchronize();
    return builds;
  }

private:
  // Which of the four Vec3 buffers hold what during a step.
  struct Roles4
  {
    int x, p, v, free;
  };

  struct HostState
  {
    std::vector<Vec3<Real>> x, v;
    std::vector<Real> density, lambda;
    std::vector<std::int64_t> id;
    ConstHostParticles<Real> view() const { return { x, v, density, lambda, id }; }
  };

  using Clock = std::chrono::steady_clock;
  static double since(Clock::time_point start)
  {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  }
  static std::uint32_t count(std::size_t n) { return static_cast<std::uint32_t>(n); }
  static int otherBuffer(int a, int b, int c)
  {
    for (int i = 0; i < 4; ++i)
    {
      if (i != a && i != b && i != c)
      {
        return i;
      }
    }
    return -1;
  }
  static int freeBuffer(int a, int b, int c) { return otherBuffer(a, b, c); }

  subdomain::SlabView slabView() const
  {
    return { slabFirst_, communicator_.size(), communicator_.rank() };
  }

  StepBuffers<Real> buffers() const
  {
    StepBuffers<Real> b{};
    for (int i = 0; i < 4; ++i)
    {
      b.vec[i] = vec_[i];
    }
    b.density = density_;
    b.lambda = lambda_;
    b.id = id_;
    b.keys[0] = keys_[0];
    b.keys[1] = keys_[1];
    b.masks = constants_.schedule.enabled ? masks_ : nullptr;
    b.stride = count(capacity_);
    b.cellOffsets = cellOffsets_;
    b.maxMoved = maxMoved_;
    b.maskBuilds = maskBuilds_;
    b.adaptive = nullptr;
    b.blockSums = nullptr;
    return b;
  }

  template <class T>
  T* allocateFixed(std::size_t n)
  {
    void* p = device_->allocate(std::max<std::size_t>(n, 1) * sizeof(T));
    fixed_.push_back(p);
    return static_cast<T*>(p);
  }

  void allocateFixed()
  {
    const auto ranks = static_cast<std::size_t>(communicator_.size());
    cellOffsets_ = allocateFixed<std::uint32_t>(std::size_t(constants_.cellCount) + 1);
    maxMoved_ = allocateFixed<unsigned long long>(
      static_cast<std::size_t>(std::max(constants_.iterations, 1)));
    maskBuilds_ = allocateFixed<unsigned long long>(1);
    borderMaskBuilds_ = allocateFixed<unsigned long long>(1);
    columnCounts_ = allocateFixed<std::uint32_t>(
      2 * static_cast<std::size_t>(constants_.geometry.nx) * subdomain::kCounterCopies);
    ownerCounts_ = allocateFixed<std::uint32_t>((ranks + 1) * subdomain::kCounterCopies);
    slabFirst_ = allocateFixed<int>(ranks + 1);
    selected_ = allocateFixed<std::uint32_t>(8);
    deviceTime_ = allocateFixed<StepTime<Real>>(1);
    constants_.time = deviceTime_;
    adaptive_ = allocateFixed<AdaptiveState>(1);
    healthBits_ = allocateFixed<unsigned long long>(3);
    listCounts_ = static_cast<std::uint32_t*>(device_->allocateHost(8 * sizeof(std::uint32_t)));
    // The owner counts' copies, then the ghosts sent to each side.
    setupCounts_ = static_cast<std::uint32_t*>(
      device_->allocateHost(((ranks + 1) * subdomain::kCounterCopies + 2) * sizeof(std::uint32_t)));
    auto exec = device_->executor();
    exec.fillZero(maskBuilds_, sizeof(unsigned long long));
    exec.fillZero(borderMaskBuilds_, sizeof(unsigned long long));
  }

  void releaseParticles()
  {
    for (void* p : particleArrays_)
    {
      device_->release(p);
    }
    particleArrays_.clear();
    if (pack_)
    {
      device_->release(pack_);
    }
    if (recv_)
    {
      device_->release(recv_);
    }
    pack_ = recv_ = nullptr;
    packBytes_ = recvBytes_ = 0;
  }

  // Grows the per-particle arrays to hold `needed` (by half again at least, so growth happens
  // O(log N) times), keeping the first `keep` entries of the four Vec3 buffers, density, lambda
  // and id. Never shrinks: once grown, steps allocate nothing.
  void reserve(std::size_t needed, std::size_t keep)
  {
    if (needed <= capacity_ && capacity_ > 0)
    {
      return;
    }
    if (needed >= std::numeric_limits<std::uint32_t>::max())
    {
      throw InvalidInput("particle count = " + std::to_string(needed) +
        ": more than 32-bit indices hold");
    }
    const std::size_t capacity = std::max({ needed, capacity_ + capacity_ / 2, std::size_t(1024) });
    std::vector<void*> arrays;
    auto make = [&](std::size_t bytesPerParticle) {
      void* p = device_->allocate(capacity * bytesPerParticle);
      arrays.push_back(p);
      return p;
    };
    Vec3<Real>* vec[4];
    for (auto& v : vec)
    {
      v = static_cast<Vec3<Real>*>(make(sizeof(Vec3<Real>)));
    }
    auto* density = static_cast<Real*>(make(sizeof(Real)));
    auto* lambda = static_cast<Real*>(make(sizeof(Real)));
    auto* densityAlt = static_cast<Real*>(make(sizeof(Real)));
    auto* lambdaAlt = static_cast<Real*>(make(sizeof(Real)));
    auto* id = static_cast<std::int64_t*>(make(sizeof(std::int64_t)));
    auto* idAlt = static_cast<std::int64_t*>(make(sizeof(std::int64_t)));
    auto* keys0 = static_cast<CellKey*>(make(sizeof(CellKey)));
    auto* keys1 = static_cast<CellKey*>(make(sizeof(CellKey)));
    auto* masks = static_cast<std::uint32_t*>(
      make(constants_.schedule.enabled ? kNeighborRows * sizeof(std::uint32_t) : 1));
    auto* sendList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
    auto* ghostList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
    auto* ownedList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
    auto* borderList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
    auto* interiorList = static_cast<std::uint32_t*>(make(sizeof(std::uint32_t)));
    // Adaptive mode's partial sums and maxima: two per block of 4096, a fraction of a byte per
    // particle (whole bytes here, to keep make() per particle).
    auto* blockSums = static_cast<double*>(make(1));
    device_->reserveTemp(count(capacity), std::size_t(constants_.cellCount) + 1, constants_.keyBits);
    auto exec = device_->executor();
    if (keep > 0)
    {
      for (int i = 0; i < 4; ++i)
      {
        exec.copy(vec[i], vec_[i], keep * sizeof(Vec3<Real>));
      }
      exec.copy(density, density_, keep * sizeof(Real));
      exec.copy(lambda, lambda_, keep * sizeof(Real));
      exec.copy(id, id_, keep * sizeof(std::int64_t));
    }
    device_->synchronize();
    for (void* p : particleArrays_)
    {
      device_->release(p);
    }
    particleArrays_ = arrays;
    for (int i = 0; i < 4; ++i)
    {
      vec_[i] = vec[i];
    }
    density_ = density;
    lambda_ = lambda;
    densityAlt_ = densityAlt;
    lambdaAlt_ = lambdaAlt;
    id_ = id;
    idAlt_ = idAlt;
    keys_[0] = keys0;
    keys_[1] = keys1;
    masks_ = masks;
    sendList_ = sendList;
    ghostList_ = ghostList;
    ownedList_ = ownedList;
    borderList_ = borderList;
    interiorList_ = interiorList;
    blockSums_ = blockSums;
    capacity_ = capacity;
  }

  // Page-locked host memory for the messages, so that the copies to and from the device run at
  // the bus's speed and asynchronously; grow-only.
  struct HostBuffer
  {
    unsigned char* data = nullptr;
    std::size_t size = 0;
  };
  unsigned char* hostBuffer(HostBuffer& b, std::size_t bytes)
  {
    if (bytes > b.size || !b.data)
    {
      const std::size_t size = std::max({ bytes, b.size + b.size / 2, std::size_t(4096) });
      device_->synchronize();
      if (b.data)
      {
        device_->releaseHost(b.data);
      }
      b.data = static_cast<unsigned char*>(device_->allocateHost(size));
      b.size = size;
    }
    return b.data;
  }

  // The incoming messages in_[from] (each from `skip` bytes on, `bytes` long) one after another
  // into page-locked memory and up to device memory at `to`, in one copy.
  void uploadMessages(unsigned char* to, const std::vector<std::pair<int, std::size_t>>& from,
    std::size_t skip = 0, bool aside = false)
  {
    std::size_t total = 0;
    for (const auto& [rank, bytes] : from)
    {
      total += bytes;
      (void)rank;
    }
    if (total == 0)
    {
      return;
    }
    unsigned char* staging = hostBuffer(hostRecv_, total);
    std::size_t at = 0;
    for (const auto& [rank, bytes] : from)
    {
      const distributed::Bytes& message = in_[static_cast<std::size_t>(rank)];
      std::memcpy(staging + at, message.data() + skip, bytes);
      at += bytes;
    }
    if (aside)
    {
      device_->uploadAside(to, staging, total);
    }
    else
    {
      device_->upload(to, staging, total);
    }
  }

  // Grow-only byte buffers for the messages.
  unsigned char* packBuffer(std::size_t bytes) { return growBytes(pack_, packBytes_, bytes); }
  unsigned char* recvBuffer(std::size_t bytes) { return growBytes(recv_, recvBytes_, bytes); }
  unsigned char* growBytes(unsigned char*& buffer, std::size_t& have, std::size_t bytes)
  {
    if (bytes > have || !buffer)
    {
      const std::size_t size = std::max({ bytes, have + have / 2, std::size_t(4096) });
      device_->synchronize();
      if (buffer)
      {
        device_->release(buffer);
      }
      buffer = static_cast<unsigned char*>(device_->allocate(size));
      have = size;
    }
    return buffer;
  }

  void uploadSlabs()
  {
    for (std::size_t r = 0; r < slabs_.first.size(); ++r)
    {
      hostFirst_[r] = slabs_.first[r];
    }
    device_->upload(slabFirst_, hostFirst_.data(), hostFirst_.size() * sizeof(int));
  }

  // 1. Slabs balanced from the global column counts of positions vec[from]. In the same wait and
  // allGather, the global column counts of the predicted positions vec[predicted] (-1: they are
  // vec[from], as before evaluateAtRest): after the migration a rank holds every particle of its
  // columns, so these give each rank's leavers per destination (its own counts) and every
  // ghost message's length (the global ones) without waiting for the device again.
  void cut(int from, int predicted)
  {
    const auto start = Clock::now();
    const auto nx = static_cast<std::size_t>(constants_.geometry.nx);
    const std::size_t histograms = predicted >= 0 ? 2 : 1;
    auto exec = device_->executor();
    const std::size_t copies = nx * subdomain::kCounterCopies; // one histogram's counters
    exec.fillZero(columnCounts_, histograms * copies * sizeof(std::uint32_t));
    subdomain::countColumns(exec, constants_.geometry, count(n_), vec_[from], columnCounts_);
    if (predicted >= 0)
    {
      subdomain::countColumns(
        exec, constants_.geometry, count(n_), vec_[predicted], columnCounts_ + copies);
    }
    device_->download(
      hostCounts_.data(), columnCounts_, histograms * copies * sizeof(std::uint32_t));
    device_->synchronize();
    std::vector<double>& mine = columnsMine_;
    mine.resize(2 * nx);
    predictedMine_.resize(nx);
    for (std::size_t c = 0; c < nx; ++c)
    {
      mine[c] = static_cast<double>(subdomain::sumOfCopies(hostCounts_.data(), c));
      predictedMine_[c] = subdomain::sumOfCopies(hostCounts_.data(), (histograms - 1) * nx + c);
      mine[nx + c] = static_cast<double>(predictedMine_[c]);
    }
    std::vector<std::uint64_t>& perColumn = columnsAll_;
    perColumn.assign(nx, 0);
    predictedAll_.assign(nx, 0);
    const std::vector<std::vector<double>> all = distributed::allGather(communicator_, mine);
    for (const std::vector<double>& r : all)
    {
      if (r.size() != 2 * nx)
      {
        throw std::logic_error("decomposed CUDA step: a rank's column counts have the wrong length");
      }
      for (std::size_t c = 0; c < nx; ++c)
      {
        perColumn[c] += static_cast<std::uint64_t>(r[c]);
        predictedAll_[c] += static_cast<std::uint64_t>(r[nx + c]);
      }
    }
    const distributed::Slabs balanced = distributed::Slabs::balanced(perColumn, communicator_.size());
    exchange_.cutMoved = balanced.first != slabs_.first;
    slabs_ = balanced;
    uploadSlabs();
    // How many particles each rank sends this one in the migration: its predicted positions in
    // this rank's columns (every rank's own counts came with the allGather).
    const int me = communicator_.rank();
    arrivingFrom_.assign(all.size(), 0);
    for (std::size_t c = 0; c < nx; ++c)
    {
      if (ownerOf(static_cast<int>(c)) != me)
      {
        continue;
      }
      for (std::size_t from = 0; from < all.size(); ++from)
      {
        if (static_cast<int>(from) != me)
        {
          arrivingFrom_[from] += static_cast<std::uint64_t>(all[from][nx + c]);
        }
      }
    }
    exchange_.migrationMilliseconds += since(start);
  }

  // The owner of a column as the device computes it (SlabView over the same borders).
  int ownerOf(int column) const
  {
    return subdomain::SlabView{ hostFirst_.data(), communicator_.size(), 0 }.owner(column);
  }
  // What rank s sends its left (right) neighbour as ghosts: the particles of its first (last)
  // column after the migration, i.e. all of that column's predicted positions when s owns it.
  std::uint32_t ghostsSentLeft(int s) const
  {
    const int c = hostFirst_[static_cast<std::size_t>(s)];
    return s > 0 ? columnHeldBy(c, s) : 0u;
  }
  std::uint32_t ghostsSentRight(int s) const
  {
    const int c = hostFirst_[static_cast<std::size_t>(s) + 1] - 1;
    return s < communicator_.size() - 1 ? columnHeldBy(c, s) : 0u;
  }
  std::uint32_t columnHeldBy(int c, int s) const
  {
    if (c < 0 || c >= constants_.geometry.nx || ownerOf(c) != s)
    {
      return 0u;
    }
    return count(predictedAll_[static_cast<std::size_t>(c)]);
  }

  // The counts the host derived against the device's own (page-locked, copied after the
  // kernels that counted them; called after a wait for the device that follows the copy):
  // the owner counts, in kCounterCopies copies each, or the ghosts sent to each side.
  void checkOwnerCounts(const std::uint32_t* expected)
  {
    const auto ranks = static_cast<std::size_t>(communicator_.size());
    for (std::size_t i = 0; i < ranks + 1; ++i)
    {
      failUnlessExpected(subdomain::sumOfCopies(setupCounts_, i), expected[i], i,
        "leavers to rank key");
    }
  }
  void checkGhostCounts(const std::uint32_t* expected)
  {
    const auto at =
      (static_cast<std::size_t>(communicator_.size()) + 1) * subdomain::kCounterCopies;
    for (std::size_t i = 0; i < 2; ++i)
    {
      failUnlessExpected(setupCounts_[at + i], expected[i], i, "ghosts sent to side");
    }
  }
  static void failUnlessExpected(
    std::uint32_t got, std::uint32_t expected, std::size_t i, const char* what)
  {
    if (got != expected)
    {
      throw std::logic_error(std::string("decomposed CUDA step: ") + what + " " +
        std::to_string(i) + " is " + std::to_string(got) + " on the device, expected " +
        std::to_string(expected) + " from the column counts");
    }
  }

  // 2. To the owners of the columns of vec[r.p]; the roles stay. The leavers are listed per
  // destination (stable selections), packed and copied out; the kept particles that sit behind
  // the first `stay` slots fill the leavers' holes, so only O(leavers) particles move on the
  // device; the arrivals are appended.
  Roles4 migrate(Roles4 r)
  {
    const auto start = Clock::now();
    const int me = communicator_.rank();
    const auto ranks = static_cast<std::size_t>(communicator_.size());
    const std::uint32_t n = count(n_);
    auto exec = device_->executor();
    exec.fillZero(ownerCounts_, (ranks + 1) * subdomain::kCounterCopies * sizeof(std::uint32_t));
    auto* order = reinterpret_cast<std::uint32_t*>(lambda_); // unused identity
    subdomain::ownerKeys(
      exec, constants_.geometry, slabView(), n, vec_[r.p], keys_[0], order, ownerCounts_);
    // The counts per destination from this rank's predicted column counts (the cut's); the
    // device's own come back without a wait and are checked at the wait below.
    std::vector<std::uint32_t>& owners = ownerExpected_;
    std::fill(owners.begin(), owners.end(), 0u);
    for (std::size_t c = 0; c < predictedMine_.size(); ++c)
    {
      const int o = ownerOf(static_cast<int>(c));
      owners[o == me ? 0 : static_cast<std::size_t>(o) + 1] += predictedMine_[c];
    }
    device_->download(
      setupCounts_, ownerCounts_, (ranks + 1) * subdomain::kCounterCopies * sizeof(std::uint32_t));
    if (owners[0] > n)
    {
      throw std::logic_error("decomposed CUDA step: more particles stay than there are");
    }
    const std::uint32_t stay = owners[0];
    const std::uint32_t leaving = n - stay;
    using Record = subdomain::Migrant<Real>;
    auto* packed = reinterpret_cast<Record*>(packBuffer(std::size_t(leaving) * sizeof(Record)));
    unsigned char* staging = hostBuffer(hostPack_, std::size_t(leaving) * sizeof(Record));
    if (leaving > 0)
    {
      // ownedList_ and sendList_/ghostList_ are free until the cell sort.
      std::uint32_t offset = 0;
      for (std::size_t to = 0; to < ranks; ++to)
      {
        const std::uint32_t c = owners[to + 1];
        if (c > 0)
        {
          subdomain::selectKey<Real>(exec, n, keys_[0], static_cast<CellKey>(to + 1),
            ownedList_ + offset, selected_ + 2);
          offset += c;
        }
      }
      subdomain::packMigrants(
        exec, leaving, ownedList_, vec_[r.x], vec_[r.p], vec_[r.v], id_, packed);
      device_->download(staging, packed, std::size_t(leaving) * sizeof(Record));
    }
    // The exchange needs the leavers' bytes (and the counts) only: the holes are filled while
    // the host exchanges them.
    device_->recordEvent();
    if (leaving > 0)
    {
      subdomain::selectHolesAndMovers<Real>(exec, n, stay, keys_[0], sendList_, ghostList_, selected_);
      const std::uint32_t most = std::min(stay, leaving);
      subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, vec_[r.x]);
      subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, vec_[r.p]);
      subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, vec_[r.v]);
      subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, id_);
    }
    device_->waitEvent();
    checkOwnerCounts(owners.data());
    std::size_t offset = 0;
    for (std::size_t to = 0; to < ranks; ++to)
    {
      out_[to].clear();
      if (static_cast<int>(to) == me)
      {
        continue;
      }
      const std::size_t bytes = std::size_t(owners[to + 1]) * sizeof(Record);
      out_[to].assign(staging + offset, staging + offset + bytes);
      offset += bytes;
    }
    // Every rank knows what each sends it (the cut's counts): point-to-point with the ranks
    // that send or receive, no collective over all ranks.
    for (std::size_t from = 0; from < ranks; ++from)
    {
      inSizes_[from] = std::size_t(arrivingFrom_[from]) * sizeof(Record);
    }
    communicator_.exchangeKnownSizes(out_, in_, inSizes_);
    for (std::size_t from = 0; from < ranks; ++from)
    {
      if (in_[from].size() != std::size_t(arrivingFrom_[from]) * sizeof(Record))
      {
        throw std::logic_error("migration from rank " + std::to_string(from) + ": " +
          std::to_string(in_[from].size()) + " bytes, expected " +
          std::to_string(std::size_t(arrivingFrom_[from]) * sizeof(Record)));
      }
    }
    std::size_t arrivingBytes = 0;
    std::vector<std::pair<int, std::size_t>>& from = messages_;
    from.clear();
    for (std::size_t r = 0; r < in_.size(); ++r)
    {
      arrivingBytes += in_[r].size();
      from.emplace_back(static_cast<int>(r), in_[r].size());
    }
    const std::size_t arriving = arrivingBytes / sizeof(Record);
    reserve(stay + arriving, stay);
    unsigned char* recv = recvBuffer(arrivingBytes);
    uploadMessages(recv, from);
    exec = device_->executor();
    subdomain::unpackMigrants(exec, stay, count(arriving),
      reinterpret_cast<const Record*>(recv), vec_[r.x], vec_[r.p], vec_[r.v], id_);
    n_ = stay + arriving;
    exchange_.migrated += arriving;
    exchange_.migrationMilliseconds += since(start);
    return r;
  }

  // 3. The border particles (by vec[r.p]) to the neighbours; theirs appended as ghosts.
  Roles4 receiveGhosts(Roles4 r)
  {
    const auto start = Clock::now();
    const int me = communicator_.rank();
    const int last = communicator_.size() - 1;
    const std::uint32_t n = count(n_);
    auto exec = device_->executor();
    const GridGeometry<Real>& g = constants_.geometry;
    // No column is -1 or nx: a side without a neighbour selects nothing.
    const int leftColumn = me > 0 ? slabs_.first[static_cast<std::size_t>(me)] : -1;
    const int rightColumn = me < last ? slabs_.first[static_cast<std::size_t>(me) + 1] - 1 : -1;
    subdomain::selectColumn(exec, g, n, vec_[r.p], leftColumn, sendList_, selected_);
    subdomain::selectColumn(exec, g, n, vec_[r.p], rightColumn, ghostList_, selected_ + 1);
    // Every message's length from the global predicted column counts (the cut's): no wait for
    // the device's counts, which come back with the seeds and are checked then.
    const std::size_t ranks = static_cast<std::size_t>(communicator_.size());
    sendLeft_ = ghostsSentLeft(me);
    sendRight_ = ghostsSentRight(me);
    ghostLeft_ = me > 0 ? ghostsSentRight(me - 1) : 0u;
    ghostRight_ = me < last ? ghostsSentLeft(me + 1) : 0u;
    const std::uint32_t sent[2] = { sendLeft_, sendRight_ };
    device_->download(
      setupCounts_ + (ranks + 1) * subdomain::kCounterCopies, selected_, 2 * sizeof(std::uint32_t));
    if (sendLeft_ > n || sendRight_ > n) // one column may go both ways (a slab one column wide)
    {
      throw std::logic_error("decomposed CUDA step: more ghosts to send than particles");
    }
    using Seed = subdomain::GhostSeed<Real>;
    auto* packed = reinterpret_cast<Seed*>(packBuffer((sendLeft_ + sendRight_) * sizeof(Seed)));
    subdomain::packSeeds(exec, sendLeft_, sendList_, vec_[r.p], packed);
    subdomain::packSeeds(exec, sendRight_, ghostList_, vec_[r.p], packed + sendLeft_);
    const std::size_t sendBytes = (sendLeft_ + sendRight_) * sizeof(Seed);
    unsigned char* staging = hostBuffer(hostPack_, sendBytes);
    if (sendBytes > 0)
    {
      device_->download(staging, packed, sendBytes);
    }
    device_->synchronize();
    checkGhostCounts(sent);
    const std::uint32_t ghosts = ghostLeft_ + ghostRight_;
    reserve(std::size_t(n) + ghosts, n);
    unsigned char* recv = recvBuffer(ghosts * sizeof(Seed));
    if (inPlace_)
    {
      // From the page-locked seeds to the neighbours and from theirs into the page-locked
      // staging of the upload, no host copy (~1 ms of a 32M step on 4 GPUs went to copying the
      // seeds through byte vectors, the device idle). The synchronize above finished the last
      // upload from that staging (the migration's).
      unsigned char* landing = hostBuffer(hostRecv_, ghosts * sizeof(Seed));
      exchangeWithNeighborsInPlace(sendLeft_ * sizeof(Seed), sendRight_ * sizeof(Seed), landing,
        ghostLeft_ * sizeof(Seed), ghostRight_ * sizeof(Seed));
      if (ghosts > 0)
      {
        device_->upload(recv, landing, ghosts * sizeof(Seed));
      }
    }
    else
    {
      exchangeSeedsCopied(staging);
      uploadMessages(recv, messages_);
    }
    exec = device_->executor();
    subdomain::unpackSeeds(exec, n, ghosts, reinterpret_cast<const Seed*>(recv), vec_[r.x],
      vec_[r.p], vec_[r.v], id_);
    total_ = std::size_t(n) + ghosts;
    exchange_.ghosts = ghosts;
    exchange_.ghostMilliseconds += since(start);
    return r;
  }

  // receiveGhosts' exchange through the Communicator's byte vectors (a Communicator that does
  // not exchange in place, or the A/B switches): the seeds copied out of the page-locked staging
  // and the neighbours' listed in messages_ for uploadMessages.
  void exchangeSeedsCopied(const unsigned char* staging)
  {
    using Seed = subdomain::GhostSeed<Real>;
    const int me = communicator_.rank();
    const int last = communicator_.size() - 1;
    const std::size_t sendBytes = (sendLeft_ + sendRight_) * sizeof(Seed);
    for (auto& b : out_)
    {
      b.clear();
    }
    if (me > 0)
    {
      out_[static_cast<std::size_t>(me - 1)].assign(staging, staging + sendLeft_ * sizeof(Seed));
    }
    if (me < last)
    {
      out_[static_cast<std::size_t>(me + 1)].assign(
        staging + sendLeft_ * sizeof(Seed), staging + sendBytes);
    }
    // Both sides know the lengths: with the neighbours only, no collective over all ranks.
    std::fill(inSizes_.begin(), inSizes_.end(), std::size_t(0));
    if (me > 0)
    {
      inSizes_[static_cast<std::size_t>(me - 1)] = ghostLeft_ * sizeof(Seed);
    }
    if (me < last)
    {
      inSizes_[static_cast<std::size_t>(me + 1)] = ghostRight_ * sizeof(Seed);
    }
    communicator_.exchangeKnownSizes(out_, in_, inSizes_);
    for (std::size_t from = 0; from < in_.size(); ++from)
    {
      const bool left = static_cast<int>(from) == me - 1;
      const bool right = static_cast<int>(from) == me + 1;
      const std::size_t expected =
        (left ? ghostLeft_ : right ? ghostRight_ : 0u) * sizeof(Seed);
      if (in_[from].size() != expected)
      {
        throw std::logic_error("ghosts from rank " + std::to_string(from) + ": " +
          std::to_string(in_[from].size()) + " bytes, expected " + std::to_string(expected));
      }
    }
    messages_.clear();
    if (me > 0)
    {
      messages_.emplace_back(me - 1, ghostLeft_ * sizeof(Seed));
    }
    if (me < last)
    {
      messages_.emplace_back(me + 1, ghostRight_ * sizeof(Seed));
    }
  }

  // 4. The cell sort of owned + ghosts, and the lists. Returns the sorted keys; afterwards
  // vec[r.x] = x, vec[r.p] = x*, vec[r.v] = v (cell order), r updated.
  const CellKey* sortByCell(Roles4& r)
  {
    const std::uint32_t total = count(total_);
    auto exec = device_->executor();
    const StepBuffers<Real> b = buffers();
    subdomain::cellKeys(exec, constants_.geometry, total, vec_[r.p], keys_[0],
      reinterpret_cast<std::uint32_t*>(lambda_));
    // On entry A = x, B = v, C = p, D free; on exit D = x, A = p, C = v, B free.
    const CellKey* keys = detail::sortAndGather(
      exec, b, constants_, total, vec_[r.x], vec_[r.v], vec_[r.p], vec_[r.free]);
    r = Roles4{ r.free, r.x, r.p, r.v };

    const int me = communicator_.rank();
    const int last = communicator_.size() - 1;
    const int nx = constants_.geometry.nx;
    const int begin = slabs_.first[static_cast<std::size_t>(me)];
    const int end = slabs_.first[static_cast<std::size_t>(me) + 1];
    // Empty ranges where there is no neighbour.
    const int sendL0 = me > 0 ? begin : 0, sendL1 = me > 0 ? begin + 1 : 0;
    const int sendR0 = me < last ? end - 1 : 0, sendR1 = me < last ? end : 0;
    const int ghostL0 = me > 0 ? begin - 1 : 0, ghostL1 = me > 0 ? begin : 0;
    const int ghostR0 = me < last ? end : 0, ghostR1 = me < last ? end + 1 : 0;
    subdomain::selectColumns<Real>(exec, nx, total, keys, sendL0, sendL1, sendList_, selected_);
    subdomain::selectColumns<Real>(
      exec, nx, total, keys, sendR0, sendR1, sendList_ + sendLeft_, selected_ + 1);
    subdomain::selectColumns<Real>(exec, nx, total, keys, ghostL0, ghostL1, ghostList_, selected_ + 2);
    subdomain::selectColumns<Real>(
      exec, nx, total, keys, ghostR0, ghostR1, ghostList_ + ghostLeft_, selected_ + 3);
    subdomain::selectColumns<Real>(exec, nx, total, keys, begin, end, ownedList_, selected_ + 4);
    subdomain::selectBorder<Real>(
      exec, nx, total, keys, begin, end, me > 0, me < last, true, borderList_, selected_ + 5);
    subdomain::selectBorder<Real>(
      exec, nx, total, keys, begin, end, me > 0, me < last, false, interiorList_, selected_ + 6);
    // The lengths are known already: the border is this slab's first column (with a left
    // neighbour) and its last (with a right one), the ones sent as ghosts, counted once where
    // they are the same column. The device's counts come back to page-locked memory without a
    // wait and are checked at the next one (checkLists): a protocol slip still fails the step,
    // instead of giving a wrong answer, without draining the device here.
    border_ = me > 0 && me < last && begin + 1 == end ? sendLeft_ : sendLeft_ + sendRight_;
    device_->download(listCounts_, selected_, 7 * sizeof(std::uint32_t));
    listsUnchecked_ = true;
    return keys;
  }

  // The lists' lengths from the device against the ones the step used (after a wait for the
  // device that follows sortByCell's copy of them).
  void checkLists()
  {
    if (!listsUnchecked_)
    {
      return;
    }
    listsUnchecked_ = false;
    const std::uint32_t expected[7] = { sendLeft_, sendRight_, ghostLeft_, ghostRight_, count(n_),
      border_, count(n_) - border_ };
    for (int i = 0; i < 7; ++i)
    {
      if (listCounts_[i] != expected[i])
      {
        throw std::logic_error("decomposed CUDA step: list " + std::to_string(i) + " has " +
          std::to_string(listCounts_[i]) + " particles, expected " + std::to_string(expected[i]));
      }
    }
  }

  // One ghost refresh in two halves around the interior pass. sendRefresh: fields a (and b) of
  // the send lists packed and on their way to page-locked memory, marked by an event.
  template <class T>
  void sendRefresh(T* a, T* b)
  {
    const std::size_t record = sizeof(T) * (b ? 2 : 1);
    const std::size_t sendBytes = (sendLeft_ + sendRight_) * record;
    unsigned char* pack = packBuffer(sendBytes);
    unsigned char* staging = hostBuffer(hostPack_, sendBytes);
    auto edge = device_->borderExecutor(); // behind the border launch it packs
    subdomain::packFields(edge, sendList_, sendLeft_, sendRight_, a, b, pack);
    // Off the compute queue: the interior pass queued next does not wait for this copy.
    device_->downloadAside(staging, pack, sendBytes);
  }

  // receiveRefresh: waits for the packed fields only (the interior pass queued behind them keeps
  // the device busy), exchanges them with the neighbours and queues their upload and scatter
  // into the ghost slots. The time from the packed fields' arrival to the queued scatter is the
  // ghost time: waiting for the neighbours' border particles included.
  template <class T>
  void receiveRefresh(T* a, T* b)
  {
    const int me = communicator_.rank();
    const int last = communicator_.size() - 1;
    const std::size_t record = sizeof(T) * (b ? 2 : 1);
    const std::size_t sendBytes = (sendLeft_ + sendRight_) * record;
    const auto waitStart = Clock::now();
    device_->waitEvent();
    const auto start = Clock::now();
    exchange_.deviceWaitMilliseconds +=
      std::chrono::duration<double, std::milli>(start - waitStart).count();
    checkLists(); // their copy was queued before the border fields'
    const std::size_t leftBytes = ghostLeft_ * record, rightBytes = ghostRight_ * record;
    unsigned char* recv = recvBuffer(leftBytes + rightBytes);
    if (inPlace_)
    {
      // Straight from the page-locked border fields to the neighbours and from theirs into the
      // page-locked staging of the upload: no host copy (the last upload from that staging was
      // queued on the copy stream before the download just waited for, so it is done).
      unsigned char* staging = hostBuffer(hostRecv_, leftBytes + rightBytes);
      const auto exchangeStart = Clock::now();
      exchangeWithNeighborsInPlace(sendLeft_ * record, sendRight_ * record, staging, leftBytes,
        rightBytes);
      exchange_.refreshWaitMilliseconds += since(exchangeStart);
      if (leftBytes + rightBytes > 0)
      {
        // Off the compute queue too: it overlaps the interior pass; the scatter waits for it.
        device_->uploadAside(recv, staging, leftBytes + rightBytes);
      }
    }
    else
    {
      exchangeCopied(record, sendBytes, recv);
    }
    auto exec = device_->executor();
    subdomain::scatterFields(exec, ghostList_, ghostLeft_, ghostRight_, recv, a, b);
    exchange_.ghostMilliseconds += since(start);
  }

  // The neighbours' messages from the page-locked hostPack_ (this rank's left message, then its
  // right one) straight into page-locked `receive` (the left neighbour's, then the right one's),
  // over a Communicator that exchanges in place: no host copy. Both sides know every length.
  void exchangeWithNeighborsInPlace(std::size_t sendLeftBytes, std::size_t sendRightBytes,
    unsigned char* receive, std::size_t leftBytes, std::size_t rightBytes)
  {
    const int me = communicator_.rank();
    const int last = communicator_.size() - 1;
    std::fill(sendSizes_.begin(), sendSizes_.end(), std::size_t(0));
    std::fill(inSizes_.begin(), inSizes_.end(), std::size_t(0));
    std::fill(sendAt_.begin(), sendAt_.end(), nullptr);
    std::fill(receiveAt_.begin(), receiveAt_.end(), nullptr);
    if (me > 0)
    {
      const auto left = static_cast<std::size_t>(me - 1);
      sendAt_[left] = hostPack_.data;
      sendSizes_[left] = sendLeftBytes;
      receiveAt_[left] = receive;
      inSizes_[left] = leftBytes;
    }
    if (me < last)
    {
      const auto right = static_cast<std::size_t>(me + 1);
      sendAt_[right] = hostPack_.data + sendLeftBytes;
      sendSizes_[right] = sendRightBytes;
      receiveAt_[right] = receive + leftBytes;
      inSizes_[right] = rightBytes;
    }
    communicator_.exchangeKnownSizesInPlace(sendAt_, sendSizes_, receiveAt_, inSizes_);
  }

  // receiveRefresh's exchange through the Communicator's byte vectors (a Communicator that does
  // not exchange in place): the messages copied out of and into the page-locked staging on the
  // host.
  void exchangeCopied(std::size_t record, std::size_t sendBytes, unsigned char* recv)
  {
    const int me = communicator_.rank();
    const int last = communicator_.size() - 1;
    const unsigned char* staging = hostPack_.data;
    for (auto& o : out_)
    {
      o.clear();
    }
    if (me > 0)
    {
      out_[static_cast<std::size_t>(me - 1)].assign(staging, staging + sendLeft_ * record);
    }
    if (me < last)
    {
      out_[static_cast<std::size_t>(me + 1)].assign(
        staging + sendLeft_ * record, staging + sendBytes);
    }
    // Both sides know the sizes: the ghost lists were agreed when the ghosts were sent.
    std::fill(inSizes_.begin(), inSizes_.end(), std::size_t(0));
    if (me > 0)
    {
      inSizes_[static_cast<std::size_t>(me - 1)] = ghostLeft_ * record;
    }
    if (me < last)
    {
      inSizes_[static_cast<std::size_t>(me + 1)] = ghostRight_ * record;
    }
    const auto exchangeStart = Clock::now();
    communicator_.exchangeKnownSizes(out_, in_, inSizes_);
    exchange_.refreshWaitMilliseconds += since(exchangeStart);
    messages_.clear();
    const auto expect = [&](int from, std::size_t bytes) {
      const distributed::Bytes& message = in_[static_cast<std::size_t>(from)];
      if (message.size() != bytes)
      {
        throw std::logic_error("ghost refresh from rank " + std::to_string(from) + ": " +
          std::to_string(message.size()) + " bytes, expected " + std::to_string(bytes));
      }
      messages_.emplace_back(from, bytes);
    };
    if (me > 0)
    {
      expect(me - 1, ghostLeft_ * record);
    }
    if (me < last)
    {
      expect(me + 1, ghostRight_ * record);
    }
    // Off the compute queue too: it overlaps the interior pass; the scatter waits for it.
    uploadMessages(recv, messages_, 0, true);
  }

  // 5. The passes over the owned particles, each one border first, its fields sent while the
  // interior runs, received before the next pass; then the owned particles back into cell
  // order. Ghosts are never computed: nothing reads a ghost's own result.
  void solve(Roles4 r, const CellKey* sortedKeys)
  {
    const std::uint32_t n = count(n_);
    const std::uint32_t border = border_;
    const std::uint32_t interior = n - border;
    const detail::ListedParticles onBorder{ borderList_ };
    const detail::ListedParticles onInterior{ interiorList_ };
    const StepConstants<Real>& k = constants_;
    const StepBuffers<Real> b = buffers();
    auto exec = device_->executor();
    Vec3<Real>* const x = vec_[r.x];
    Vec3<Real>* const v = vec_[r.v];
    Vec3<Real>* const positions[2] = { vec_[r.p], vec_[r.free] };
    exec.fillZero(maxMoved_, static_cast<std::size_t>(k.iterations) * sizeof(unsigned long long));
    // The border launches run on the device's border stream, beside the interior ones (the two
    // write disjoint particles; interior particles read no ghost); their mask builds are counted
    // apart, so that no counter is written by two launches at once.
    StepBuffers<Real> edgeBuffers = b;
    edgeBuffers.maskBuilds = borderMaskBuilds_;
    const StepBuffers<Real>& be = edgeBuffers;
    // Adaptive mode: the mean compression over every rank's owned particles after each density
    // pass, as SubdomainStepper::meanDensityError has it (per rank in fixed blocks, then the
    // ranks in order); after the first projection the loop ends once it is within the tolerance,
    // and the velocities are then updated from the positions reached.
    const bool adaptive = k.tolerance > 0;
    int performed = 0;
    bool converged = false;
    for (int iteration = 0; iteration < k.iterations; ++iteration)
    {
      const FluidView<Real, MaskedNeighbors<Real>> f =
        detail::iterationView(b, k, sortedKeys, x, v, positions, iteration);
      exec = device_->executor();
      auto edge = device_->borderExecutor();
      device_->forkBorder();
      detail::firstPassOnPositions(
        edge, DensityStage{}, be, k, border, f, iteration, false, detail::DensityPass{}, onBorder);
      sendRefresh<Real>(density_, lambda_);
      detail::firstPassOnPositions(exec, DensityStage{}, b, k, interior, f, iteration, false,
        detail::DensityPass{}, onInterior);
      device_->joinBorder();
      receiveRefresh<Real>(density_, lambda_);
      if (adaptive)
      {
        const Compression c = compression(n);
        report_.densityError = c.mean;
        if (iteration > 0 &&
          c.within(parameters_.densityErrorTolerance, parameters_.maxDensityErrorTolerance))
        {
          converged = true;
          break;
        }
      }
      const bool last = iteration + 1 == k.iterations;
      exec = device_->executor();
      device_->forkBorder();
      detail::correctionPass(edge, be, border, f, iteration, last, nullptr, onBorder);
      // The last correction also updates the velocities, which XSPH and vorticity read.
      sendRefresh<Vec3<Real>>(f.scratch, last ? v : nullptr);
      detail::correctionPass(exec, b, interior, f, iteration, last, nullptr, onInterior);
      device_->joinBorder();
      receiveRefresh<Vec3<Real>>(f.scratch, last ? v : nullptr);
      ++performed;
    }
    if (adaptive)
    {
      report_.iterations = performed;
    }
    if (converged)
    {
      // The last correction did not know it was the last: line 21 for the positions reached,
      // border particles first so that their velocities travel while the interior's are set.
      FluidView<Real, MaskedNeighbors<Real>> apply =
        detail::iterationView(b, k, sortedKeys, x, v, positions, performed);
      exec = device_->executor();
      auto edge = device_->borderExecutor();
      device_->forkBorder();
      subdomain::updateVelocities<Real>(edge, border, borderList_, apply);
      sendRefresh<Vec3<Real>>(v, nullptr);
      subdomain::updateVelocities<Real>(exec, interior, interiorList_, apply);
      device_->joinBorder();
      receiveRefresh<Vec3<Real>>(v, nullptr);
    }
    // The passes after the iterations read the positions the last projection wrote.
    StepConstants<Real> after = k;
    after.iterations = performed;
    const FluidView<Real, MaskedNeighbors<Real>> f =
      detail::afterIterationsView(b, after, sortedKeys, x, v, positions);
    exec = device_->executor();
    {
      auto edge = device_->borderExecutor();
      device_->forkBorder();
      detail::firstPassOnPositions(edge, VorticityStage{}, be, after, border, f, performed, false,
        detail::VorticityPass{}, onBorder);
    }
    sendRefresh<Vec3<Real>>(x, nullptr);
    detail::firstPassOnPositions(exec, VorticityStage{}, b, after, interior, f, performed, false,
      detail::VorticityPass{}, onInterior);
    device_->joinBorder();
    receiveRefresh<Vec3<Real>>(x, nullptr);
    exec = device_->executor();
    FluidView<Real, MaskedNeighbors<Real>> confine = f;
    confine.v = f.scratch;
    subdomain::confine<Real>(exec, n, ownedList_, confine);
    // Line 23 and the ghosts dropped: x = the corrected positions, v = f.scratch, owned only, into
    // the buffers that held v and omega.
    keepOwned(f.p, f.scratch, r.v, r.x);
  }

  // Adaptive mode: mean and max of max(rho_i / rho_0 - 1, 0) over every rank's owned particles
  // (collective). The owned densities are gathered into densityAlt_ (free until keepOwned) and
  // reduced there.
  Compression compression(std::uint32_t n)
  {
    auto exec = device_->executor();
    subdomain::gather<Real>(exec, n, ownedList_, density_, densityAlt_);
    // A negative tolerance: the state only reports, the loop here decides.
    exec.fillZero(adaptive_, sizeof(AdaptiveState));
    exec.reduceCompression(densityAlt_, n, adaptive_, blockSums_, constants_, -1.0);
    AdaptiveState state{};
    device_->download(&state, adaptive_, sizeof state);
    device_->synchronize();
    double total = 0.0, count = 0.0;
    Compression c;
    for (const std::vector<double>& r : distributed::allGather(
           communicator_, { state.densityError * double(n), double(n), state.maxDensityError }))
    {
      total += r[0];
      count += r[1];
      c.max = std::max(c.max, r[2]);
    }
    c.mean = count > 0 ? total / count : 0.0;
    return c;
  }

  // The owned particles (ownedList_) of positions and velocities into vec[toX], vec[toV], and
  // their density, lambda and id, in cell order.
  void keepOwned(const Vec3<Real>* x, const Vec3<Real>* v, int toX, int toV)
  {
    if (total_ == n_)
    {
      // No ghosts (one rank): the owned particles are all of them, in place.
      for (int i = 0; i < 4; ++i)
      {
        if (vec_[i] == x)
        {
          x_ = i;
        }
        if (vec_[i] == v)
        {
          v_ = i;
        }
      }
      return;
    }
    auto exec = device_->executor();
    const std::uint32_t n = count(n_);
    subdomain::gather<Real>(exec, n, ownedList_, x, vec_[toX]);
    subdomain::gather<Real>(exec, n, ownedList_, v, vec_[toV]);
    subdomain::gather<Real>(exec, n, ownedList_, density_, densityAlt_);
    subdomain::gather<Real>(exec, n, ownedList_, lambda_, lambdaAlt_);
    subdomain::gather<Real>(exec, n, ownedList_, id_, idAlt_);
    std::swap(density_, densityAlt_);
    std::swap(lambda_, lambdaAlt_);
    std::swap(id_, idAlt_);
    x_ = toX;
    v_ = toV;
  }

  // Density and lambda at the current positions, nothing moves (after particles are added), as
  // SubdomainStepper::evaluateAtRest: the ghosts' values are not refreshed, nothing reads them.
  void evaluateAtRest()
  {
    auto exec = device_->executor();
    const int p = freeBuffer(x_, v_, -1);
    exec.copy(vec_[p], vec_[x_], n_ * sizeof(Vec3<Real>));
    Roles4 r{ x_, p, v_, otherBuffer(x_, p, v_) };
    r = migrate(r);
    r = receiveGhosts(r);
    const CellKey* keys = sortByCell(r);
    exec = device_->executor();
    const StepBuffers<Real> b = buffers();
    FluidView<Real, MaskedNeighbors<Real>> f = detail::solverView(b, constants_, keys);
    f.p = vec_[r.p];
    detail::firstPassOnPositions(exec, DensityStage{}, b, constants_, count(n_), f, 0, false,
      detail::DensityPass{}, detail::ListedParticles{ ownedList_ });
    keepOwned(vec_[r.x], vec_[r.v], r.p, r.free);
    device_->synchronize();
    checkLists();
  }

  HostState hostState() const
  {
    device_->activate();
    HostState s;
    s.x.resize(n_);
    s.v.resize(n_);
    s.density.resize(n_);
    s.lambda.resize(n_);
    s.id.resize(n_);
    if (n_ > 0)
    {
      device_->download(s.x.data(), vec_[x_], n_ * sizeof(Vec3<Real>));
      device_->download(s.v.data(), vec_[v_], n_ * sizeof(Vec3<Real>));
      device_->download(s.density.data(), density_, n_ * sizeof(Real));
      device_->download(s.lambda.data(), lambda_, n_ * sizeof(Real));
      device_->download(s.id.data(), id_, n_ * sizeof(std::int64_t));
    }
    device_->synchronize();
    return s;
  }

  // This rank's particles as read() gave them; the next step cuts the slabs from them.
  template <class In>
  void loadState(const Snapshot<In>& state)
  {
    HostState s;
    loadFromSnapshot(state, HostParticles<Real>{ s.x, s.v, s.density, s.lambda, s.id });
    device_->activate();
    device_->synchronize();
    const std::size_t n = s.id.size();
    n_ = 0;
    reserve(n, 0);
    x_ = 0;
    v_ = 1;
    if (n > 0)
    {
      device_->upload(vec_[x_], s.x.data(), n * sizeof(Vec3<Real>));
      device_->upload(vec_[v_], s.v.data(), n * sizeof(Vec3<Real>));
      device_->upload(density_, s.density.data(), n * sizeof(Real));
      device_->upload(lambda_, s.lambda.data(), n * sizeof(Real));
      device_->upload(id_, s.id.data(), n * sizeof(std::int64_t));
    }
    device_->synchronize();
    n_ = n;
  }

  distributed::Communicator& communicator_;
  Parameters parameters_;
  std::unique_ptr<Device> device_;
  StepConstants<Real> constants_{};
  LatticeCalibration lattice_;
  double dt_ = 0;
  StepTime<Real>* deviceTime_ = nullptr; // constants_.time
  distributed::Slabs slabs_;

  // Per-particle device arrays (capacity_ each); owned particles in [0, n_) between steps, with
  // x in vec_[x_] and v in vec_[v_].
  std::vector<void*> particleArrays_;
  std::size_t capacity_ = 0;
  std::size_t n_ = 0;
  std::size_t total_ = 0; // owned + ghosts during a step
  int x_ = 0, v_ = 1;
  Vec3<Real>* vec_[4] = {};
  Real *density_ = nullptr, *lambda_ = nullptr, *densityAlt_ = nullptr, *lambdaAlt_ = nullptr;
  AdaptiveState* adaptive_ = nullptr; // adaptive mode: this rank's reduction
  unsigned long long* healthBits_ = nullptr; // health(): three maxima as double bits
  double* blockSums_ = nullptr;
  std::int64_t *id_ = nullptr, *idAlt_ = nullptr;
  CellKey* keys_[2] = {};
  std::uint32_t* masks_ = nullptr;
  std::uint32_t *sendList_ = nullptr, *ghostList_ = nullptr, *ownedList_ = nullptr;
  // The owned particles that a neighbour mirrors (this slab's border columns, each once) and the
  // others: a pass computes the border first and sends it while the interior is computed.
  std::uint32_t *borderList_ = nullptr, *interiorList_ = nullptr;
  std::uint32_t border_ = 0;

  // Fixed-size device arrays.
  std::vector<void*> fixed_;
  std::uint32_t* cellOffsets_ = nullptr;
  unsigned long long* maxMoved_ = nullptr;
  unsigned long long* maskBuilds_ = nullptr;
  unsigned long long* borderMaskBuilds_ = nullptr; // the border launches' (apart: concurrent)
  std::uint32_t* columnCounts_ = nullptr;
  std::uint32_t* ownerCounts_ = nullptr;
  int* slabFirst_ = nullptr;
  std::uint32_t* selected_ = nullptr;
  // The lists' lengths as the device counted them (page-locked, 8 entries), checked late.
  std::uint32_t* listCounts_ = nullptr;
  bool listsUnchecked_ = false;
  unsigned char *pack_ = nullptr, *recv_ = nullptr;
  std::size_t packBytes_ = 0, recvBytes_ = 0;

  // This step's list lengths: what goes to the left and right neighbours, ghosts from them.
  std::uint32_t sendLeft_ = 0, sendRight_ = 0, ghostLeft_ = 0, ghostRight_ = 0;

  // Host staging, kept between steps so that steps reuse it.
  std::vector<std::uint32_t> hostCounts_;
  std::vector<int> hostFirst_;
  HostBuffer hostPack_, hostRecv_;
  std::vector<distributed::Bytes> out_, in_;
  std::vector<std::pair<int, std::size_t>> messages_;
  std::vector<std::size_t> inSizes_;
  // The in-place refresh exchange's pointers and lengths (size() entries each).
  std::vector<const unsigned char*> sendAt_;
  std::vector<std::size_t> sendSizes_;
  std::vector<unsigned char*> receiveAt_;
  bool inPlace_ = false; // the Communicator exchanges in place
  std::vector<double> columnsMine_;       // the cut's column counts, this rank's and everyone's
  std::vector<std::uint64_t> columnsAll_;
  // The predicted positions' column counts, this rank's and everyone's (the cut's), and the
  // migration's counts per destination derived from them.
  std::vector<std::uint32_t> predictedMine_;
  std::vector<std::uint64_t> predictedAll_;
  std::vector<std::uint32_t> ownerExpected_;
  std::vector<std::uint64_t> arrivingFrom_; // the migration's particles from each rank
  // The device's own counts of the migration ([0, ranks]) and the ghosts sent ([ranks + 1,
  // ranks + 2]), page-locked, checked after the next wait.
  std::uint32_t* setupCounts_ = nullptr;

  StepReport report_;
  distributed::ExchangeReport exchange_;
};

} // namespace cuda
} // namespace pbf
