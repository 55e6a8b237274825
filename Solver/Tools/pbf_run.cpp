// pbf_run: runs a scene for a number of steps and prints statistics every few steps. The quick way
// to look at the solver without ParaView.
#include "Scene.h"
#include "Simulation.h"
#include "ToolOptions.h"

#include <chrono>
#include <cstdio>
#include <iostream>

using namespace pbf;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "steps", "steps to run (default 200)" },
    { "report", "print statistics every this many steps (default 50)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const Scene scene = options.scene.find(".json") != std::string::npos
      ? loadSceneFile(options.scene)
      : presetScene(options.scene);
    const long steps = toolInteger(options, "steps", 200, 0);
    const long report = toolInteger(options, "report", 50, 1);
    Simulation simulation(scene, options.parameters, options.backend, options.precision);
    std::printf("scene %s, %zu particles, %s, %s precision\n%s\n", scene.name.c_str(),
      simulation.stepper().size(), simulation.stepper().description().c_str(),
      toString(options.precision), describe(simulation.parameters()).c_str());
    std::printf("%8s %10s %10s %10s %10s %10s %12s %10s\n", "step", "particles", "avgErr%",
      "maxErr%", "neighbors", "maxSpeed", "kinetic[J]", "ms/step");
    double elapsed = 0;
    for (long k = 0; k <= steps; k += report)
    {
      const long n = k == 0 ? 0 : report;
      const auto t0 = std::chrono::steady_clock::now();
      simulation.advance(static_cast<std::uint64_t>(n));
      const auto t1 = std::chrono::steady_clock::now();
      elapsed = std::chrono::duration<double, std::milli>(t1 - t0).count();
      const Statistics s = simulation.stepper().statistics();
      std::printf("%8lu %10zu %10.3f %10.3f %10.2f %10.4f %12.5g %10.3f\n",
        static_cast<unsigned long>(simulation.stepCount()), s.particles,
        100 * s.averageDensityError, 100 * s.maxDensityError, s.averageNeighbors, s.maxSpeed,
        s.kineticEnergy, n ? elapsed / n : 0.0);
      if (!s.finite)
      {
        std::fprintf(stderr, "non-finite state at step %lu\n",
          static_cast<unsigned long>(simulation.stepCount()));
        return 3;
      }
    }
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_run: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
