// One rank's share of a domain-decomposed run with the particles kept on a GPU: the
// algorithm and the ghost protocol of distributed::SubdomainStepper (read that first), with the
// stages of StepSchedule.h and SubdomainSchedule.h. Written over a Device policy, so the same
// code runs on CUDA (CudaDevicePolicy.cuh) and, for the tests, on the host
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
//      they, and the ghosts' seeds, go through byte vectors). Density pass, refresh
//      density+lambda (one round); the fused correction, refresh positions (and velocities after
//      the last one);
//      vorticity+XSPH, refresh omega (with surface tension the colour gradients too, then the
//      smoothed normals, refresh the normals); confinement; then the owned particles are
//      gathered back, in cell order. A scene of several liquids carries each particle's liquid
//      with its migrant record and its ghost's seed (it changes only by migration).
//      Ghosts are not computed (nothing reads their own results; interior particles never read
//      ghosts, so the scatter cannot race the interior pass).
//
// Neighbour masks across ranks: rebuilt at every pass (see the constructor): a ghost moves by
// its owner's corrections, which a pass over the border cannot wait for.
//
// Adaptive iterations (densityErrorTolerance > 0): after each density pass the ranks' mean and
// largest compression are reduced together (DeviceSubdomainSolve.h), so every rank ends the loop
// after the same projection.
#pragma once

