// pbf_bench_mpi: scaling of the domain-decomposed solver over MPI ranks. Run it under
// mpiexec; every rank builds the dam break scaled to the particle count (pbf_bench's scene), keeps
// its slab (Distributed/SubdomainStepper.h) and steps in lockstep with the others.
//
//   mpiexec -n N pbf_bench_mpi [--particles P | --per-rank P] [--steps S] [--warmup W]
//                              [--backend serial|openmp|cuda] [--precision single|double]
//                              [--json FILE]
//
// A step is timed from a barrier to a barrier, so it is the slowest rank's; with --backend cuda
// each rank runs the CUDA sub-domain stepper on the GPU of its local rank and waits for its GPU
// before the closing barrier. Ghost exchange and migration (with the cut) are timed inside the
// step on each rank and reported as the largest over the ranks. Medians and p10/p90 over the
// timed steps, warm-up excluded. Rank 0 prints one table row and, with --json, the run. Per rank
// (stderr and JSON; the CUDA stepper only): the medians of the step's time, of the host's wait
// for its own device's border fields and of its wait inside the refreshes' exchanges with the
// neighbours: the rank that waits least for its neighbours is the one that paces them.
#include "Backends.h"
#include "Distributed/MpiCommunicator.h"
#include "Distributed/SubdomainStepper.h"
#include "ScaledScenes.h"
#include "Scene.h"
#include "SceneFluid.h"
#include "ToolOptions.h"

#include <mpi.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

double percentile(std::vector<double> v, double q)
{
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(at));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

