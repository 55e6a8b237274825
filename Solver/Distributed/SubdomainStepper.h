// One rank's share of a domain-decomposed PBF run (issue 7), on the CPU: the particles of its slab
// (Slabs.h) plus ghosts, the particles of the one grid column beyond each border, refreshed from
// their owners before every pass that reads them: positions before each density pass, density and
// lambda before each correction pass, velocities before XSPH and vorticity, vorticities before
// the confinement. Owned particles run the very same Equations.h stages as CpuStepper, in the same
// order, so one rank is bit-identical to the serial backend and N ranks differ from it only by the
// order in which neighbours are summed.
//
// Ownership follows the predicted position: after the prediction each particle migrates to the
// rank that owns its column, so that every owned particle has its whole neighbourhood at hand for
// the step. When the particle counts drift more than rebalanceThreshold from the mean, the slabs
// are cut again on the global column counts.
#pragma once

#include "Communicator.h"
#include "Equations.h"
#include "Slabs.h"
#include "Stepper.h"

#include <cstdint>
#include <vector>

namespace pbf::distributed
{

// What this rank exchanged in its last step, and how long that took (wall clock).
struct ExchangeReport
{
  std::size_t ghosts = 0;      // ghost particles received at the start of the step
  std::size_t migrated = 0;    // particles received from other ranks (migration and rebalancing)
  double ghostMilliseconds = 0;
  double migrationMilliseconds = 0;
  bool rebalanced = false;
};

template <class Real>
class SubdomainStepper
{
public:
  // Collective. Every rank passes the whole initial fluid and keeps the particles of its slab;
  // the first cut balances the particle counts.
  SubdomainStepper(Communicator& communicator, bool parallel, const Parameters& parameters,
    const ParticleBatch& everything, double rebalanceThreshold = 0.2);

  void step(); // collective

  std::size_t size() const { return x_.size(); } // owned particles
  void read(Snapshot<double>& owned) const;
  // Collective: over every rank's particles, summed in rank order (the same bits on every rank).
  // averageNeighbors is not computed across ranks (NaN).
  Statistics statistics();
  // Collective: the owned particles of each rank.
  std::vector<std::uint64_t> particlesPerRank();

  const Slabs& slabs() const { return slabs_; }
  const ExchangeReport& lastExchange() const { return exchange_; }
  const StepReport& lastStep() const { return report_; }
  int rebalances() const { return rebalances_; }

private:
  template <class Stage>
  void forOwned(Stage&& stage);
  FluidView<Real> view();
  int column(const Vec3<Real>& q) const;
  void migrate(bool byPrediction);     // to the owners of their columns
  void receiveGhosts();                // border particles of the neighbours, appended
  void sortByCell();                   // owned and ghosts together, as CpuStepper sorts
  template <class Field>
  void refreshGhosts(Field field);     // field(i) of each ghost from its owner
  void dropGhosts();                   // back to owned only, in cell order
  void rebalanceIfNeeded();
  double meanDensityError();           // collective

  Communicator& communicator_;
  bool parallel_;
  Parameters parameters_;
  Coefficients<Real> coefficients_;
  GridGeometry<Real> geometry_;
  Slabs slabs_;
  double rebalanceThreshold_;
  int rebalances_ = 0;

  // Owned particles first; during a step ghosts are appended, then all are sorted by cell.
  std::vector<Vec3<Real>> x_, p_, v_, scratch_, omega_;
  std::vector<Real> density_, lambda_;
  std::vector<std::int64_t> id_;
  std::vector<CellKey> keys_;
  std::vector<std::uint8_t> ghost_;
  std::vector<std::int32_t> ghostFrom_;        // the rank a ghost mirrors; -1 for owned
  std::vector<std::uint32_t> tag_;            // index before the sort
  std::vector<std::uint32_t> owned_;          // sorted indices of owned particles
  std::vector<std::vector<std::uint32_t>> sendIndex_;  // per rank: sorted indices it mirrors
  std::vector<std::vector<std::uint32_t>> ghostIndex_; // per rank: sorted indices of its ghosts
  std::vector<std::uint32_t> cellOffsets_, order_, cursor_;

  StepReport report_;
  ExchangeReport exchange_;
};

} // namespace pbf::distributed