#include "Communicator.h"
#include "Distributed/RankFailure.h"
#include "Distributed/RankReductions.h"
#include "Distributed/Slabs.h"
#include "Distributed/SubdomainStepper.h"
#include "DeviceHealth.h"
#include "DeviceParticleStore.h"
#include "FluidSource.h"
#include "HostParticles.h"
#include "Outflow.h"
#include "ParticleChecks.h"
#include "StepLoop.h"
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
  // Every rank is handed the whole batch (checked alike on every rank).
  DeviceSubdomainStepper(distributed::Communicator& communicator, const Parameters& parameters,
    const ParticleBatch& everything, std::unique_ptr<Device> device, double skin = 0.02,
    bool masks = true)
    : DeviceSubdomainStepper(communicator, parameters,
        BatchSource(checkedBatch(parameters, everything)), std::move(device), skin, masks)
  {
  }

  // Every rank counts the fluid's particles per grid column and keeps its own slab's
  // (FluidSource.h): no rank holds the whole fluid.
  DeviceSubdomainStepper(distributed::Communicator& communicator, const Parameters& parameters,
    const FluidSource& fluid, std::unique_ptr<Device> device, double skin = 0.02,
    bool masks = true);

  ~DeviceSubdomainStepper() override;

  static const ParticleBatch& checkedBatch(const Parameters& parameters, const ParticleBatch& batch)
  {
    checkBatch(parameters, batch);
    return batch;
  }

  DeviceSubdomainStepper(const DeviceSubdomainStepper&) = delete;
  DeviceSubdomainStepper& operator=(const DeviceSubdomainStepper&) = delete;

  // The public calls that the ranks make together fail together (distributed/RankFailure.h): a
  // device fault on one rank stops every rank with the same error.
  void step() override
  {
    distributed::together(communicator_, [&] { stepAlone(); });
  }
  void setTimeStep(double dt, double pressureElapsed = 0) override
  {
    distributed::together(communicator_, [&] { setTimeStepAlone(dt, pressureElapsed); });
  }
  // Collective: this rank's particles in the zones go; returns the count over every rank.
  std::size_t removeOutflow(const std::vector<Box>& zones) override;
  void append(const ParticleBatch& batch) override
  {
    distributed::together(communicator_, [&] { appendAlone(batch); });
  }
  void read(Snapshot<float>& out) const override
  {
    distributed::together(
      communicator_, [&] { copyToSnapshot(parameters_, hostState().view(), out); });
  }
  void read(Snapshot<double>& out) const override
  {
    distributed::together(
      communicator_, [&] { copyToSnapshot(parameters_, hostState().view(), out); });
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
  // Device memory this rank holds: the particle store and its scratch, the fixed arrays and the
  // message buffers (the solids' fields aside: small beside them).
  std::size_t deviceBytes() const override
  {
    return (store_ ? store_->bytes() : 0) + fixedBytes_ + packBytes_ + recvBytes_ +
      3 * borderCapacity_ * sizeof(std::uint32_t);
  }
  // The cells of the window this rank sorts its particles in (setWindow), and of the domain.
  std::uint32_t windowCells() const { return constants_.cellCount; }
  std::uint32_t domainCells() const { return columns_.cellCount(); }
  void load(const Snapshot<float>& state) override
  {
    distributed::together(communicator_, [&] { loadState(state); });
  }
  void load(const Snapshot<double>& state) override
  {
    distributed::together(communicator_, [&] { loadState(state); });
  }

  double timeStep() const override { return dt_; }

  std::size_t size() const override { return n_; }
  Backend backend() const override { return Backend::CUDA; }
  Precision precision() const override
  {
    return sizeof(Real) == sizeof(float) ? Precision::Single : Precision::Double;
  }
  // Collective (every rank gives the same solids): their grids, views and the boundary table go
  // up in one allocation, then density and lambda are evaluated again with them
  // (DeviceSubdomainSolids.h).
  void setObstacles(
    const std::vector<DistanceGrid>& obstacles, const std::vector<SolidPose>& poses = {}) override;
  void setObstaclePoses(const std::vector<SolidPose>& poses) override;

  std::string description() const override
  {
    const auto r = static_cast<std::size_t>(communicator_.rank());
    return "CUDA, " + device_->name() + ", rank " + std::to_string(r) + " of " +
      std::to_string(communicator_.size()) + " (grid columns " + std::to_string(slabs_.first[r]) +
      "-" + std::to_string(slabs_.first[r + 1] - 1) + " of " + std::to_string(slabs_.columns()) +
      " along x)";
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
  // What the public calls above run on each rank, inside distributed::together.
  // The divergence check's scan and the automatic step's fastest particle, every step: three
  // maxima over the owned particles on the device (largest speed^2, largest compression, any
  // non-finite value), 24 bytes back, then reduced over the ranks so that every rank reaches the
  // same verdict (distributed::reduceHealth's rule). nonFinite counts the ranks with one; outside
  // is 0: the collision step keeps finite positions in the box.
  Health healthAlone() const;

  void stepAlone()
  {
    device_->activate();
    exchange_ = distributed::ExchangeReport{};
    report_ = StepReport{};
    Loop loop(*this);
    runStep(loop, SolveRule::of(parameters_));
  }

  // Every rank sets the same dt (Simulation chooses it from reduced maxima).
  void setTimeStepAlone(double dt, double pressureElapsed);

  // Every rank passes the whole batch; each keeps the particles of its slab.
  void appendAlone(const ParticleBatch& batch);

  // The particles of this rank's slab, in the stepper's precision, each checked (checkParticle)
  // when `check`: a part of a fluid that no one checked whole.
  struct Owned
  {
    std::vector<Vec3<Real>> x, v;
    std::vector<std::int64_t> id;
    std::vector<std::uint8_t> liquid; // 0 for a fluid without liquids
  };
  Owned ownedOf(const FluidSource& fluid, bool check) const;

  // Uploads them behind the particles held, then cuts and evaluates density and lambda at rest.
  void appendOwned(Owned&& o);

  // Which of the four Vec3 buffers hold what during a step.
  struct Roles4
  {
    int x, p, v, free;
  };

  struct HostState
  {
    std::vector<Vec3<Real>> x, v;
    std::vector<Real> density, lambda, pressure;
    std::vector<std::int64_t> id;
    std::vector<std::uint8_t> liquid; // empty in a scene without liquids
    ConstHostParticles<Real> view() const
    {
      return { x, v, density, lambda, pressure, id, liquid };
    }
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
    b.pressure = pressure_;
    b.id = id_;
    b.liquid = liquid_;
    b.colour = colour_;
    b.normal = normal_;
    b.keys[0] = keys_[0];
    b.keys[1] = keys_[1];
    b.masks = constants_.schedule.enabled ? masks_ : nullptr;
    b.stride = count(capacity_);
    b.cellOffsets = cellOffsets_;
    b.maxMoved = maxMoved_;
    b.maskBuilds = maskBuilds_;
    b.adaptive = nullptr;
    b.blockSums = nullptr;
    b.wallWarps = WarpSums{ wallFlags_, wallValues_ };
    b.wallLoads = wallLoads_;
    b.wallBlockSums = wallBlockSums_;
    return b;
  }

  template <class T>
  T* allocateFixed(std::size_t n)
  {
    const std::size_t bytes = std::max<std::size_t>(n, 1) * sizeof(T);
    void* p = device_->allocate(bytes);
    fixed_.push_back(p);
    fixedBytes_ += bytes;
    return static_cast<T*>(p);
  }

  void allocateFixed(); // the arrays that do not grow with the particles

  void releaseParticles();

  // Grows the per-particle arrays to hold `needed` (DeviceParticleStore::reserve: by half again
  // where both arenas fit, else by a sixteenth, through the host where even that does not fit
  // beside the old), keeping the first `keep` entries of the four Vec3 buffers, density, lambda,
  // id and liquid. Never shrinks: once grown, steps allocate nothing.
  void reserve(std::size_t needed, std::size_t keep);
  // The window of the domain's columns this rank sorts its particles in: its slab's and its
  // ghosts' columns that hold a predicted position (predictedAll_), so that its cells are its
  // share of the domain's; cellOffsets_ grows to hold them.
  void setWindow();
  // Room for `count` entries in each of the border lists (their contents are not kept: every
  // use writes them first); the host knows every count before the device selects.
  void reserveBorderLists(std::size_t count);
  // The array pointers below from the store, after it grew or swapped its alternates.
  void adoptStore();

  // Page-locked host memory for the messages, so that the copies to and from the device run at
  // the bus's speed and asynchronously; grow-only.
  struct HostBuffer
  {
    unsigned char* data = nullptr;
    std::size_t size = 0;
  };
  unsigned char* hostBuffer(HostBuffer& b, std::size_t bytes);

  // The incoming messages in_[from] (each from `skip` bytes on, `bytes` long) one after another
  // into page-locked memory and up to device memory at `to`, in one copy.
  void uploadMessages(unsigned char* to, const std::vector<std::pair<int, std::size_t>>& from,
    std::size_t skip = 0, bool aside = false);

  // Grow-only byte buffers for the messages.
  unsigned char* packBuffer(std::size_t bytes) { return growBytes(pack_, packBytes_, bytes); }
  unsigned char* recvBuffer(std::size_t bytes) { return growBytes(recv_, recvBytes_, bytes); }
  unsigned char* growBytes(unsigned char*& buffer, std::size_t& have, std::size_t bytes);

  void uploadSlabs();

  // 1. Slabs balanced from the global column counts of positions vec[from]. In the same wait and
  // allGather, the global column counts of the predicted positions vec[predicted] (-1: they are
  // vec[from], as before evaluateAtRest): after the migration a rank holds every particle of its
  // columns, so these give each rank's leavers per destination (its own counts) and every
  // ghost message's length (the global ones) without waiting for the device again.
  void cut(int from, int predicted);

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
    if (c < 0 || c >= columns_.nx || ownerOf(c) != s)
    {
      return 0u;
    }
    return count(predictedAll_[static_cast<std::size_t>(c)]);
  }

  // The counts the host derived against the device's own (page-locked, copied after the
  // kernels that counted them; called after a wait for the device that follows the copy):
  // the owner counts, in kCounterCopies copies each, or the ghosts sent to each side.
  void checkOwnerCounts(const std::uint32_t* expected);
  void checkGhostCounts(const std::uint32_t* expected);
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
  Roles4 migrate(Roles4 r);
  // migrate's exchange: the leavers' records from the page-locked staging to each destination
  // (owners[to + 1] of them), the arrivals into in_ (their counts known from the cut).
  void exchangeMigrants(const unsigned char* staging, const std::uint32_t* owners);

  // 3. The border particles (by vec[r.p]) to the neighbours; theirs appended as ghosts, with
  // their liquids in a scene of several (Seed: GhostSeed or LiquidSeed).
  Roles4 receiveGhosts(Roles4 r)
  {
    return liquid_ ? receiveGhostsAs<subdomain::LiquidSeed<Real>>(r)
                   : receiveGhostsAs<subdomain::GhostSeed<Real>>(r);
  }
  template <class Seed>
  Roles4 receiveGhostsAs(Roles4 r);

  // receiveGhosts' exchange through the Communicator's byte vectors (a Communicator that does
  // not exchange in place, or the A/B switches): the seeds (`seed` bytes each) copied out of the
  // page-locked staging and the neighbours' listed in messages_ for uploadMessages.
  void exchangeSeedsCopied(const unsigned char* staging, std::size_t seed);

  // 4. The cell sort of owned + ghosts, and the lists. Returns the sorted keys; afterwards
  // vec[r.x] = x, vec[r.p] = x*, vec[r.v] = v (cell order), r updated.
  const CellKey* sortByCell(Roles4& r);

  // The lists' lengths from the device against the ones the step used (after a wait for the
  // device that follows sortByCell's copy of them).
  void checkLists();

  // One ghost refresh in two halves around the interior pass. sendRefresh: the fields of the
  // send lists packed and on their way to page-locked memory, marked by an event.
  template <class T>
  void sendRefresh(subdomain::RefreshFields<T> fields);

  // receiveRefresh: waits for the packed fields only (the interior pass queued behind them keeps
  // the device busy), exchanges them with the neighbours and queues their upload and scatter
  // into the ghost slots. The time from the packed fields' arrival to the queued scatter is the
  // ghost time: waiting for the neighbours' border particles included.
  template <class T>
  void receiveRefresh(subdomain::RefreshFields<T> fields);

  // The neighbours' messages from the page-locked hostPack_ (this rank's left message, then its
  // right one) straight into page-locked `receive` (the left neighbour's, then the right one's),
  // over a Communicator that exchanges in place: no host copy. Both sides know every length.
  void exchangeWithNeighborsInPlace(std::size_t sendLeftBytes, std::size_t sendRightBytes,
    unsigned char* receive, std::size_t leftBytes, std::size_t rightBytes);

  // receiveRefresh's exchange through the Communicator's byte vectors (a Communicator that does
  // not exchange in place): the messages copied out of and into the page-locked staging on the
  // host.
  void exchangeCopied(std::size_t record, std::size_t sendBytes, unsigned char* recv);

  // A step as StepLoop.h's Loop (DeviceSubdomainSolve.h): parts 1-4 above, then 5, the passes
  // over the owned particles, each one border first, its fields sent while the interior runs,
  // received before the next pass; then the owned particles back into cell order. Ghosts are
  // never computed: nothing reads a ghost's own result.
  class Loop;

  // Adaptive mode: mean and max of max(rho_i / rho_0 - 1, 0) over every rank's owned particles
  // (collective). The owned densities are gathered into densityAlt_ (free until keepOwned) and
  // reduced there.
  Compression compression(std::uint32_t n);

  // The owned particles (ownedList_) of positions and velocities into vec[toX], vec[toV], and
  // their density, lambda and id, in cell order.
  void keepOwned(const Vec3<Real>* x, const Vec3<Real>* v, int toX, int toV);

  // Density and lambda at the current positions, nothing moves (after particles are added), as
  // SubdomainStepper::evaluateAtRest: the ghosts' values are not refreshed, nothing reads them.
  void evaluateAtRest();

  HostState hostState() const;

  // This rank's particles as read() gave them; the next step cuts the slabs from them.
  template <class In>
  void loadState(const Snapshot<In>& state);

  distributed::Communicator& communicator_;
  Parameters parameters_;
  std::unique_ptr<Device> device_;
  StepConstants<Real> constants_{};
  // The domain's whole grid: its columns along x are the cut's, the owners' and the seeds'.
  // constants_.geometry is this rank's window of it (setWindow), where its particles are sorted.
  GridGeometry<Real> columns_{};
  std::size_t cellCapacity_ = 0; // cells cellOffsets_ has room for
  LatticeCalibration lattice_;
  double dt_ = 0;
  StepTime<Real>* deviceTime_ = nullptr; // constants_.time
  distributed::Slabs slabs_;

  // Per-particle device arrays (capacity_ each, in the store; the pointers below are its); owned
  // particles in [0, n_) between steps, with x in vec_[xBuffer_] and v in vec_[vBuffer_].
  std::unique_ptr<DeviceParticleStore<Real, Device>> store_;
  std::size_t capacity_ = 0;
  std::size_t n_ = 0;
  std::size_t total_ = 0; // owned + ghosts during a step
  int xBuffer_ = 0, vBuffer_ = 1;
  Vec3<Real>* vec_[4] = {};
  Real *density_ = nullptr, *lambda_ = nullptr, *densityAlt_ = nullptr, *lambdaAlt_ = nullptr;
  Real *pressure_ = nullptr, *pressureAlt_ = nullptr;
  AdaptiveState* adaptive_ = nullptr; // adaptive mode: this rank's reduction
  unsigned long long* healthBits_ = nullptr; // health(): kHealthWords (DeviceHealth.h)
  double* blockSums_ = nullptr;
  // With mirror walls: the correction's warps' sums of the walls' loads and the step's loads.
  std::uint32_t* wallFlags_ = nullptr;
  double* wallValues_ = nullptr;
  double* wallLoads_ = nullptr;
  double* wallBlockSums_ = nullptr;
  std::int64_t *id_ = nullptr, *idAlt_ = nullptr;
  // Each particle's liquid (null without liquids); the colour gradients and their smoothed
  // normals (null without surface tension).
  std::uint8_t *liquid_ = nullptr, *liquidAlt_ = nullptr;
  Vec3<Real> *colour_ = nullptr, *normal_ = nullptr;
  CellKey* keys_[2] = {};
  std::uint32_t* masks_ = nullptr;
  std::uint32_t *sendList_ = nullptr, *ghostList_ = nullptr, *ownedList_ = nullptr;
  // The lists of a few columns (sendList_, ghostList_, borderList_) in one allocation of their
  // own, borderCapacity_ entries each: 12 bytes a particle less than lists as long as the store.
  std::uint32_t* borderLists_ = nullptr;
  std::size_t borderCapacity_ = 0;
  // The owned particles that a neighbour mirrors (this slab's border columns, each once) and the
  // others: a pass computes the border first and sends it while the interior is computed.
  std::uint32_t *borderList_ = nullptr, *interiorList_ = nullptr;
  std::uint32_t border_ = 0;

  // Fixed-size device arrays.
  std::vector<void*> fixed_;
  std::size_t fixedBytes_ = 0;
  void* solids_ = nullptr; // constants_.obstacles and .boundary: views, table, nodes
  std::vector<DistanceGridView<Real>> solidViews_; // as sampled, for placeSolids
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

// The member functions of each part of the step, by concern.
#include "DeviceSubdomainSetup.h"
#include "DeviceSubdomainCut.h"
#include "DeviceSubdomainGhosts.h"
#include "DeviceSubdomainExchange.h"
#include "DeviceSubdomainMemory.h"
#include "DeviceSubdomainSolve.h"
#include "DeviceSubdomainSolids.h"