// Every rank's value, on rank 0 (elsewhere empty).
std::vector<double> gatherToRankZero(double mine, int ranks)
{
  std::vector<double> all(static_cast<std::size_t>(ranks), 0.0);
  MPI_Gather(&mine, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  return all;
}

std::string listed(const std::vector<double>& values)
{
  std::string text;
  char item[32];
  for (std::size_t r = 0; r < values.size(); ++r)
  {
    std::snprintf(item, sizeof item, "%s%.2f", r ? ", " : "", values[r]);
    text += item;
  }
  return text;
}

double largestOverRanks(double mine)
{
  double largest = 0;
  MPI_Allreduce(&mine, &largest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return largest;
}

// The step times of the timed steps, warm-up excluded [ms]: from barrier to barrier (the slowest
// rank's), the ghost exchange's and the migration's (largest over the ranks), and this rank's own.
struct StepTimes
{
  std::vector<double> ms, ghostMs, migrationMs, ownMs, deviceWaitMs, refreshWaitMs, beforeMs;
};

StepTimes timeSteps(distributed::DecomposedStepper& stepper, long warmup, long steps)
{
  StepTimes t;
  for (long s = 0; s < warmup + steps; ++s)
  {
    MPI_Barrier(MPI_COMM_WORLD);
    const auto start = std::chrono::steady_clock::now();
    stepper.step();
    stepper.synchronize(); // a GPU's queued work belongs to the step
    const double own =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    MPI_Barrier(MPI_COMM_WORLD);
    const double elapsed =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const double ghost = largestOverRanks(stepper.lastExchange().ghostMilliseconds);
    const double migration = largestOverRanks(stepper.lastExchange().migrationMilliseconds);
    if (s >= warmup)
    {
      t.ms.push_back(elapsed);
      t.ghostMs.push_back(ghost);
      t.migrationMs.push_back(migration);
      t.ownMs.push_back(own);
      t.deviceWaitMs.push_back(stepper.lastExchange().deviceWaitMilliseconds);
      t.refreshWaitMs.push_back(stepper.lastExchange().refreshWaitMilliseconds);
      t.beforeMs.push_back(stepper.lastExchange().beforePassesMilliseconds);
    }
  }
  return t;
}

// Every rank's medians and memory, on rank 0 (elsewhere empty).
struct RankMeasures
{
  std::vector<double> own, deviceWait, refreshWait, before, peakHost, deviceBytes, hostBytes;
};

RankMeasures gatherPerRank(
  const distributed::DecomposedStepper& stepper, const StepTimes& t, int ranks)
{
  RankMeasures p;
  p.own = gatherToRankZero(percentile(t.ownMs, 0.5), ranks);
  p.deviceWait = gatherToRankZero(percentile(t.deviceWaitMs, 0.5), ranks);
  p.refreshWait = gatherToRankZero(percentile(t.refreshWaitMs, 0.5), ranks);
  p.before = gatherToRankZero(percentile(t.beforeMs, 0.5), ranks);
  // The host memory each rank's process has held at its peak (setup included) [MB].
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  p.peakHost = gatherToRankZero(static_cast<double>(usage.ru_maxrss) / 1024.0, ranks);
  // Device bytes per particle on each rank: all it holds on its GPU over the particles it owns.
  p.deviceBytes = gatherToRankZero(static_cast<double>(stepper.deviceBytes()) /
      static_cast<double>(std::max<std::size_t>(stepper.size(), 1)),
    ranks);
  // Host bytes per particle on each rank: the particle arrays of a CPU rank (their capacities).
  p.hostBytes = gatherToRankZero(static_cast<double>(stepper.hostBytes()) /
      static_cast<double>(std::max<std::size_t>(stepper.size(), 1)),
    ranks);
  return p;
}

// What rank 0 reports of the run.
struct RunSummary
{
  int ranks = 0;
  long steps = 0;
  std::size_t particles = 0;
  double setupSeconds = 0;
  double ghosts = 0; // the most ghosts of a rank in the last step
  std::vector<std::uint64_t> particlesPerRank;
  bool finite = true;
};

// The per-rank lines on stderr, and the table's row on stdout.
void printRun(const ToolOptions& options, const distributed::DecomposedStepper& stepper,
  const RunSummary& run, const StepTimes& t, const RankMeasures& p)
{
  const auto [fewest, most] =
    std::minmax_element(run.particlesPerRank.begin(), run.particlesPerRank.end());
  const double median = percentile(t.ms, 0.5);
  std::fprintf(stderr, "setup (scene, constructor, first evaluation) %.1f s on the slowest rank; "
    "%s\n", run.setupSeconds, stepper.description().c_str());
  std::fprintf(stderr, "per rank, medians in ms: own step (to its device's end) [%s]; waiting for "
    "its device's border fields [%s]; in the refreshes' exchanges [%s]; from the step's start to "
    "the passes [%s]\n",
    listed(p.own).c_str(), listed(p.deviceWait).c_str(),
    listed(p.refreshWait).c_str(), listed(p.before).c_str());
  std::fprintf(stderr, "peak host memory per rank [MB]: [%s]\n", listed(p.peakHost).c_str());
  std::fprintf(stderr, "device bytes per particle per rank: [%s]; host (particle arrays): [%s]\n",
    listed(p.deviceBytes).c_str(), listed(p.hostBytes).c_str());
  std::printf("| ranks | backend | precision | particles | ms/step median (p10-p90) | steps/s | "
              "ghost ms | migration ms | particles per rank (min-max) | ghosts (max) | finite |\n");
  std::printf("| %d | %s | %s | %zu | %.2f (%.2f-%.2f) | %.1f | %.2f | %.2f | %llu-%llu | %.0f | "
              "%s |\n",
    run.ranks, toString(options.backend), toString(options.precision), run.particles,
    median, percentile(t.ms, 0.1), percentile(t.ms, 0.9), 1000.0 / median,
    percentile(t.ghostMs, 0.5), percentile(t.migrationMs, 0.5),
    static_cast<unsigned long long>(*fewest), static_cast<unsigned long long>(*most), run.ghosts,
    run.finite ? "yes" : "NO");
  std::fflush(stdout);
}

// --json FILE: the run as one JSON object.
void writeRunJson(const std::string& path, const ToolOptions& options, const RunSummary& run,
  const StepTimes& t, const RankMeasures& p)
{
  std::ofstream out(path);
  out << "{ \"ranks\": " << run.ranks << ", \"backend\": \"" << toString(options.backend)
      << "\", \"precision\": \"" << toString(options.precision)
      << "\", \"particles\": " << run.particles << ", \"steps\": " << run.steps
      << ", \"median_ms\": " << percentile(t.ms, 0.5) << ", \"p10_ms\": " << percentile(t.ms, 0.1)
      << ", \"p90_ms\": " << percentile(t.ms, 0.9)
      << ", \"ghost_ms\": " << percentile(t.ghostMs, 0.5)
      << ", \"migration_ms\": " << percentile(t.migrationMs, 0.5)
      << ", \"ghosts_max\": " << run.ghosts
      << ", \"setup_s\": " << run.setupSeconds << ", \"own_ms_per_rank\": [" << listed(p.own)
      << "], \"device_wait_ms_per_rank\": [" << listed(p.deviceWait)
      << "], \"refresh_wait_ms_per_rank\": [" << listed(p.refreshWait)
      << "], \"before_passes_ms_per_rank\": [" << listed(p.before)
      << "], \"peak_host_mb_per_rank\": [" << listed(p.peakHost)
      << "], \"device_bytes_per_particle_per_rank\": [" << listed(p.deviceBytes)
      << "], \"host_bytes_per_particle_per_rank\": [" << listed(p.hostBytes)
      << "], \"particles_per_rank\": [";
  for (std::size_t r = 0; r < run.particlesPerRank.size(); ++r)
  {
    out << (r ? ", " : "") << run.particlesPerRank[r];
  }
  out << "] }\n";
}

template <class Real>
int run(const ToolOptions& options, distributed::MpiCommunicator& communicator)
{
  RunSummary summary;
  summary.ranks = communicator.size();
  summary.steps = toolInteger(options, "steps", 20, 1);
  const long warmup = toolInteger(options, "warmup", 3, 0);
  const double particles = options.extra.count("per-rank")
    ? static_cast<double>(toolInteger(options, "per-rank", 100000, 1)) * summary.ranks
    : static_cast<double>(toolInteger(options, "particles", 200000, 1));
  const Scene scene = scaledDamBreak(particles, options.parameters.particleSpacing);
  const Parameters parameters = withSceneDomain(options.parameters, scene);
  checkSceneSize(scene, parameters);
  // Each rank generates only its slab of the scene (SceneFluid.h); the setup time includes it.
  const auto setupStart = std::chrono::steady_clock::now();
  const SceneFluid fluid(scene, parameters);
  const std::unique_ptr<Stepper> owner = distributed::makeSubdomainStepper(
    communicator, options.backend, options.precision, parameters, fluid);
  auto& stepper = dynamic_cast<distributed::DecomposedStepper&>(*owner);
  stepper.synchronize();
  summary.setupSeconds = largestOverRanks(
    std::chrono::duration<double>(std::chrono::steady_clock::now() - setupStart).count());

  const StepTimes times = timeSteps(stepper, warmup, summary.steps);
  summary.particlesPerRank = stepper.particlesPerRank();
  const Statistics statistics = stepper.statistics();
  summary.finite = statistics.finite;
  summary.ghosts = largestOverRanks(static_cast<double>(stepper.lastExchange().ghosts));
  const RankMeasures measures = gatherPerRank(stepper, times, summary.ranks);
  summary.particles = fluid.size();
  if (communicator.rank() != 0)
  {
    return 0;
  }
  printRun(options, stepper, summary, times, measures);
  if (options.extra.count("json"))
  {
    writeRunJson(options.extra.at("json"), options, summary, times, measures);
  }
  return summary.finite ? 0 : 1;
}

} // namespace

int main(int argc, char** argv)
{
  MPI_Init(&argc, &argv);
  int status = 0;
  try
  {
    const std::map<std::string, std::string> keys = {
      { "particles", "particles in all (default 200000)" },
      { "per-rank", "particles per rank instead (weak scaling)" },
      { "steps", "timed steps (default 20)" },
      { "warmup", "steps before timing (default 3)" },
      { "json", "write the run to this file (rank 0)" },
    };
    ToolOptions options = parseToolOptions(argc, argv, keys);
    usePaperIterationsUnlessGiven(options);
    distributed::MpiCommunicator communicator;
    status = options.precision == Precision::Double ? run<double>(options, communicator)
                                                    : run<float>(options, communicator);
  }
  catch (const std::exception& error)
  {
    std::fprintf(stderr, "pbf_bench_mpi: %s\n", error.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  MPI_Finalize();
  return status;
}
