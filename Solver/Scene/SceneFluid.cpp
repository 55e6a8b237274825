#include "SceneFluid.h"

#include "Solids.h"

#include <cmath>

namespace pbf
{

SceneFluid::SceneFluid(const Scene& scene, const Parameters& parameters,
  const std::vector<DistanceGrid>& solids, const std::vector<SolidPose>& poses)
  : scene_(scene)
  , spacing_(parameters.particleSpacing)
  , liquids_(!scene.liquids.empty())
  , solids_(solids)
  , poses_(poses)
{
  forEachSceneSite(scene_, spacing_, [&](const Vec3d& x, const Vec3d&, std::uint8_t) {
    if (!solids_.empty() && pbf::insideSolids(x, solids_, poses_))
    {
      ++insideSolids_;
      return;
    }
    ++size_;
  });
}

void SceneFluid::forEachKept(
  const std::function<void(const Vec3d&, const Vec3d&, std::uint8_t, std::int64_t)>& site) const
{
  std::int64_t id = 0;
  forEachSceneSite(scene_, spacing_, [&](const Vec3d& x, const Vec3d& v, std::uint8_t liquid) {
    if (!solids_.empty() && pbf::insideSolids(x, solids_, poses_))
    {
      return;
    }
    site(x, v, liquid, id++);
  });
}

void SceneFluid::forEachPosition(const std::function<void(const Vec3d&)>& visit) const
{
  forEachKept([&](const Vec3d& x, const Vec3d&, std::uint8_t, std::int64_t) { visit(x); });
}

void SceneFluid::forEachWhere(const Keep& keep, const Visit& visit) const
{
  forEachKept([&](const Vec3d& x, const Vec3d& v, std::uint8_t liquid, std::int64_t id) {
    if (keep(x))
    {
      visit(x, v, id, liquid);
    }
  });
}

} // namespace pbf
