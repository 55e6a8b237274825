#include "ObstacleCheck.h"

#include "Distributed/ThreadCluster.h"
#include "Simulation.h"
#include "Solids.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

namespace pbf::validation
{

std::vector<ObstacleScene> obstacleScenes(double s)
{
  std::vector<ObstacleScene> scenes;
  scenes.push_back({ "MARIN box", presetScene("marin_dam_break"), 6.0 });

  // The dam break with a sphere standing on the floor in the surge's way.
  Scene sphere = presetScene("dam_break");
  sphere.name = "dam_break_sphere";
  SolidRegion ball;
  ball.kind = SolidRegion::Kind::Sphere;
  ball.center = { 0.9, 0.0, 0.3 };
  ball.radius = 0.2;
  sphere.solids.push_back(ball);
  scenes.push_back({ "sphere in the dam break", sphere, 2.0 });

  // A block of water thrown at 4 m/s (+x) at a plate 1.5 spacings thick across its path, as a
  // thin shell of a single square: nothing but the shell stands between the two halves.
  Scene plate;
  plate.name = "plate_head_on";
  plate.domain = { { 0, 0, 0 }, { 1.2, 0.6, 0.6 } };
  FluidBox block;
  block.min = { 0.05, 0.15, 0.15 };
  block.max = { 0.35, 0.45, 0.45 };
  block.velocity = { 4.0, 0.0, 0.0 };
  plate.boxes.push_back(block);
  SolidRegion sheet;
  sheet.kind = SolidRegion::Kind::Mesh;
  sheet.mesh.points = { { 0.7, 0.05, 0.05 }, { 0.7, 0.55, 0.05 }, { 0.7, 0.55, 0.55 },
    { 0.7, 0.05, 0.55 } };
  sheet.mesh.triangles = { { 0, 1, 2 }, { 0, 2, 3 } };
  sheet.thickness = 1.5 * s;
  sheet.name = "the plate";
  plate.solids.push_back(sheet);
  scenes.push_back({ "plate 1.5 s thick at 4 m/s", plate, 0.4 });
  return scenes;
}

ObstacleReport checkObstacles(const ObstacleScene& item, const Parameters& parameters,
  Backend backend, Precision precision, int ranks, double frame)
{
  const Parameters p = withSceneDomain(parameters, item.scene);
  const std::vector<DistanceGrid> fields = solidFields(item.scene.solids, p);
  ObstacleReport report;
  report.closest = std::numeric_limits<double>::infinity();
  std::mutex mutex;
  const int frames = static_cast<int>(std::llround(item.until / frame));
  // Per frame, over every rank: how many inside, the closest, the fastest.
  std::vector<std::size_t> inside(static_cast<std::size_t>(frames) + 1, 0);
  std::vector<std::size_t> count(static_cast<std::size_t>(frames) + 1, 0);
  auto run = [&](distributed::Communicator* communicator) {
    Simulation simulation(item.scene, parameters, backend, precision, communicator);
    for (int f = 0; f <= frames; ++f)
    {
      simulation.advanceTo(f * frame);
      Snapshot<double> state;
      simulation.stepper().read(state);
      std::size_t in = 0;
      double closest = std::numeric_limits<double>::infinity(), fastest = 0;
      for (std::size_t i = 0; i < state.position.size(); ++i)
      {
        double phi = std::numeric_limits<double>::infinity();
        for (const DistanceGrid& g : fields)
        {
          phi = std::min(phi, g.at(state.position[i]));
        }
        in += phi < 0 ? 1 : 0;
        closest = std::min(closest, phi);
        fastest = std::max(fastest, length(state.velocity[i]));
      }
      std::lock_guard<std::mutex> lock(mutex);
      inside[static_cast<std::size_t>(f)] += in;
      count[static_cast<std::size_t>(f)] += state.position.size();
      report.closest = std::min(report.closest, closest);
      report.fastest = std::max(report.fastest, fastest);
    }
  };
  if (ranks > 1)
  {
    distributed::runThreadCluster(ranks, [&](distributed::Communicator& c) { run(&c); });
  }
  else
  {
    run(nullptr);
  }
  report.frames = frames + 1;
  report.particles = count.back();
  report.worstInside = *std::max_element(inside.begin(), inside.end());
  return report;
}

} // namespace pbf::validation
