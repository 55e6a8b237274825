// pbf_bench: time the solver on a dam break scaled to a given particle count.
//
// The scene is the dam_break preset widened in x and z (scaledDamBreak) so that the default
// spacing gives N particles: the height, the flow and the time step stay the preset's. Warm-up
// steps are excluded; GPU steps are timed with CUDA events on the stepper's stream, CPU steps with
// the host's steady clock. Prints a table and, with --json, writes every run as JSON.
//
// --refined SPACINGS times the scene users run instead: the dam_break preset (or --scene) refined
// to those spacings, frame by frame to --until, fixed and automatic stepping side by side, in ms
// per step and per simulated second (RefinedBench.h).
#include "Backends.h"
#include "RefinedBench.h"
#include "Scene.h"
#include "ScaledScenes.h"
#include "Simulation.h"
#include "Stepper.h"
#include "ToolOptions.h"

#ifdef PBF_WITH_CUDA
#include "Cuda/CudaBackend.h"
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

struct Result
{
  std::string backend, precision, device, neighbors;
  double skin = 0;
  bool graphs = false;
  int block = 0;
  int iterations = 0;
  std::size_t particles = 0;
  int steps = 0;
  double medianMs = 0, p10Ms = 0, p90Ms = 0, stepsPerSecond = 0;
  double averageNeighbors = 0, averageDensityError = 0, maxDensityError = 0;
  double bytesPerParticle = 0; // device memory per particle (CUDA only)
  std::size_t deviceBytes = 0;
  double maskBuildsPerStep = 0;
  double setupSeconds = 0;
  bool finite = true;
};

double percentile(std::vector<double> v, double q)
{
  if (v.empty())
  {
    return 0;
  }
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(at));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

// The run's step times and final state into its result: median and spread, the state's
// neighbours and compression.
void summarize(const std::vector<double>& ms, const Stepper& stepper, Result& r)
{
  r.medianMs = percentile(ms, 0.5);
  r.p10Ms = percentile(ms, 0.1);
  r.p90Ms = percentile(ms, 0.9);
  r.stepsPerSecond = r.medianMs > 0 ? 1000.0 / r.medianMs : 0.0;
  const Statistics s = stepper.statistics();
  r.averageNeighbors = s.averageNeighbors;
  r.averageDensityError = s.averageDensityError;
  r.maxDensityError = s.maxDensityError;
  r.finite = s.finite;
}

// The benchmark's solid, set on the stepper: 1 a sphere standing on the floor in the surge's way,
// a fifth of the tank's height across (what one solid costs a step: its distance lookups in every
// pass near it); 3 the same sphere rolling towards the column at 1 m/s, turning at 1 rad/s (what
// a moving solid adds: the rotation into its frame at every lookup, its pose's upload before each
// step); 2 the MARIN box (Data/marin_dam_break.json) in the same proportions of the tank,
// mirrored in x because this column stands at the -x end. Returns the rolling sphere's motion.
SolidMotion setBenchmarkSolid(Stepper& stepperRef, const Parameters& parameters, int solid)
{
  Stepper* stepper = &stepperRef;
  SolidMotion rolling;
  if (solid == 1 || solid == 3)
  {
    const Box& d = parameters.domain;
    SolidRegion sphere;
    sphere.kind = SolidRegion::Kind::Sphere;
    sphere.radius = 0.2 * (d.max.y - d.min.y);
    sphere.center = { d.min.x + 0.6 * (d.max.x - d.min.x), d.min.y + sphere.radius,
      0.5 * (d.min.z + d.max.z) };
    if (solid == 3)
    {
      rolling.pivot = sphere.center;
      rolling.keyframes = { { 0.0, { 0, 0, 0 }, Rotation{} },
        { 1.0, { -1.0, 0, 0 }, Rotation::fromDegrees({ 0, 0, 57.29577951308232 }) } };
      sphere.motion = rolling;
      stepper->setObstacles(solidFields({ sphere }, parameters), { rolling.at(0.0) });
    }
    else
    {
      stepper->setObstacles(solidFields({ sphere }, parameters));
    }
  }
  else if (solid == 2)
  {
    const Box& d = parameters.domain;
    const Vec3d size = d.max - d.min;
    SolidRegion box;
    box.kind = SolidRegion::Kind::Box;
    box.box = { d.min + Vec3d{ (1.0 - 0.8245 / 3.22) * size.x, 0.0, 0.2955 * size.z },
      d.min + Vec3d{ (1.0 - 0.6635 / 3.22) * size.x, 0.161 * size.y, 0.6985 * size.z } };
    stepper->setObstacles(solidFields({ box }, parameters));
  }
  return rolling;
}

