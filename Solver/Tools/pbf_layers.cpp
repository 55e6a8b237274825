// pbf_layers: two liquids in layers (Layers.h) at one or more spacings, to --until seconds: the
// interface's height and flatness, the share of particles on the wrong side, each liquid's mean
// height and compression, every --sample seconds. --lower and --upper give the liquids' rest
// densities (default water under oil, 1000 and 800; swap them for heavy over light).
// With --rayleigh-taylor 1 the heavier liquid (--upper) starts over the lighter (--lower) in a
// thin slab (--thickness) with the interface perturbed by --amplitude cos(k x): the mode's
// amplitude every --sample seconds and the growth rate fitted to it, against the inviscid
// sqrt(A k g) and the rate with the model's XSPH viscosity. The layers at rest run on --ranks
// decomposed ranks (as threads) too. Documentation/ValidationInterfaces.md has the figures.
#include "Layers.h"

#include "Distributed/RankReductions.h"
#include "Distributed/ThreadCluster.h"
#include "ToolOptions.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

namespace
{

// The ranks' particles as one state: what measureLayers reads of them.
Snapshot<double> joined(const std::vector<Snapshot<double>>& parts)
{
  Snapshot<double> all;
  for (const Snapshot<double>& part : parts)
  {
    all.id.insert(all.id.end(), part.id.begin(), part.id.end());
    all.position.insert(all.position.end(), part.position.begin(), part.position.end());
    all.density.insert(all.density.end(), part.density.begin(), part.density.end());
    all.liquid.insert(all.liquid.end(), part.liquid.begin(), part.liquid.end());
  }
  return all;
}

// The layers every `sample` seconds to `until`, printed by rank 0: each rank reads its own
// particles into parts[rank] (one rank: the whole state).
void sampleLayers(Simulation& simulation, distributed::Communicator* communicator, double s,
  double until, double sample, std::vector<Snapshot<double>>& parts)
{
  const auto start = std::chrono::steady_clock::now();
  const int rank = communicator ? communicator->rank() : 0;
  const int samples = static_cast<int>(std::lround(until / sample));
  for (int k = 0; k <= samples; ++k)
  {
    simulation.advanceTo(k * sample);
    simulation.stepper().read(parts[static_cast<std::size_t>(rank)]);
    if (communicator)
    {
      distributed::allGather(*communicator, { 0.0 }); // every part read
    }
    if (rank != 0)
    {
      continue;
    }
    const Snapshot<double> state = joined(parts);
    const LayerMeasure m = measureLayers(state, simulation.parameters());
    const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%.4g,%.3f,%zu,%.4f,%.3f,%.3f,%.4f,%.4f,%.3f,%.3f,%d,%.1f\n", s, k * sample,
      state.id.size(), m.interface, m.interfaceRms / s, 100 * m.wrongSide, m.meanHeight[0],
      m.meanHeight[1], 100 * m.compression[0], 100 * m.compression[1], m.columns, seconds);
    std::fflush(stdout);
  }
}

} // namespace

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "spacings", "comma-separated particle spacings [m] (default 0.02)" },
    { "lower", "the lower liquid's rest density [kg/m^3] (default 1000)" },
    { "upper", "the upper liquid's rest density [kg/m^3] (default 800)" },
    { "depth", "each layer's depth [m] (default 0.16)" },
    { "until", "simulated time [s] (default 5)" },
    { "sample", "sampling interval [s] (default 0.5; 0.02 with --rayleigh-taylor)" },
    { "rayleigh-taylor", "1: heavy over light, perturbed (default 0)" },
    { "amplitude", "Rayleigh-Taylor: the interface's perturbation [m] (default 0.01)" },
    { "thickness", "Rayleigh-Taylor: the slab's thickness [m] (default 4 spacings)" },
    { "ranks", "the layers on decomposed ranks, as threads (default 1: none)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const std::vector<double> spacings = toolReals(options, "spacings", 0.02);
    const double lower = toolReal(options, "lower", 1000.0);
    const double upper = toolReal(options, "upper", 800.0);
    const double depth = toolReal(options, "depth", 0.16);
    const double until = toolReal(options, "until", 5.0);
    const bool rayleighTaylor = toolInteger(options, "rayleigh-taylor", 0, 0) != 0;
    const double sample = toolReal(options, "sample", rayleighTaylor ? 0.02 : 0.5);
    if (rayleighTaylor)
    {
      const double amplitude = toolReal(options, "amplitude", 0.01);
      std::printf("spacing,particles,light,heavy,k,a0_m,fitted_a0_m,fitted,rate_1_s,inviscid_1_s,"
                  "viscous_1_s,error%%,nu_m2_s,seconds\n");
      for (double s : spacings)
      {
        Parameters p = options.parameters;
        p.particleSpacing = s;
        const double thickness = toolReal(options, "thickness", 4 * s);
        const auto start = std::chrono::steady_clock::now();
        const RayleighTaylorRun run = runRayleighTaylor(p, options.backend, options.precision,
          lower, upper, depth, thickness, amplitude, until, sample);
        const double g = length(p.gravity);
        const double inviscid = rayleighTaylorRate(lower, upper, run.k, g, 0.0);
        const double viscous = rayleighTaylorRate(lower, upper, run.k, g, run.nu);
        const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        for (std::size_t i = 0; i < run.t.size(); ++i)
        {
          std::printf("# t=%.3f a=%.5f\n", run.t[i], run.amplitude[i]);
        }
        std::printf("%.4g,%zu,%.0f,%.0f,%.3f,%.5f,%.5f,%d,%.3f,%.3f,%.3f,%+.1f,%.3g,%.1f\n", s,
          run.particles, lower, upper, run.k, run.amplitude0, run.fittedAmplitude0, run.fitted,
          run.rate, inviscid,
          viscous, 100 * (run.rate / viscous - 1), run.nu, seconds);
        std::fflush(stdout);
      }
      return 0;
    }
    std::printf("spacing,t,particles,interface_m,rms/s,wrong%%,height_lower_m,height_upper_m,"
                "compression_lower%%,compression_upper%%,columns,seconds\n");
    const int ranks = static_cast<int>(toolInteger(options, "ranks", 1, 1));
    for (double s : spacings)
    {
      Parameters p = options.parameters;
      p.particleSpacing = s;
      const Scene scene = layeredScene(lower, upper, depth);
      std::vector<Snapshot<double>> parts(static_cast<std::size_t>(ranks));
      if (ranks <= 1)
      {
        Simulation simulation(scene, p, options.backend, options.precision);
        sampleLayers(simulation, nullptr, s, until, sample, parts);
        continue;
      }
      distributed::runThreadCluster(ranks, [&](distributed::Communicator& communicator) {
        Simulation simulation(scene, p, options.backend, options.precision, &communicator);
        sampleLayers(simulation, &communicator, s, until, sample, parts);
      });
    }
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_layers: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
