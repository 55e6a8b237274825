// Whether any particle centre enters a solid: the scenes of the obstacle check (the MARIN box, a
// sphere in the dam break's way, a thin plate hit head-on at 4 m/s), run on any backend and any
// number of ranks (threads), every frame scanned against the solids' own distance fields.
#pragma once

#include "Scene.h"
#include "Stepper.h"

#include <string>
#include <vector>

namespace pbf::validation
{

struct ObstacleScene
{
  std::string name;
  Scene scene;
  double until = 0; // [s]
};

// The three scenes at particle spacing s (the plate is 1.5 s thick).
std::vector<ObstacleScene> obstacleScenes(double spacing);

struct ObstacleReport
{
  int frames = 0;
  std::size_t particles = 0;   // at the end, all ranks
  double closest = 0;          // smallest signed distance of a particle centre, any frame [m]
  std::size_t worstInside = 0; // most particle centres inside a solid in one frame
  double fastest = 0;          // the fastest particle of any frame [m/s]
};

// Runs `scene` to scene.until on `backend` (ranks > 1: decomposed over that many threads),
// scanning every frame (`frame` [s] apart).
ObstacleReport checkObstacles(const ObstacleScene& scene, const Parameters& parameters,
  Backend backend, Precision precision, int ranks, double frame);

} // namespace pbf::validation