// The widened dam break's settings from the command line, each checked as it is read.
struct BenchSettings
{
  std::vector<double> counts; // particle counts, one run each
  int steps = 0;
  int warmup = 0;
  std::string neighbors; // CUDA: masks | walk
  double skin = 0;
  bool graphs = true;
  int block = 0;
  int solid = 0;      // setBenchmarkSolid
  double outflowY = 0; // > 0: an outflow strip at this height (bodiesBenchmark)
  int bodies = -1;    // >= 0: through Simulation with this many bodies (bodiesBenchmark)
  int liquids = 1;
};

// The stepper a run times, and the same stepper where it runs on the GPU (its events time it).
struct TimedStepper
{
  std::unique_ptr<Stepper> stepper;
#ifdef PBF_WITH_CUDA
  cuda::CudaStepperInterface* gpu = nullptr;
#endif
};

// The stepper on the batch: for CUDA with the settings' neighbour search, skin, graphs and block
// (recorded in the result), otherwise the backend's own (its neighbours "walk").
TimedStepper makeTimedStepper(const ToolOptions& options, const Parameters& parameters,
  const ParticleBatch& batch, const BenchSettings& settings, Result& r)
{
  TimedStepper timed;
#ifdef PBF_WITH_CUDA
  if (options.backend == Backend::CUDA)
  {
    cuda::Options o;
    o.search = settings.neighbors == "walk" ? cuda::NeighborSearch::CellWalk
                                            : cuda::NeighborSearch::RowMasks;
    o.skin = settings.skin;
    o.graphs = settings.graphs;
    o.block = settings.block;
    auto made = cuda::makeCudaStepper(options.precision, parameters, batch, o);
    timed.gpu = made.get();
    timed.stepper = std::move(made);
    r.neighbors = settings.neighbors;
    r.skin = settings.skin;
    r.graphs = settings.graphs;
    r.block = settings.block;
  }
  else
#else
  (void)settings;
#endif
  {
    timed.stepper = makeStepper(options.backend, options.precision, parameters, batch);
    r.neighbors = "walk";
  }
  return timed;
}

#ifdef PBF_WITH_CUDA
// The timed steps on the GPU after the warm-up: CUDA events on the stepper's stream, one before
// the first and one after each step. The setup time ends when the warm-up's work is done.
template <class Place>
std::vector<double> timeGpuSteps(cuda::CudaStepperInterface& gpu, int warmup, int steps,
  Place&& place, std::chrono::steady_clock::time_point setup0, Result& r)
{
  gpu.synchronize();
  r.setupSeconds =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - setup0).count();
  const std::uint64_t builds0 = gpu.diagnostics().maskBuilds;
  cuda::EventTimer timer(static_cast<std::size_t>(steps) + 1);
  timer.mark(gpu);
  for (int s = 0; s < steps; ++s)
  {
    place(warmup + s);
    gpu.step();
    timer.mark(gpu);
  }
  std::vector<double> ms = timer.intervalsMs();
  const cuda::Diagnostics d = gpu.diagnostics();
  r.bytesPerParticle = d.bytesPerParticle;
  r.deviceBytes = d.deviceBytes;
  // In builds of every particle's masks: 1 is the least a step does.
  r.maskBuildsPerStep = steps > 0 && r.particles > 0
    ? double(d.maskBuilds - builds0) / steps / double(r.particles)
    : 0.0;
  return ms;
}
#endif

