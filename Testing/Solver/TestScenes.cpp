#include "TestScenes.h"

namespace pbf::test
{

Scene restingBlock(int side, double spacing)
{
  const double width = side * spacing;
  Scene scene;
  scene.name = "resting_block";
  scene.domain = { { 0, 0, 0 }, { width, 2 * width, width } };
  scene.boxes.push_back({ { 0, 0, 0 }, { width, width, width }, { 0, 0, 0 } });
  return scene;
}

double potentialEnergy(const Simulation& simulation)
{
  Snapshot<double> snapshot;
  simulation.stepper().read(snapshot);
  const Parameters& p = simulation.parameters();
  const double mass = calibratedParticleMass(p);
  const Vec3d up = p.gravity * (-1.0 / length(p.gravity));
  double energy = 0;
  for (const Vec3d& x : snapshot.position)
  {
    energy += mass * length(p.gravity) * dot(x - p.domain.min, up);
  }
  return energy;
}

std::map<std::int64_t, std::size_t> indexById(const Snapshot<double>& snapshot)
{
  std::map<std::int64_t, std::size_t> index;
  for (std::size_t i = 0; i < snapshot.id.size(); ++i)
  {
    index[snapshot.id[i]] = i;
  }
  return index;
}

} // namespace pbf::test
