// The initial fluid of a decomposed run, handed over in parts. Every rank visits every particle's
// position once (to count the particles of each grid column, from which the ranks agree on a
// balanced cut without exchanging anything) and then keeps only its own slab's particles, with the
// ids that the whole fluid gives them. So no rank holds the whole fluid: a billion particles are
// 57 GB as one ParticleBatch, on every rank at once.
#pragma once

#include "Particles.h"

#include <functional>

namespace pbf
{

class FluidSource
{
public:
  virtual ~FluidSource() = default;
  // visit(x) for every particle's position, in the fluid's order.
  virtual void forEachPosition(const std::function<void(const Vec3d&)>& visit) const = 0;
  // The particles whose position keep(x) accepts, in the fluid's order, with their ids.
  virtual ParticleBatch where(const std::function<bool(const Vec3d&)>& keep) const = 0;
};

// A fluid held whole already (a test's batch, the points of an input): the parts are views of it.
// Its arrays are of one length (checkBatch).
class BatchSource final : public FluidSource
{
public:
  explicit BatchSource(const ParticleBatch& batch)
    : batch_(batch)
  {
  }

  void forEachPosition(const std::function<void(const Vec3d&)>& visit) const override
  {
    for (const Vec3d& x : batch_.position)
    {
      visit(x);
    }
  }

  ParticleBatch where(const std::function<bool(const Vec3d&)>& keep) const override
  {
    ParticleBatch part;
    for (std::size_t i = 0; i < batch_.position.size(); ++i)
    {
      if (!keep(batch_.position[i]))
      {
        continue;
      }
      part.position.push_back(batch_.position[i]);
      part.velocity.push_back(batch_.velocity[i]);
      part.id.push_back(batch_.id[i]);
      if (!batch_.liquid.empty())
      {
        part.liquid.push_back(batch_.liquid[i]);
      }
    }
    return part;
  }

private:
  const ParticleBatch& batch_;
};

} // namespace pbf