// The timed steps on the CPU after the warm-up, each on the host's steady clock.
template <class Place>
std::vector<double> timeHostSteps(Stepper& stepper, int warmup, int steps, Place&& place,
  std::chrono::steady_clock::time_point setup0, Result& r)
{
  r.setupSeconds =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - setup0).count();
  std::vector<double> ms;
  for (int s = 0; s < steps; ++s)
  {
    const auto t0 = std::chrono::steady_clock::now();
    place(warmup + s);
    stepper.step();
    const auto t1 = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  return ms;
}

Result benchmark(const ToolOptions& options, double particles, const BenchSettings& settings)
{
  const int warmup = settings.warmup;
  const int steps = settings.steps;
  const int solid = settings.solid;
  Scene scene = scaledDamBreak(particles, options.parameters.particleSpacing);
  if (settings.liquids == 2)
  {
    splitIntoTwoLiquids(scene);
  }
  const Parameters parameters = withSceneDomain(options.parameters, scene);
  const auto setup0 = std::chrono::steady_clock::now();
  ParticleBatch batch = fillScene(scene, parameters);

  Result r;
  r.backend = toString(options.backend);
  r.precision = toString(options.precision);
  r.iterations = parameters.solverIterations;
  r.particles = batch.position.size();
  r.steps = steps;

  TimedStepper timed = makeTimedStepper(options, parameters, batch, settings, r);
  std::unique_ptr<Stepper>& stepper = timed.stepper;
  batch = ParticleBatch{}; // the host copy is not needed any more
  r.device = stepper->description();
  // Solid 3: where the rolling sphere is at the end of step s (its pose uploaded before each
  // step, as Simulation does; that copy is part of what it costs).
  const SolidMotion rolling = setBenchmarkSolid(*stepper, parameters, solid);
  auto place = [&](int s) {
    if (solid == 3)
    {
      stepper->setObstaclePoses({ rolling.at((s + 1) * parameters.timeStep) });
    }
  };

  for (int s = 0; s < warmup; ++s)
  {
    place(s);
    stepper->step();
  }
  std::vector<double> ms;
#ifdef PBF_WITH_CUDA
  if (timed.gpu)
  {
    ms = timeGpuSteps(*timed.gpu, warmup, steps, place, setup0, r);
  }
  else
#endif
  {
    ms = timeHostSteps(*stepper, warmup, steps, place, setup0, r);
  }
  summarize(ms, *stepper, r);
  return r;
}

