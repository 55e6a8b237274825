// pbf_refined: the scene users run, refined. The dam_break preset (or any scene) at one or more
// spacings, simulated frame by frame to a time with automatic steps (Simulation::advanceTo), in
// two modes: "defaults" (adaptive iterations to the default tolerance) and "fixed4" (the paper's
// 4 projections per step). Reports what a user of the GPU sees: ms per frame and per simulated
// second (wall time of advanceTo, the device's queued work and the per-step host reads of the
// automatic step included), steps and iterations per frame, and the physics of every frame: mean
// and max compression, max speed, the surge front. --csv DIR writes one CSV of frames per run.
#include "Scene.h"
#include "Simulation.h"
#include "ToolOptions.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

struct Summary
{
  std::string mode;
  double spacing = 0;
  std::size_t particles = 0;
  int frames = 0;
  std::uint64_t steps = 0;
  long iterations = 0;
  double milliseconds = 0;
  double worstAverage = 0, worstMax = 0, fastest = 0;
  double minTimeStep = 0, maxTimeStep = 0;
  std::string failure; // empty: the run reached the end
};

// The farthest particle along +x, plus half a spacing (the fluid's edge), from the domain's wall.
double front(const Simulation& simulation)
{
  Snapshot<float> s;
  simulation.stepper().read(s);
  double far = simulation.parameters().domain.min.x;
  for (const Vec3<float>& x : s.position)
  {
    far = std::max(far, double(x.x));
  }
  return far - simulation.parameters().domain.min.x + 0.5 * simulation.parameters().particleSpacing;
}

Summary run(const ToolOptions& options, const Scene& scene, double spacing, const std::string& mode,
  double until, double interval, const std::string& csvDirectory)
{
  Parameters p = options.parameters;
  p.particleSpacing = spacing;
  if (mode == "fixed4")
  {
    p.densityErrorTolerance = 0;
    p.solverIterations = 4;
  }
  Summary summary;
  summary.mode = mode;
  summary.spacing = spacing;
  std::ofstream csv;
  if (!csvDirectory.empty())
  {
    std::ostringstream name;
    name << csvDirectory << "/" << scene.name << "_" << spacing << "_" << mode << "_"
         << toString(options.backend) << ".csv";
    csv.open(name.str());
    csv << "time,front,average_error,max_error,max_speed,average_neighbors,steps,iterations,"
           "milliseconds,min_dt,max_dt\n";
  }
  try
  {
    Simulation simulation(scene, p, options.backend, options.precision);
    summary.particles = simulation.stepper().size();
    std::printf("# %s at s = %g: %zu particles, %s, %s\n", mode.c_str(), spacing,
      summary.particles, simulation.stepper().description().c_str(),
      describe(simulation.parameters()).c_str());
    std::fflush(stdout);
    for (int k = 1; static_cast<double>(k - 1) * interval < until * (1 - 1e-12); ++k)
    {
      const auto start = std::chrono::steady_clock::now();
      const AdvanceReport r = simulation.advanceTo(static_cast<double>(k) * interval);
      const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      summary.frames = k;
      summary.steps += r.steps;
      summary.iterations += r.iterations;
      summary.milliseconds += ms;
      summary.minTimeStep = k == 1 ? r.minTimeStep : std::min(summary.minTimeStep, r.minTimeStep);
      summary.maxTimeStep = std::max(summary.maxTimeStep, r.maxTimeStep);
      const Statistics s = simulation.stepper().statistics();
      summary.worstAverage = std::max(summary.worstAverage, s.averageDensityError);
      summary.worstMax = std::max(summary.worstMax, s.maxDensityError);
      summary.fastest = std::max(summary.fastest, s.maxSpeed);
      if (csv)
      {
        csv << simulation.time() << "," << front(simulation) << "," << s.averageDensityError
            << "," << s.maxDensityError << "," << s.maxSpeed << "," << s.averageNeighbors << ","
            << r.steps << "," << r.iterations << "," << ms << "," << r.minTimeStep << ","
            << r.maxTimeStep << "\n";
      }
    }
  }
  catch (const std::exception& error)
  {
    summary.failure = error.what();
    std::printf("# %s at s = %g failed after %d frames: %s\n", mode.c_str(), spacing,
      summary.frames, error.what());
  }
  return summary;
}

} // namespace

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "spacings", "comma-separated particle spacings [m] (default 0.04,0.02)" },
    { "until", "simulated time [s] (default 2)" },
    { "frame", "frame interval [s] (default 1/60)" },
    { "modes", "defaults, fixed4 or both (default both)" },
    { "csv", "a folder for one CSV of frames per run" },
  };
  try
  {
    const ToolOptions options = parseToolOptions(argc, argv, keys);
    const Scene scene = options.scene.find(".json") != std::string::npos
      ? loadSceneFile(options.scene)
      : presetScene(options.scene);
    const std::vector<double> spacings = options.extra.count("spacings")
      ? toolReals(options, "spacings", 0.0)
      : std::vector<double>{ 0.04, 0.02 };
    const double until = toolReal(options, "until", 2.0);
    const double interval = toolReal(options, "frame", 1.0 / 60.0);
    const std::string modes = options.extra.count("modes") ? options.extra.at("modes") : "both";
    if (modes != "defaults" && modes != "fixed4" && modes != "both")
    {
      throw InvalidInput("--modes = \"" + modes + "\": must be defaults, fixed4 or both");
    }
    const std::string csv = options.extra.count("csv") ? options.extra.at("csv") : "";
    std::vector<Summary> summaries;
    for (double spacing : spacings)
    {
      for (const std::string mode : { "fixed4", "defaults" })
      {
        if (modes == "both" || modes == mode)
        {
          summaries.push_back(run(options, scene, spacing, mode, until, interval, csv));
        }
      }
    }
    std::printf("\n%-8s %-8s %10s %6s %8s %9s %8s %9s %10s %12s %8s %8s %8s %s\n", "spacing",
      "mode", "particles", "frames", "steps", "steps/fr", "iter/st", "ms/step", "ms/frame",
      "s/sim.s", "avgErr%", "maxErr%", "vmax", "status");
    for (const Summary& s : summaries)
    {
      const double steps = std::max<double>(1.0, static_cast<double>(s.steps));
      const double frames = std::max(1, s.frames);
      std::printf("%-8g %-8s %10zu %6d %8llu %9.1f %8.2f %9.3f %10.1f %12.2f %8.3f %8.3f %8.3f %s\n",
        s.spacing, s.mode.c_str(), s.particles, s.frames,
        static_cast<unsigned long long>(s.steps), s.steps / frames, s.iterations / steps,
        s.milliseconds / steps, s.milliseconds / frames,
        s.milliseconds / 1000.0 / (frames * interval), 100 * s.worstAverage, 100 * s.worstMax,
        s.fastest, s.failure.empty() ? "ok" : "FAILED");
    }
    for (const Summary& s : summaries)
    {
      if (!s.failure.empty())
      {
        return 1;
      }
    }
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_refined: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
