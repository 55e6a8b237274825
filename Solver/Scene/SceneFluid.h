// A scene's initial fluid, generated in parts (FluidSource.h): the lattice sites of its boxes and
// spheres in fillScene's order, less those inside its solids at t = 0, with the ids that
// outsideSolids gives the rest (0..N-1 in that order). A decomposed run's ranks each generate
// their own slab from it, so that no rank holds the whole fluid; fillScene and outsideSolids
// give the same particles whole. It refers to the caller's scene, which outlives it, and keeps its
// own copy of the solids' fields (small beside the fluid).
#pragma once

#include "FluidSource.h"
#include "Scene.h"
#include "SignedDistance.h"
#include "SolidMotion.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace pbf
{

class SceneFluid final : public FluidSource
{
public:
  // solids: the scene's distance fields at t = 0 placed by `poses` (empty: where they were
  // sampled), as Simulation removes the fluid seeded inside them. Counts the fluid once: one pass
  // over every site, nothing kept.
  SceneFluid(const Scene& scene, const Parameters& parameters,
    const std::vector<DistanceGrid>& solids = {}, const std::vector<SolidPose>& poses = {});

  void forEachPosition(const std::function<void(const Vec3d&)>& visit) const override;
  void forEachWhere(const Keep& keep, const Visit& visit) const override;
  bool hasLiquids() const override { return liquids_; }

  std::size_t size() const { return size_; }
  // Sites inside a solid, left out.
  std::size_t insideSolids() const { return insideSolids_; }

private:
  // site(x, v, liquid, id) for every site outside the solids, ids in order.
  void forEachKept(
    const std::function<void(const Vec3d&, const Vec3d&, std::uint8_t, std::int64_t)>& site) const;
  const Scene& scene_;
  double spacing_;
  bool liquids_;
  std::vector<DistanceGrid> solids_;
  std::vector<SolidPose> poses_;
  std::size_t size_ = 0;
  std::size_t insideSolids_ = 0;
};

} // namespace pbf
