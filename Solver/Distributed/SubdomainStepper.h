// One rank's share of a domain-decomposed PBF run, on the CPU: the particles of its slab
// (Slabs.h) plus ghosts, the particles of the one grid column beyond each border, refreshed from
// their owners before every pass that reads them: positions before each density pass, density and
// lambda before each correction pass, velocities before XSPH and vorticity, vorticities before
// the confinement. Owned particles run the very same Equations.h stages as CpuStepper, in the same
// order, so one rank is bit-identical to the serial backend and N ranks differ from it only by the
// order in which neighbours are summed.
//
// The slabs are cut again at the start of every step from the global particle count of each
// column, so they are a function of the state alone: a checkpoint restored on the same number of
// ranks continues bit-identically, and the balance never drifts (what it can be is limited only
// by whole columns). Ownership then follows the predicted position: after the prediction each
// particle migrates to the rank that owns its column, so that every owned particle has its whole
// neighbourhood at hand for the step.
//
// It is a Stepper, so Simulation (emitters, checkpoints, the divergence check) drives it as any
// other; statistics(), health(), append(), step() and the constructor are collective: every rank
// calls them in the same order. size(), read() and load() are of this rank's particles.
#pragma once

#include "Communicator.h"
#include "FluidSource.h"
#include "HostStepLoop.h"
#include "HostStepper.h"
#include "Slabs.h"
#include "Stepper.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pbf::distributed
{

// What this rank exchanged in its last step, and how long that took (wall clock).
struct ExchangeReport
{
  std::size_t ghosts = 0;      // ghost particles received at the start of the step
  std::size_t migrated = 0;    // particles received from other ranks (new cut and prediction)
  double ghostMilliseconds = 0;
  double migrationMilliseconds = 0; // the cut included
  bool cutMoved = false;       // the step began with a new cut
  // Diagnostics of the CUDA sub-domain stepper's ghost refreshes (0 elsewhere): the host's time
  // waiting for its own device's border fields, and inside the exchanges with the neighbours
  // (waiting for theirs; ~0 on the rank that paces the others).
  double deviceWaitMilliseconds = 0;
  double refreshWaitMilliseconds = 0;
  // The host's time from the start of the step to the passes (cut, prediction, migration,
  // ghosts, cell sort and lists queued; its waits for the device and the other ranks included).
  double beforePassesMilliseconds = 0;
};

// What the benchmark and the tests ask of one rank's stepper beyond Stepper, whichever backend
// runs it (SubdomainStepper here, cuda::DeviceSubdomainStepper on a GPU).
class DecomposedStepper : public Stepper
{
public:
  // Collective: the particles of each rank.
  virtual std::vector<std::uint64_t> particlesPerRank() const = 0;
  virtual const Slabs& slabs() const = 0;
  virtual const ExchangeReport& lastExchange() const = 0;
  virtual int rank() const = 0;
  virtual int ranks() const = 0;
  // Device memory this rank's stepper holds (0 on the CPU).
  virtual std::size_t deviceBytes() const { return 0; }
  // Host memory this rank's particle arrays hold (their capacities; 0 where they are on a device).
  virtual std::size_t hostBytes() const { return 0; }
};

template <class Real>
class SubdomainStepper final : public HostStepper<DecomposedStepper, Real>
{
public:
  // Every rank is handed the whole batch and keeps the particles of its slab.
  SubdomainStepper(Communicator& communicator, bool parallel, const Parameters& parameters,
    const ParticleBatch& everything);
  // Every rank counts the fluid per column and keeps its own slab (FluidSource.h).
  SubdomainStepper(Communicator& communicator, bool parallel, const Parameters& parameters,
    const FluidSource& fluid);

  void step() override;
  // Every rank passes the whole batch (Simulation emits the same on every rank).
  void append(const ParticleBatch& batch) override;

  // size() and read(): this rank's particles.
  std::string description() const override;
  // Over every rank's particles, summed in rank order (the same bits on every rank).
  // averageNeighbors is not computed across ranks (NaN).
  Statistics statistics() const override;
  Health health() const override;
  // This rank's particles as read() gave them, at a step where the ranks were as now. The next
  // step cuts the slabs from this state, as the run that took it did.
  void load(const Snapshot<float>& state) override
  {
    loadFromSnapshot(fluid_.parameters, state, fluid_.particles());
  }
  void load(const Snapshot<double>& state) override
  {
    loadFromSnapshot(fluid_.parameters, state, fluid_.particles());
  }
  // Collective: this rank's particles in the zones go; returns the count over every rank.
  std::size_t removeOutflow(const std::vector<Box>& zones) override;
  // Collective: every rank holds every solid (their fields are small beside the fluid), and
  // density and lambda are evaluated again with them, as CpuStepper does.
  void setObstacles(
    const std::vector<DistanceGrid>& obstacles, const std::vector<SolidPose>& poses = {}) override
  {
    fluid_.setObstacles(obstacles, poses);
    evaluateAtRest();
  }
  // Every rank places every solid alike: a pose is a function of the time alone.
  void setObstaclePoses(const std::vector<SolidPose>& poses) override { fluid_.setPoses(poses); }

  // Collective: the particles of each rank.
  std::vector<std::uint64_t> particlesPerRank() const override;
  const Slabs& slabs() const override { return slabs_; }
  const ExchangeReport& lastExchange() const override { return exchange_; }
  int rank() const override { return communicator_.rank(); }
  int ranks() const override { return communicator_.size(); }
  std::size_t hostBytes() const override;

private:
  void stepAlone();
  // The stages of a step that are this stepper's own (HostStepLoop.h).
  friend class HostStepLoop<Real, SubdomainStepper>;
  void predict();        // after a new cut, over the owned particles
  void findNeighbours(); // migration by x*, the ghosts, the sort of owned and ghosts
  template <class Stage>
  void forEach(Stage&& stage) { forOwned(stage); }
  void refresh(HostField field);
  std::size_t ownedCount() const { return owned_.size(); }
  template <class Stage>
  void forEachInBlocks(std::size_t block, Stage&& stage)
  {
    pbf::forEachInBlocks(parallel_, owned_.size(), block,
      [this](std::size_t k) { return owned_[k]; }, stage);
  }
  std::vector<double> sumOverRanks(const std::vector<double>& mine);
  template <class Stage>
  void forOwned(Stage&& stage);
  // Inline: the exchanges (SubdomainExchange.cpp) ask it of every particle.
  int column(const Vec3<Real>& q) const
  {
    return columns_.clampedCell(q.x, columns_.origin.x, columns_.nx);
  }
  // The particles of `fluid` in this rank's slab behind those held (each checked when `check`:
  // a part of a fluid that no one checked whole).
  void keepOwn(const FluidSource& fluid, bool check);
  // The memory plan: room for `count` particles in every per-particle array, made only where the
  // host has the bytes available (InvalidInput naming the count otherwise, the arrays as they
  // were); roomFor(n) before an append grows by at least a sixteenth, never to twice the share.
  void reserveParticles(std::size_t count);
  void roomFor(std::size_t n);
  // Room for a window of `columns` columns in the grid's cell arrays (sortByCell).
  void roomForCells(int columns);
  std::size_t bytesPerParticle() const;
  void cut();                          // balanced slabs from the global column counts
  void migrate(bool byPrediction);     // to the owners of their columns
  void receiveGhosts();                // border particles of the neighbours, appended
  void sortByCell();                   // owned and ghosts together, as CpuStepper sorts
  template <class Field>
  void refreshGhosts(Field field);     // field(i) of each ghost from its owner
  void dropGhosts();                   // back to owned only, in cell order
  void evaluateAtRest();               // density and lambda of the current positions
  Compression compression();           // collective

  using HostStepper<DecomposedStepper, Real>::parallel_;
  // Owned particles first; during a step ghosts are appended, then all are sorted by cell.
  using HostStepper<DecomposedStepper, Real>::fluid_;
  using HostStepper<DecomposedStepper, Real>::report_;
  Communicator& communicator_;
  Slabs slabs_;
  // The domain's whole grid: its columns along x are the cut's and the owners'. fluid_.geometry
  // is this rank's window of it (sortByCell): the columns of the particles it sorts.
  GridGeometry<Real> columns_;
  std::vector<std::int32_t> ghostFrom_;        // the rank a ghost mirrors; -1 for owned
  std::vector<std::uint32_t> tag_;            // index before the sort
  std::vector<std::uint32_t> owned_;          // sorted indices of owned particles
  std::vector<std::vector<std::uint32_t>> sendIndex_;  // per rank: sorted indices it mirrors
  std::vector<std::vector<std::uint32_t>> ghostIndex_; // per rank: sorted indices of its ghosts
  // Gather targets of the sort's index and ghost arrays, kept to avoid allocating every step.
  std::vector<std::uint32_t> gatherIndex_;
  std::vector<std::int32_t> gatherFrom_;

  ExchangeReport exchange_;
  std::size_t capacity_ = 0; // particles the arrays have room for (reserveParticles)
};

} // namespace pbf::distributed
