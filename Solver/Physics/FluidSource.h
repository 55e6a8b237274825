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
  using Keep = std::function<bool(const Vec3d&)>;
  using Visit = std::function<void(const Vec3d& x, const Vec3d& v, std::int64_t id,
    std::uint8_t liquid)>;

  virtual ~FluidSource() = default;
  // visit(x) for every particle's position, in the fluid's order.
  virtual void forEachPosition(const std::function<void(const Vec3d&)>& visit) const = 0;
  // visit(x, v, id, liquid) for the particles whose position keep(x) accepts, in the fluid's
  // order (liquid 0 where the fluid names none): a stepper stores its slab straight into its own
  // arrays, in its own precision, with no batch of doubles beside them.
  virtual void forEachWhere(const Keep& keep, const Visit& visit) const = 0;
  // Whether the particles carry liquids (ParticleBatch::liquid).
  virtual bool hasLiquids() const = 0;

  // The particles whose position keep(x) accepts, in the fluid's order, with their ids.
  ParticleBatch where(const Keep& keep) const
  {
    ParticleBatch part;
    const bool liquids = hasLiquids();
    forEachWhere(keep, [&](const Vec3d& x, const Vec3d& v, std::int64_t id, std::uint8_t liquid) {
      part.position.push_back(x);
      part.velocity.push_back(v);
      part.id.push_back(id);
      if (liquids)
      {
        part.liquid.push_back(liquid);
      }
    });
    return part;
  }
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

  void forEachWhere(const Keep& keep, const Visit& visit) const override
  {
    for (std::size_t i = 0; i < batch_.position.size(); ++i)
    {
      if (keep(batch_.position[i]))
      {
        visit(batch_.position[i], batch_.velocity[i], batch_.id[i],
          batch_.liquid.empty() ? std::uint8_t(0) : batch_.liquid[i]);
      }
    }
  }

  bool hasLiquids() const override { return !batch_.liquid.empty(); }

private:
  const ParticleBatch& batch_;
};

} // namespace pbf
