// pbf_obstacle_check: "no particle inside any obstacle" on one backend: the MARIN box
// to 6 s, a sphere in the dam break's way to 2 s, a plate 1.5 spacings thick hit head-on at
// 4 m/s, every frame (1/60 s) scanned against the solids' distance fields. --ranks N decomposes
// the run over N threads (the CPU or the GPU sub-domain stepper, by --backend).
#include "ObstacleCheck.h"

#include "ToolOptions.h"

#include <chrono>
#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "ranks", "decompose over this many ranks (threads; default 1)" },
    { "until-scale", "run each scene for this fraction of its time (default 1)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const long ranks = toolInteger(options, "ranks", 1, 1);
    const double scale = toolReal(options, "until-scale", 1.0);
    std::printf("scene,backend,ranks,spacing,particles,frames,inside_worst_frame,closest_m,"
                "fastest_m_s,seconds\n");
    for (ObstacleScene scene : obstacleScenes(options.parameters.particleSpacing))
    {
      scene.until *= scale;
      const auto start = std::chrono::steady_clock::now();
      const ObstacleReport r = checkObstacles(scene, options.parameters, options.backend,
        options.precision, static_cast<int>(ranks), 1.0 / 60.0);
      const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::printf("%s,%s,%ld,%g,%zu,%d,%zu,%.5f,%.2f,%.1f\n", scene.name.c_str(),
        toString(options.backend), ranks, options.parameters.particleSpacing, r.particles,
        r.frames, r.worstInside, r.closest, r.fastest, seconds);
      std::fflush(stdout);
    }
    return 0;
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_obstacle_check: " << error.what() << "\n";
    return 1;
  }
}
