// pbf_pair_census: what each structure of a neighbour pass would cost on a real state, counted
// (PairCensus.h). The state is pbf_bench's after its warm-up (the widened dam break of N
// particles, --particles, after --warmup steps) or, with --refined S, the dam_break preset at
// spacing S simulated to --until (the scene users run, mid-flow). Prints one table: lane slots per
// particle and pass for the row masks the CUDA backend walks and for cluster-pair tiles.
#include "PairCensus.h"
#include "ScaledScenes.h"
#include "Simulation.h"
#include "ToolOptions.h"

#include <cstdio>
#include <iostream>

using namespace pbf;

namespace
{

std::vector<Vec3d> positionsOf(const Stepper& stepper)
{
  Snapshot<double> snapshot;
  stepper.read(snapshot);
  return snapshot.position;
}

} // namespace

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "particles", "the widened dam break's particle count (default 1000000)" },
    { "warmup", "steps before the count (default 20, as pbf_bench)" },
    { "refined", "count the dam_break preset at this spacing [m] instead" },
    { "until", "with --refined: simulated time of the count [s] (default 0.5)" },
    { "skin", "the masks' and pair lists' margin beyond h, in h (default 0.075, the CUDA default)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const double skin = toolReal(options, "skin", 0.075);
    std::vector<Vec3d> position;
    Parameters parameters;
    std::string state;
    if (options.extra.count("refined"))
    {
      parameters = options.parameters;
      parameters.particleSpacing = toolReal(options, "refined", 0.01);
      const double until = toolReal(options, "until", 0.5);
      Simulation simulation(toolScene(options), parameters, options.backend, options.precision);
      simulation.advanceTo(until);
      parameters = simulation.parameters();
      position = positionsOf(simulation.stepper());
      state = options.scene + " at s = " + std::to_string(parameters.particleSpacing) +
        " m, t = " + std::to_string(until) + " s";
    }
    else
    {
      usePaperIterationsUnlessGiven(options);
      const double particles = toolReal(options, "particles", 1e6);
      const long warmup = toolInteger(options, "warmup", 20, 0);
      const Scene scene = scaledDamBreak(particles, options.parameters.particleSpacing);
      parameters = withSceneDomain(options.parameters, scene);
      auto stepper =
        makeStepper(options.backend, options.precision, parameters, fillScene(scene, parameters));
      for (long s = 0; s < warmup; ++s)
      {
        stepper->step();
      }
      position = positionsOf(*stepper);
      state = "the benchmark's widened dam break after " + std::to_string(warmup) + " steps";
    }
    const double h = parameters.smoothingLength();
    const CellSortedParticles sorted =
      sortByCell(position, makeGridGeometry<double>(parameters.domain, h));
    const PairCensus c = countPairs(sorted, h, skin * h, { { 8, 8 }, { 8, 4 }, { 4, 4 } });
    std::printf("state: %s, %zu particles, h = %.4g m, skin %.3g h\n", state.c_str(),
      c.particles, h, skin);
    std::printf("per particle: %.2f candidates within h (itself included), %.2f in the 27 cells, "
                "%.2f visited by the masks\n",
      c.withinH, c.cellWalk, c.maskVisits);
    std::printf("%-36s %14s %14s %10s\n", "structure", "slots/particle", "pair-once", "hits");
    std::printf("%-36s %14.2f %14s %9.1f%%\n", "27-cell walk, a lane per particle", c.cellWalkSlots,
      "-", 100.0 * c.withinH / c.cellWalkSlots);
    std::printf("%-36s %14.2f %14.2f %9.1f%%\n", "row masks, a lane per particle (now)",
      c.maskSlots, c.maskOnceSlots, 100.0 * c.maskHitFraction);
    for (const ClusterPairCensus& k : c.clusters)
    {
      char name[64];
      std::snprintf(name, sizeof name, "cluster pairs %dx%d (%.1f j per i)", k.shape.i, k.shape.j,
        k.clusterPairsPerCluster);
      char once[32] = "-";
      if (k.slotsOncePerParticle > 0)
      {
        std::snprintf(once, sizeof once, "%.2f", k.slotsOncePerParticle);
      }
      std::printf("%-36s %14.2f %14s %9.1f%%\n", name, k.slotsPerParticle, once,
        100.0 * k.hitFraction);
    }
    return 0;
  }
  catch (const std::exception& e)
  {
    std::cerr << "pbf_pair_census: " << e.what() << '\n';
    return 1;
  }
}
