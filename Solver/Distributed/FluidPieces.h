// A fluid that comes in pieces, one per rank: the points of the filter's input under a parallel
// pipeline, where each rank's upstream delivers its piece and no rank sees the whole. The pieces
// in rank order are the fluid, and its order. Each rank counts its piece per column (the ranks
// add the counts up for the balanced cut) and sends each particle to the rank that owns it, so a
// rank holds its piece and its slab, never the whole.
#pragma once

#include "Communicator.h"
#include "FluidSource.h"

namespace pbf::distributed
{

class FluidPieces final : public FluidSource
{
public:
  // Collective. `piece` outlives this and carries the particles' ids in the whole fluid. A
  // message carries at most `perMessage` particles (MPI counts a message's bytes in an int: 16M
  // particles are 912 MB); more go in further rounds.
  FluidPieces(const ParticleBatch& piece, Communicator& communicator,
    std::size_t perMessage = std::size_t(1) << 24);

  void forEachPosition(const std::function<void(const Vec3d&)>& visit) const override;
  void forEachWhere(const Keep& keep, const Visit& visit) const override;
  bool hasLiquids() const override { return liquids_; }
  std::vector<std::vector<double>> allParts(const std::vector<double>& mine) const override;
  // Each piece's particles go to their owners in as few exchanges as the message size allows; a
  // rank visits what it receives in rank order, which is the fluid's order.
  void forEachOwned(const Owner& owner, int rank, const Visit& visit) const override;

private:
  const ParticleBatch& piece_;
  Communicator& communicator_;
  std::size_t perMessage_;
  bool liquids_ = false;
};

} // namespace pbf::distributed