// --bodies N: the same scene run as users run it, through Simulation with fixed steps, with N
// boxes the fluid moves (addFloatingBoxes; 0: none, the path's own baseline). Each step reads the
// loads back and places the bodies before the next, so the host waits on the device every step:
// timed on the host's steady clock, that wait included.
// --outflow Y adds an outflow: a strip one spacing high at height Y and two spacings wide along
// the -x wall, which the column's back falls through as it collapses, so that some particles
// leave at every step while the count stays nearly the same (what the removal costs: a
// selection, the gathers and, on a GPU, the step captured again).
Result bodiesBenchmark(const ToolOptions& options, double particles, int warmup, int steps,
  int bodies, double outflowY)
{
  Scene scene = scaledDamBreak(particles, options.parameters.particleSpacing);
  addFloatingBoxes(scene, bodies, options.parameters.particleSpacing);
  if (outflowY > 0)
  {
    Outflow slab;
    slab.box = scene.domain;
    slab.box.min.y = outflowY;
    slab.box.max.y = outflowY + options.parameters.particleSpacing;
    slab.box.max.x = scene.domain.min.x + 2 * options.parameters.particleSpacing;
    scene.outflows.push_back(slab);
  }
  Parameters parameters = withSceneDomain(options.parameters, scene);
  parameters.timeStepping = TimeStepping::Fixed;
  const auto setup0 = std::chrono::steady_clock::now();
  Simulation simulation(scene, parameters, options.backend, options.precision);
  Result r;
  r.backend = toString(options.backend);
  r.precision = toString(options.precision);
  r.iterations = parameters.solverIterations;
  r.particles = simulation.stepper().size();
  r.steps = steps;
  r.neighbors = std::to_string(bodies) + " bod" + (bodies == 1 ? "y" : "ies") +
    (outflowY > 0 ? ", outflow" : "");
  r.device = simulation.stepper().description();
  simulation.advance(static_cast<std::uint64_t>(warmup));
  r.setupSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - setup0).count();
  std::vector<double> ms;
  for (int s = 0; s < steps; ++s)
  {
    const auto t0 = std::chrono::steady_clock::now();
    simulation.advance(1);
    ms.push_back(
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  summarize(ms, simulation.stepper(), r);
  if (outflowY > 0)
  {
    std::printf("# outflow at y = %g m: %llu particles left over the %d warm-up and %d timed steps\n",
      outflowY, static_cast<unsigned long long>(simulation.removedCount()), warmup, steps);
  }
  return r;
}

std::string quoted(const std::string& text)
{
  std::string out = "\"";
  for (char c : text)
  {
    if (c == '"' || c == '\\')
    {
      out += '\\';
    }
    out += c;
  }
  return out + "\"";
}

std::string toJson(const std::vector<Result>& results, const std::string& label)
{
  std::ostringstream out;
  out.precision(9);
  out << "{\n  \"tool\": \"pbf_bench\",\n  \"label\": " << quoted(label)
      << ",\n  \"scene\": \"dam_break widened in x and z to the particle count\",\n  \"runs\": [\n";
  for (std::size_t i = 0; i < results.size(); ++i)
  {
    const Result& r = results[i];
    out << "    {\"backend\": " << quoted(r.backend) << ", \"precision\": " << quoted(r.precision)
        << ", \"device\": " << quoted(r.device) << ", \"neighbors\": " << quoted(r.neighbors)
        << ", \"skin\": " << r.skin << ", \"graphs\": " << (r.graphs ? "true" : "false") << ", \"block\": " << r.block
        << ", \"iterations\": " << r.iterations << ",\n     \"particles\": " << r.particles
        << ", \"steps\": " << r.steps << ", \"median_ms\": " << r.medianMs
        << ", \"p10_ms\": " << r.p10Ms << ", \"p90_ms\": " << r.p90Ms
        << ", \"steps_per_second\": " << r.stepsPerSecond
        << ",\n     \"average_neighbors\": " << r.averageNeighbors
        << ", \"average_density_error\": " << r.averageDensityError
        << ", \"max_density_error\": " << r.maxDensityError
        << ", \"finite\": " << (r.finite ? "true" : "false")
        << ",\n     \"device_bytes_per_particle\": " << r.bytesPerParticle
        << ", \"device_bytes\": " << r.deviceBytes
        << ", \"mask_builds_per_step\": " << r.maskBuildsPerStep
        << ", \"setup_seconds\": " << r.setupSeconds << "}"
        << (i + 1 < results.size() ? ",\n" : "\n");
  }
  out << "  ]\n}\n";
  return out.str();
}

void printRow(const Result& r)
{
  std::printf("%-7s %-6s %-5s %10zu %6d %10.3f %10.3f %10.3f %9.1f %7.2f %8.3f %8.3f %7.1f %6.2f%s\n",
    r.backend.c_str(), r.precision.c_str(), r.neighbors.c_str(), r.particles, r.steps, r.medianMs,
    r.p10Ms, r.p90Ms, r.stepsPerSecond, r.averageNeighbors, 100 * r.averageDensityError,
    100 * r.maxDensityError, r.bytesPerParticle, r.maskBuildsPerStep, r.finite ? "" : "  NON-FINITE");
  std::fflush(stdout);
}

std::vector<double> parseCounts(const std::string& text)
{
  if (text == "default")
  {
    return { 16e3, 32e3, 64e3, 128e3, 256e3, 512e3, 1e6, 2e6, 4e6, 8e6, 16e6 };
  }
  std::vector<double> counts;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ','))
  {
    std::size_t used = 0;
    double value = 0;
    try
    {
      value = std::stod(item, &used);
    }
    catch (const std::exception&)
    {
      used = 0;
    }
    if (used != item.size() || !(value >= 1 && value < 2.1e9))
    {
      throw InvalidInput("--sweep item \"" + item + "\": must be a particle count");
    }
    counts.push_back(value);
  }
  return counts;
}

} // namespace

