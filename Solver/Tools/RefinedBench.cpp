#include "RefinedBench.h"

#include "Simulation.h"

#ifdef PBF_WITH_CUDA
#include "Cuda/CudaBackend.h"
#endif

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <vector>

namespace pbf
{

namespace
{

// What a frame's CSV row says of the particles beyond the solver's statistics, from one read.
struct FrameShape
{
  double front = 0;        // the farthest particle along +x, plus half a spacing (the fluid's
                           // edge), from the domain's wall: the surge front of a dam break
  double speedP999 = 0;    // the 99.9th and 99.99th percentiles of |v| [m/s]: how fast the
  double speedP9999 = 0;   // fluid is, where the fastest particle is a single drop
  double centreHeight = 0; // the particles' mean height above the floor [m]: a fluid that
                           // expands like a gas raises it, one that melts from a lattice not
};

double percentileOf(std::vector<double>& v, double q)
{
  if (v.empty())
  {
    return 0;
  }
  const std::size_t k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

FrameShape frameShape(const Simulation& simulation)
{
  Snapshot<float> s;
  simulation.stepper().read(s);
  const Parameters& p = simulation.parameters();
  FrameShape f;
  double far = p.domain.min.x, height = 0;
  std::vector<double> speed;
  speed.reserve(s.velocity.size());
  for (std::size_t i = 0; i < s.position.size(); ++i)
  {
    far = std::max(far, double(s.position[i].x));
    height += double(s.position[i].y) - p.domain.min.y;
    speed.push_back(length(Vec3d::from(s.velocity[i])));
  }
  f.front = far - p.domain.min.x + 0.5 * p.particleSpacing;
  f.centreHeight = s.position.empty() ? 0.0 : height / double(s.position.size());
  f.speedP9999 = percentileOf(speed, 0.9999);
  f.speedP999 = percentileOf(speed, 0.999);
  return f;
}

double median(std::vector<double> v)
{
  if (v.empty())
  {
    return 0;
  }
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

Parameters modeParameters(Parameters p, const std::string& mode)
{
  if (mode == "fixed" || mode == "fixed4")
  {
    p.densityErrorTolerance = 0;
    p.solverIterations = 4;
  }
  if (mode == "fixed")
  {
    p.timeStepping = TimeStepping::Fixed;
  }
  return p;
}

// Times one frame: CUDA events on the stepper's stream where it is a CUDA stepper, the steady
// clock otherwise.
class FrameClock
{
public:
  explicit FrameClock(const Stepper& stepper)
  {
#ifdef PBF_WITH_CUDA
    gpu_ = dynamic_cast<const cuda::CudaStepperInterface*>(&stepper);
#else
    (void)stepper;
#endif
  }
  void start()
  {
#ifdef PBF_WITH_CUDA
    if (gpu_)
    {
      events_ = std::make_unique<cuda::EventTimer>(2);
      events_->mark(*gpu_);
      return;
    }
#endif
    start_ = std::chrono::steady_clock::now();
  }
  double stopMs()
  {
#ifdef PBF_WITH_CUDA
    if (gpu_)
    {
      events_->mark(*gpu_);
      return events_->intervalsMs().front();
    }
#endif
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_)
      .count();
  }

private:
#ifdef PBF_WITH_CUDA
  const cuda::CudaStepperInterface* gpu_ = nullptr;
  std::unique_ptr<cuda::EventTimer> events_;
#endif
  std::chrono::steady_clock::time_point start_;
};

} // namespace

RefinedSettings refinedSettings(const ToolOptions& options)
{
  RefinedSettings s;
  s.spacings = toolReals(options, "refined", options.parameters.particleSpacing);
  s.until = toolReal(options, "until", 2.0);
  s.frameInterval = toolReal(options, "frame", 1.0 / 60.0);
  const std::string modes =
    options.extra.count("modes") ? options.extra.at("modes") : "fixed,fixed4,defaults";
  std::stringstream in(modes);
  std::string mode;
  while (std::getline(in, mode, ','))
  {
    if (mode != "fixed" && mode != "fixed4" && mode != "defaults")
    {
      throw InvalidInput(
        "--modes item \"" + mode + "\": must be fixed, fixed4 or defaults (comma-separated)");
    }
    s.modes.push_back(mode);
  }
  if (s.modes.empty())
  {
    throw InvalidInput("--modes = \"" + modes + "\": names no mode");
  }
  s.csvDirectory = options.extra.count("csv") ? options.extra.at("csv") : "";
  return s;
}

RefinedRun runRefined(const ToolOptions& options, const Scene& scene, double spacing,
  const std::string& mode, const RefinedSettings& settings)
{
  Parameters p = modeParameters(options.parameters, mode);
  p.particleSpacing = spacing;
  RefinedRun run;
  run.mode = mode;
  run.spacing = spacing;
  std::ofstream csv;
  if (!settings.csvDirectory.empty())
  {
    std::ostringstream name;
    name << settings.csvDirectory << "/" << scene.name << "_" << spacing << "_" << mode << "_"
         << toString(options.backend) << ".csv";
    csv.open(name.str());
    csv << "time,front,average_error,max_error,max_speed,average_neighbors,steps,iterations,"
           "milliseconds,min_dt,max_dt,speed_p999,speed_p9999,centre_height\n";
  }
  try
  {
    Simulation simulation(scene, p, options.backend, options.precision);
    run.particles = simulation.stepper().size();
    std::printf("# %s at s = %g: %zu particles, %s, %s\n", mode.c_str(), spacing, run.particles,
      simulation.stepper().description().c_str(), describe(simulation.parameters()).c_str());
    std::fflush(stdout);
    FrameClock clock(simulation.stepper());
    const double until = settings.until * (1 - 1e-12);
    for (int k = 1; static_cast<double>(k - 1) * settings.frameInterval < until; ++k)
    {
      clock.start();
      const AdvanceReport r = simulation.advanceTo(static_cast<double>(k) * settings.frameInterval);
      const double ms = clock.stopMs();
      run.frames = k;
      run.reachedTime = simulation.time();
      if (k > 1) // the first frame is the warm-up
      {
        run.frameMs.push_back(ms);
        run.timedSteps += r.steps;
        run.timedIterations += r.iterations;
      }
      run.minTimeStep = k == 1 ? r.minTimeStep : std::min(run.minTimeStep, r.minTimeStep);
      run.maxTimeStep = std::max(run.maxTimeStep, r.maxTimeStep);
      const Statistics s = simulation.stepper().statistics();
      run.worstAverage = std::max(run.worstAverage, s.averageDensityError);
      run.worstMax = std::max(run.worstMax, s.maxDensityError);
      run.fastest = std::max(run.fastest, s.maxSpeed);
      if (csv)
      {
        const FrameShape f = frameShape(simulation);
        csv << simulation.time() << "," << f.front << "," << s.averageDensityError << ","
            << s.maxDensityError << "," << s.maxSpeed << "," << s.averageNeighbors << ","
            << r.steps << "," << r.iterations << "," << ms << "," << r.minTimeStep << ","
            << r.maxTimeStep << "," << f.speedP999 << "," << f.speedP9999 << ","
            << f.centreHeight << "\n";
      }
    }
  }
  catch (const SimulationDiverged& error)
  {
    run.failure = error.what();
    run.diverged = true;
  }
  catch (const std::exception& error)
  {
    run.failure = error.what();
  }
  if (!run.failure.empty())
  {
    std::printf("# %s at s = %g stopped after %d frames (t = %.4f s): %s\n", mode.c_str(), spacing,
      run.frames, run.reachedTime, run.failure.c_str());
  }
  return run;
}

bool printRefinedTable(const std::vector<RefinedRun>& runs, double frameInterval)
{
  std::printf("\n%-8s %-8s %10s %6s %9s %8s %9s %10s %10s %8s %8s %8s %s\n", "spacing", "mode",
    "particles", "frames", "steps/fr", "iter/st", "ms/step", "ms/frame", "s/sim.s", "avgErr%",
    "maxErr%", "vmax", "status");
  bool ok = true;
  for (const RefinedRun& r : runs)
  {
    const double timed = static_cast<double>(r.frameMs.size());
    double total = 0;
    for (double ms : r.frameMs)
    {
      total += ms;
    }
    const double steps = std::max<double>(1.0, static_cast<double>(r.timedSteps));
    std::string status = "ok";
    if (r.diverged)
    {
      char text[64];
      std::snprintf(text, sizeof text, "diverged by t = %.3f s", r.reachedTime + frameInterval);
      status = text;
    }
    else if (!r.failure.empty())
    {
      status = "FAILED";
    }
    std::printf("%-8g %-8s %10zu %6d %9.1f %8.2f %9.3f %10.1f %10.2f %8.3f %8.3f %8.3f %s\n",
      r.spacing, r.mode.c_str(), r.particles, r.frames,
      timed > 0 ? static_cast<double>(r.timedSteps) / timed : 0.0,
      static_cast<double>(r.timedIterations) / steps, total / steps, median(r.frameMs),
      timed > 0 ? total / 1000.0 / (timed * frameInterval) : 0.0, 100 * r.worstAverage,
      100 * r.worstMax, r.fastest, status.c_str());
    ok = ok && (r.failure.empty() || r.mode == "fixed");
  }
  std::printf("(ms/frame: median over frames 2..N; ms/step and s/sim.s: their total over their "
              "steps and simulated time; the first frame is the warm-up)\n");
  std::fflush(stdout);
  return ok;
}

} // namespace pbf
