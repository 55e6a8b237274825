// pbf_run: runs a scene for a number of steps, or frame by frame to a time, and prints statistics
// as it goes. The quick way to look at the solver without ParaView.
#include "Scene.h"
#include "Simulation.h"
#include "ToolOptions.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

using namespace pbf;

namespace
{

// Frame k lands on k * frame exactly, as the VTK filter's frames do.
int runFrames(Simulation& simulation, const ToolOptions& options, const Scene& scene, long report)
{
  const double until = toolReal(options, "until", 1.0);
  const double frame = toolReal(options, "frame", 1.0 / 60.0);
  std::printf("scene %s, %zu particles, %s, %s precision\n%s\n", scene.name.c_str(),
    simulation.stepper().size(), simulation.stepper().description().c_str(),
    toString(options.precision), describe(simulation.parameters()).c_str());
  std::printf("%7s %8s %8s %10s %10s %10s %10s %10s %9s %9s %9s %10s\n", "t[s]", "frame", "step",
    "particles", "avgErr%", "maxErr%", "neighbors", "maxSpeed", "substeps", "dtMin[ms]",
    "iter/step", "ms/frame");
  AdvanceReport frames; // since the last line
  long framesSince = 0;
  double worstAverage = 0, worstMax = 0, fastest = 0;
  for (long k = 0;; ++k)
  {
    const double t = static_cast<double>(k) * frame;
    if (k > 0)
    {
      frames.add(simulation.advanceTo(t));
      ++framesSince;
    }
    const bool last = t >= until;
    if (k % report == 0 || last)
    {
      const Statistics s = simulation.stepper().statistics();
      worstAverage = std::max(worstAverage, s.averageDensityError);
      worstMax = std::max(worstMax, s.maxDensityError);
      fastest = std::max(fastest, s.maxSpeed);
      const double perFrame = framesSince > 0 ? 1.0 / static_cast<double>(framesSince) : 0.0;
      const double steps = static_cast<double>(frames.steps);
      std::printf("%7.3f %8ld %8lu %10zu %10.3f %10.3f %10.2f %10.4f %9.2f %9.4f %9.2f %10.2f\n",
        t, k, static_cast<unsigned long>(simulation.stepCount()), s.particles,
        100 * s.averageDensityError, 100 * s.maxDensityError, s.averageNeighbors, s.maxSpeed,
        steps * perFrame, 1e3 * frames.minTimeStep,
        steps > 0 ? static_cast<double>(frames.iterations) / steps : 0.0,
        frames.milliseconds * perFrame);
      std::fflush(stdout);
      frames = AdvanceReport{};
      framesSince = 0;
      if (!s.finite)
      {
        std::fprintf(stderr, "non-finite state at t = %g s\n", t);
        return 3;
      }
    }
    if (last)
    {
      break;
    }
  }
  std::printf("worst: avgErr %.3f %%, maxErr %.3f %%, maxSpeed %.3f m/s\n", 100 * worstAverage,
    100 * worstMax, fastest);
  return 0;
}

} // namespace

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "steps", "steps to run (default 200)" },
    { "report", "print statistics every this many steps (default 50), or frames with --until" },
    { "until", "run frame by frame to this time [s] instead of --steps" },
    { "frame", "the frame interval with --until [s] (default 1/60)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const Scene scene = toolScene(options);
    const long steps = toolInteger(options, "steps", 200, 0);
    const long report = toolInteger(options, "report", 50, 1);
    Simulation simulation(scene, options.parameters, options.backend, options.precision);
    if (options.extra.count("until"))
    {
      return runFrames(simulation, options, scene, report);
    }
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
