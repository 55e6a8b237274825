// pbf_soak: a long run that checks, every --check steps, what must never change: the particle
// count (initial plus exactly what the emitters released), unique ids, every particle inside the
// domain, no NaN, and flat memory (host RSS; device bytes for CUDA). Exits 1 at the first
// violation, naming the step. Run on the CPU and on the GPU (Utilities/gpu/run.sh).
#include "ScaledScenes.h"
#include "Scene.h"
#include "Simulation.h"
#include "ToolOptions.h"

#ifdef PBF_WITH_CUDA
#include "Cuda/CudaBackend.h"
#endif

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <unistd.h>
#include <unordered_set>

using namespace pbf;

namespace
{

double residentMegabytes()
{
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1048576.0;
}

double deviceMegabytes(const Stepper& stepper)
{
#ifdef PBF_WITH_CUDA
  if (const auto* gpu = dynamic_cast<const cuda::CudaStepperInterface*>(&stepper))
  {
    return static_cast<double>(gpu->diagnostics().deviceBytes) / 1048576.0;
  }
#endif
  (void)stepper;
  return 0.0;
}

// The first violation in the state, or "" when all holds.
std::string violation(const Simulation& simulation, std::int64_t expectedCount)
{
  Snapshot<double> s;
  simulation.stepper().read(s);
  if (static_cast<std::int64_t>(s.id.size()) != expectedCount)
  {
    return "particle count " + std::to_string(s.id.size()) + ", expected " +
      std::to_string(expectedCount);
  }
  std::unordered_set<std::int64_t> ids(s.id.begin(), s.id.end());
  if (static_cast<std::int64_t>(ids.size()) != expectedCount)
  {
    return "ids not unique: " + std::to_string(ids.size()) + " distinct of " +
      std::to_string(expectedCount);
  }
  const Box& d = simulation.parameters().domain;
  for (std::size_t i = 0; i < s.position.size(); ++i)
  {
    const Vec3d& x = s.position[i];
    const Vec3d& v = s.velocity[i];
    if (!std::isfinite(x.x + x.y + x.z + v.x + v.y + v.z + s.density[i] + s.lambda[i]))
    {
      return "non-finite state at particle id " + std::to_string(s.id[i]);
    }
    if (x.x < d.min.x || x.y < d.min.y || x.z < d.min.z || x.x > d.max.x || x.y > d.max.y ||
      x.z > d.max.z)
    {
      return "particle id " + std::to_string(s.id[i]) + " outside the domain";
    }
  }
  return "";
}

} // namespace

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "steps", "steps to run (default 10000)" },
    { "check", "check every this many steps (default 500)" },
    { "particles", "instead of --scene: the dam break widened to this many particles" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    usePaperIterationsUnlessGiven(options);
    const long steps = toolInteger(options, "steps", 10000, 0);
    const long check = toolInteger(options, "check", 500, 1);
    const Scene scene = options.extra.count("particles")
      ? scaledDamBreak(std::stod(options.extra["particles"]), options.parameters.particleSpacing)
      : toolScene(options);
    Simulation simulation(scene, options.parameters, options.backend, options.precision);
    std::printf("soak %s: %zu particles at start, %s, %s precision, %ld steps\n",
      scene.name.c_str(), simulation.stepper().size(), simulation.stepper().description().c_str(),
      toString(options.precision), steps);
    std::printf("%8s %10s %10s %10s %10s %10s %9s\n", "step", "particles", "maxSpeed", "avgErr%",
      "RSS MB", "device MB", "ms/step");
    const auto start = std::chrono::steady_clock::now();
    double firstRss = 0, lastRss = 0;
    for (long done = 0; done <= steps; done += check)
    {
      const AdvanceReport report =
        simulation.advance(done == 0 ? 0 : static_cast<std::uint64_t>(check));
      const std::int64_t expected = simulation.idCount();
      const std::string problem = violation(simulation, expected);
      const Statistics s = simulation.stepper().statistics();
      lastRss = residentMegabytes();
      firstRss = done == 0 ? lastRss : firstRss;
      std::printf("%8lu %10zu %10.4f %10.3f %10.1f %10.1f %9.3f\n",
        static_cast<unsigned long>(simulation.stepCount()), s.particles, s.maxSpeed,
        100 * s.averageDensityError, lastRss, deviceMegabytes(simulation.stepper()),
        report.steps ? report.milliseconds / double(report.steps) : 0.0);
      if (!problem.empty())
      {
        std::printf("FAILED at step %lu: %s\n", static_cast<unsigned long>(simulation.stepCount()),
          problem.c_str());
        return 1;
      }
    }
    const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("PASSED: %ld steps, %zu particles, %.1f s, RSS %.1f -> %.1f MB\n", steps,
      simulation.stepper().size(), seconds, firstRss, lastRss);
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_soak: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
