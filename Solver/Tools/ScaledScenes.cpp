#include "ScaledScenes.h"

#include <algorithm>
#include <cmath>

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

} // namespace pbf