// Each benchmark's own options are refused by the other, not ignored: a measurement must not
// silently be of something else than the command says.
void refuseTheOtherBenchmarksOptions(const ToolOptions& options, bool refined)
{
  const std::vector<std::string> widenedOnly = { "particles", "sweep", "steps", "warmup",
    "neighbors", "skin", "graphs", "block", "solid", "bodies", "outflow", "liquids", "json",
    "label" };
  const std::vector<std::string> refinedOnly = { "until", "frame", "modes", "csv" };
  for (const std::string& key : refined ? widenedOnly : refinedOnly)
  {
    if (options.extra.count(key))
    {
      throw InvalidInput("--" + key + " applies to " +
        (refined ? std::string("the widened dam break, not to --refined") : "--refined only") +
        (key == "graphs" ? " (with --refined, PBF_CUDA_GRAPHS=0 launches the kernels one by one)"
                         : ""));
    }
  }
}

// --refined: the scene refined to each spacing, in each mode, frame by frame; the table printed.
int runRefinedTable(const ToolOptions& options)
{
  const RefinedSettings settings = refinedSettings(options);
  const Scene scene = toolScene(options);
  std::vector<RefinedRun> runs;
  for (double spacing : settings.spacings)
  {
    for (const std::string& mode : settings.modes)
    {
      runs.push_back(runRefined(options, scene, spacing, mode, settings));
    }
  }
  return printRefinedTable(runs, settings.frameInterval) ? 0 : 1;
}

