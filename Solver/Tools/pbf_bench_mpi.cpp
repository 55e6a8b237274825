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

template <class Real>
int run(const ToolOptions& options, distributed::MpiCommunicator& communicator)
{
  const int ranks = communicator.size();
  const long steps = toolInteger(options, "steps", 20, 1);
  const long warmup = toolInteger(options, "warmup", 3, 0);
  const double particles = options.extra.count("per-rank")
    ? static_cast<double>(toolInteger(options, "per-rank", 100000, 1)) * ranks
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
  const double setupSeconds = largestOverRanks(
    std::chrono::duration<double>(std::chrono::steady_clock::now() - setupStart).count());

  std::vector<double> ms, ghostMs, migrationMs, ownMs, deviceWaitMs, refreshWaitMs, beforeMs;
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
      ms.push_back(elapsed);
      ghostMs.push_back(ghost);
      migrationMs.push_back(migration);
      ownMs.push_back(own);
      deviceWaitMs.push_back(stepper.lastExchange().deviceWaitMilliseconds);
      refreshWaitMs.push_back(stepper.lastExchange().refreshWaitMilliseconds);
      beforeMs.push_back(stepper.lastExchange().beforePassesMilliseconds);
    }
  }
  const std::vector<std::uint64_t> perRank = stepper.particlesPerRank();
  const Statistics statistics = stepper.statistics();
  const double ghosts = largestOverRanks(static_cast<double>(stepper.lastExchange().ghosts));
  const std::vector<double> ownPerRank = gatherToRankZero(percentile(ownMs, 0.5), ranks);
  const std::vector<double> deviceWaitPerRank =
    gatherToRankZero(percentile(deviceWaitMs, 0.5), ranks);
  const std::vector<double> refreshWaitPerRank =
    gatherToRankZero(percentile(refreshWaitMs, 0.5), ranks);
  const std::vector<double> beforePerRank = gatherToRankZero(percentile(beforeMs, 0.5), ranks);
  // The host memory each rank's process has held at its peak (setup included) [MB].
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const std::vector<double> peakHostPerRank =
    gatherToRankZero(static_cast<double>(usage.ru_maxrss) / 1024.0, ranks);
  const std::size_t particleCount = fluid.size();
  // Device bytes per particle on each rank: all it holds on its GPU over the particles it owns.
  const std::vector<double> deviceBytesPerRank =
    gatherToRankZero(static_cast<double>(stepper.deviceBytes()) /
        static_cast<double>(std::max<std::size_t>(stepper.size(), 1)),
      ranks);
  // Host bytes per particle on each rank: the particle arrays of a CPU rank (their capacities).
  const std::vector<double> hostBytesPerRank =
    gatherToRankZero(static_cast<double>(stepper.hostBytes()) /
        static_cast<double>(std::max<std::size_t>(stepper.size(), 1)),
      ranks);
  if (communicator.rank() != 0)
  {
    return 0;
  }
  const auto [fewest, most] = std::minmax_element(perRank.begin(), perRank.end());
  const double median = percentile(ms, 0.5);
  std::fprintf(stderr, "setup (scene, constructor, first evaluation) %.1f s on the slowest rank; "
    "%s\n", setupSeconds, stepper.description().c_str());
  std::fprintf(stderr, "per rank, medians in ms: own step (to its device's end) [%s]; waiting for "
    "its device's border fields [%s]; in the refreshes' exchanges [%s]; from the step's start to "
    "the passes [%s]\n",
    listed(ownPerRank).c_str(), listed(deviceWaitPerRank).c_str(),
    listed(refreshWaitPerRank).c_str(), listed(beforePerRank).c_str());
  std::fprintf(stderr, "peak host memory per rank [MB]: [%s]\n", listed(peakHostPerRank).c_str());
  std::fprintf(stderr, "device bytes per particle per rank: [%s]; host (particle arrays): [%s]\n",
    listed(deviceBytesPerRank).c_str(), listed(hostBytesPerRank).c_str());
  std::printf("| ranks | backend | precision | particles | ms/step median (p10-p90) | steps/s | "
              "ghost ms | migration ms | particles per rank (min-max) | ghosts (max) | finite |\n");
  std::printf("| %d | %s | %s | %zu | %.2f (%.2f-%.2f) | %.1f | %.2f | %.2f | %llu-%llu | %.0f | "
              "%s |\n",
    ranks, toString(options.backend), toString(options.precision), particleCount,
    median, percentile(ms, 0.1), percentile(ms, 0.9), 1000.0 / median, percentile(ghostMs, 0.5),
    percentile(migrationMs, 0.5), static_cast<unsigned long long>(*fewest),
    static_cast<unsigned long long>(*most), ghosts, statistics.finite ? "yes" : "NO");
  std::fflush(stdout);
  if (options.extra.count("json"))
  {
    std::ofstream out(options.extra.at("json"));
    out << "{ \"ranks\": " << ranks << ", \"backend\": \"" << toString(options.backend)
        << "\", \"precision\": \"" << toString(options.precision)
        << "\", \"particles\": " << particleCount << ", \"steps\": " << steps
        << ", \"median_ms\": " << median << ", \"p10_ms\": " << percentile(ms, 0.1)
        << ", \"p90_ms\": " << percentile(ms, 0.9)
        << ", \"ghost_ms\": " << percentile(ghostMs, 0.5)
        << ", \"migration_ms\": " << percentile(migrationMs, 0.5) << ", \"ghosts_max\": " << ghosts
        << ", \"setup_s\": " << setupSeconds << ", \"own_ms_per_rank\": [" << listed(ownPerRank)
        << "], \"device_wait_ms_per_rank\": [" << listed(deviceWaitPerRank)
        << "], \"refresh_wait_ms_per_rank\": [" << listed(refreshWaitPerRank)
        << "], \"before_passes_ms_per_rank\": [" << listed(beforePerRank)
        << "], \"peak_host_mb_per_rank\": [" << listed(peakHostPerRank)
        << "], \"device_bytes_per_particle_per_rank\": [" << listed(deviceBytesPerRank)
        << "], \"host_bytes_per_particle_per_rank\": [" << listed(hostBytesPerRank)
        << "], \"particles_per_rank\": [";
    for (std::size_t r = 0; r < perRank.size(); ++r)
    {
      out << (r ? ", " : "") << perRank[r];
    }
    out << "] }\n";
  }
  return statistics.finite ? 0 : 1;
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
