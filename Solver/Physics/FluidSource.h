// The initial fluid of a decomposed run, handed over in parts, so that no rank holds the whole
// fluid (a billion particles are 57 GB as one ParticleBatch, on every rank at once). A part is
// either the whole fluid seen by every rank alike (a scene that every rank generates, a batch
// held whole) or, where the fluid comes in pieces (the points of a parallel pipeline's input),
// this rank's piece, allParts() then gathering what the parts found. From the counts of each grid
// column the ranks agree on a balanced cut, and each keeps only its own slab's particles, with
// the ids that the whole fluid gives them.
#pragma once

#include "Particles.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace pbf
{

class FluidSource
{
public:
  using Keep = std::function<bool(const Vec3d&)>;
  using Owner = std::function<int(const Vec3d&)>;
  using Visit = std::function<void(const Vec3d& x, const Vec3d& v, std::int64_t id,
    std::uint8_t liquid)>;

  virtual ~FluidSource() = default;
  // visit(x) for every position of this part, in the fluid's order.
  virtual void forEachPosition(const std::function<void(const Vec3d&)>& visit) const = 0;
  // visit(x, v, id, liquid) for the particles of this part whose position keep(x) accepts, in the
  // fluid's order (liquid 0 where the fluid names none).
  virtual void forEachWhere(const Keep& keep, const Visit& visit) const = 0;
  // Whether the particles carry liquids (ParticleBatch::liquid), the same on every rank.
  virtual bool hasLiquids() const = 0;
  // Every part's values, in the fluid's order of the parts: {mine} where this part is the whole
  // fluid; collective (one entry per rank) where the fluid comes in pieces.
  virtual std::vector<std::vector<double>> allParts(const std::vector<double>& mine) const
  {
    return { mine };
  }
  // visit(x, v, id, liquid) for the particles of the whole fluid whose owner(x) is `rank`, in the
  // fluid's order: a stepper stores its slab straight into its own arrays, in its own precision,
  // with no batch of doubles beside them. Collective where the fluid comes in pieces (each piece
  // sends its particles to their owners).
  virtual void forEachOwned(const Owner& owner, int rank, const Visit& visit) const
  {
    forEachWhere([&](const Vec3d& x) { return owner(x) == rank; }, visit);
  }

  // The sums over the parts of each part's values, in part order (the same bits on every rank).
  std::vector<double> sumOverParts(const std::vector<double>& mine) const
  {
    std::vector<double> sum(mine.size(), 0.0);
    for (const std::vector<double>& part : allParts(mine))
    {
      for (std::size_t k = 0; k < sum.size() && k < part.size(); ++k)
      {
        sum[k] += part[k];
      }
    }
    return sum;
  }

  // The whole fluid's particle count in each of `columns` grid columns, column(x) giving each
  // position's (counts below 2^53 are exact in a double).
  std::vector<std::uint64_t> countPerColumn(
    const std::function<std::size_t(const Vec3d&)>& column, std::size_t columns) const
  {
    std::vector<double> mine(columns, 0.0);
    forEachPosition([&](const Vec3d& x) { mine[column(x)] += 1.0; });
    const std::vector<double> sum = sumOverParts(mine);
    return std::vector<std::uint64_t>(sum.begin(), sum.end());
  }

  // How many particles of the whole fluid keep(x) accepts.
  std::uint64_t countWhere(const Keep& keep) const
  {
    double mine = 0.0;
    forEachPosition([&](const Vec3d& x) { mine += keep(x) ? 1.0 : 0.0; });
    return static_cast<std::uint64_t>(sumOverParts({ mine })[0]);
  }

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