namespace
{

// The tool's own keys, beside the Parameters fields and --backend, --precision, --scene.
std::map<std::string, std::string> benchKeys()
{
  return {
    { "particles", "particle count of the scaled dam break (default 1e6)" },
    { "sweep", "comma-separated particle counts, or \"default\" (16k to 16M)" },
    { "steps", "timed steps per run (default 100)" },
    { "warmup", "untimed steps before timing (default 20)" },
    { "neighbors", "CUDA neighbour search: masks | walk (default masks)" },
    { "skin", "CUDA mask reach beyond h, fraction of h (default: cuda::Options::skin)" },
    { "graphs", "CUDA: 1 replays a step as one graph, 0 launches kernels (default 1)" },
    { "block", "CUDA: threads per block of the neighbour passes (default 128)" },
    { "json", "write the results to this JSON file" },
    { "label", "free text stored in the JSON" },
    { "refined", "comma-separated spacings [m]: time the scene (--scene, default dam_break) "
                 "refined, frame by frame, instead of the widened dam break" },
    { "until", "--refined: simulated time [s] (default 2)" },
    { "frame", "--refined: frame interval [s] (default 1/60)" },
    { "modes", "--refined: comma-separated of fixed, fixed4, defaults (default all three)" },
    { "csv", "--refined: a folder for one CSV of frames per run" },
    { "liquids", "1 (default) or 2: the column as water under oil (what several liquids cost)" },
    { "bodies", "N >= 0: run through Simulation with N floating boxes in the surge's way (what "
                "bodies cost; the loads read back every step), instead of the bare stepper" },
    { "outflow", "Y [m]: through Simulation as --bodies, with an outflow strip at height Y "
                 "along the -x wall that the column falls through (what removing costs)" },
    { "solid", "1: a sphere solid in the surge's way, 2: the MARIN box, 3: the sphere rolling "
               "at 1 m/s (what a solid costs; default 0: none)" },
  };
}

BenchSettings benchSettings(ToolOptions& options)
{
  auto extra = [&](const std::string& key, const std::string& fallback) {
    return options.extra.count(key) ? options.extra[key] : fallback;
  };
  BenchSettings b;
  b.counts = options.extra.count("sweep")
    ? parseCounts(options.extra["sweep"])
    : parseCounts(extra("particles", "1000000"));
  b.steps = std::stoi(extra("steps", "100"));
  b.warmup = std::stoi(extra("warmup", "20"));
  b.neighbors = extra("neighbors", "masks");
  if (b.neighbors != "masks" && b.neighbors != "walk")
  {
    throw InvalidInput("--neighbors = \"" + b.neighbors + "\": must be masks or walk");
  }
#ifdef PBF_WITH_CUDA
  const double defaultSkin = cuda::Options{}.skin; // the stepper's own default, not a copy
#else
  const double defaultSkin = 0; // no CUDA stepper to use it
#endif
  b.skin = options.extra.count("skin") ? std::stod(options.extra["skin"]) : defaultSkin;
  b.graphs = extra("graphs", "1") != "0";
  b.block = std::stoi(extra("block", "128"));
  const std::string solid = extra("solid", "0");
  if (solid != "0" && solid != "1" && solid != "2" && solid != "3")
  {
    throw InvalidInput("--solid = " + solid + ": must be 0 (none), 1 (a sphere), 2 (a box) or 3 (a rolling sphere)");
  }
  if (b.steps < 1 || b.warmup < 0)
  {
    throw InvalidInput("--steps must be >= 1 and --warmup >= 0");
  }
  b.outflowY = std::stod(extra("outflow", "0"));
  if (options.extra.count("outflow") && !(b.outflowY > 0))
  {
    throw InvalidInput("--outflow = " + options.extra["outflow"] + ": must be a height > 0 [m]");
  }
  b.bodies = std::stoi(extra("bodies", b.outflowY > 0 ? "0" : "-1"));
  if (options.extra.count("bodies") && (b.bodies < 0 || solid != "0"))
  {
    throw InvalidInput("--bodies = " + options.extra["bodies"] +
      ": must be a count >= 0, and not with --solid");
  }

  b.liquids = std::stoi(extra("liquids", "1"));
  if (b.liquids != 1 && b.liquids != 2)
  {
    throw InvalidInput("--liquids = " + options.extra["liquids"] + ": must be 1 or 2");
  }
  b.solid = std::stoi(solid);
  return b;
}

void printHeader(const ToolOptions& options, const BenchSettings& settings)
{
  std::printf("pbf_bench: dam break widened to N particles, %d warm-up + %d timed steps; %s\n",
    settings.warmup, settings.steps, describe(options.parameters).c_str());
  std::printf("%-7s %-6s %-5s %10s %6s %10s %10s %10s %9s %7s %8s %8s %7s %6s\n", "backend",
    "prec", "nbrs", "particles", "steps", "median_ms", "p10_ms", "p90_ms", "steps/s",
    "nbrs", "avgErr%", "maxErr%", "B/part", "builds");
  std::fflush(stdout);
}

// --json FILE: the runs, with --label's text.
void writeJson(ToolOptions& options, const std::vector<Result>& results)
{
  std::ofstream out(options.extra["json"]);
  out << toJson(results, options.extra.count("label") ? options.extra["label"] : "");
  if (!out)
  {
    throw std::runtime_error("cannot write " + options.extra["json"]);
  }
}

} // namespace

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = benchKeys();
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const bool refined = options.extra.count("refined") > 0;
    refuseTheOtherBenchmarksOptions(options, refined);
    if (refined)
    {
      return runRefinedTable(options);
    }
    usePaperIterationsUnlessGiven(options);
    const BenchSettings settings = benchSettings(options);
    printHeader(options, settings);
    std::vector<Result> results;
    for (double count : settings.counts)
    {
      results.push_back(settings.bodies >= 0
          ? bodiesBenchmark(options, count, settings.warmup, settings.steps, settings.bodies,
              settings.outflowY)
          : benchmark(options, count, settings));
      printRow(results.back());
    }
    if (!results.empty())
    {
      std::printf("device: %s\n", results.front().device.c_str());
    }
    if (options.extra.count("json"))
    {
      writeJson(options, results);
    }
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_bench: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
