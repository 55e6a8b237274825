#include "ScaledScenes.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace pbf
{

Scene scaledDamBreak(double particles, double spacing)
{
  const double layers = std::max(1.0, std::round(0.6 / spacing));
  const double cx = std::max(1.0, std::round(std::sqrt(particles / (1.5 * layers))));
  const double cz = std::max(1.0, std::round(particles / (layers * cx)));
  Scene scene;
  scene.name = "dam_break_wide";
  scene.description = "dam_break preset widened in x and z to the particle count";
  const double halfX = 2 * cx * spacing, halfZ = 0.5 * cz * spacing;
  FluidBox column;
  column.min = { -halfX, 0, -halfZ };
  column.max = { -halfX + cx * spacing, layers * spacing, halfZ };
  scene.boxes.push_back(column);
  scene.domain.min = { -halfX, 0, -halfZ };
  scene.domain.max = { halfX, 4.0 / 3.0 * layers * spacing, halfZ };
  return scene;
}

void splitIntoTwoLiquids(Scene& scene)
{
  Liquid water, oil;
  water.name = "water";
  oil.name = "oil";
  oil.restDensity = 800;
  scene.liquids = { water, oil };
  FluidBox upper = scene.boxes.at(0);
  const double middle = 0.5 * (upper.min.y + upper.max.y);
  scene.boxes[0].max.y = middle;
  scene.boxes[0].liquid = 0;
  upper.min.y = middle;
  upper.liquid = 1;
  scene.boxes.push_back(upper);
}

void addFloatingBoxes(Scene& scene, int count, double spacing)
{
  const double side = 8 * spacing;
  const double z0 = scene.domain.min.z;
  const double pitch = (scene.domain.max.z - z0) / std::max(count, 1);
  const double x = 0.5 * (scene.domain.min.x + scene.domain.max.x);
  for (int k = 0; k < count; ++k)
  {
    SolidRegion box;
    box.kind = SolidRegion::Kind::Box;
    const double z = z0 + (k + 0.5) * pitch;
    box.box = { { x - 0.5 * side, spacing, z - 0.5 * side },
      { x + 0.5 * side, spacing + side, z + 0.5 * side } };
    box.density = 500;
    box.name = "box " + std::to_string(k);
    scene.solids.push_back(box);
  }
}

} // namespace pbf
