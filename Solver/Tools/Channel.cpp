#include "Channel.h"

#include "Distributed/ThreadCluster.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace pbf::validation
{

namespace
{

// Every rank steps its share and samples the count of all (statistics() is collective); rank 0
// keeps the samples.
void sampleRun(Simulation& simulation, bool keep, double until, double sample,
  std::vector<ChannelSample>& samples, std::uint64_t& steps)
{
  const auto frames = static_cast<long>(std::llround(until / sample));
  for (long k = 0; k <= frames; ++k)
  {
    simulation.advanceTo(static_cast<double>(k) * sample);
    const Statistics s = simulation.stepper().statistics();
    if (keep)
    {
      samples.push_back({ simulation.time(), s.particles, simulation.removedCount(),
        simulation.idCount() });
    }
  }
  steps = simulation.stepCount();
}

} // namespace

ChannelRun runChannel(const Scene& scene, const Parameters& parameters, Backend backend,
  Precision precision, int ranks, double until, double start, double sample)
{
  if (scene.outflows.empty())
  {
    throw InvalidInput("scene \"" + scene.name + "\": a channel needs an outflow");
  }
  ChannelRun run;
  const auto begin = std::chrono::steady_clock::now();
  if (ranks <= 1)
  {
    Simulation simulation(scene, parameters, backend, precision);
    sampleRun(simulation, true, until, sample, run.samples, run.steps);
  }
  else
  {
    distributed::runThreadCluster(ranks, [&](distributed::Communicator& communicator) {
      std::vector<ChannelSample> mine;
      std::uint64_t steps = 0;
      Simulation simulation(scene, parameters, backend, precision, &communicator);
      sampleRun(simulation, communicator.rank() == 0, until, sample, mine, steps);
      if (communicator.rank() == 0)
      {
        run.samples = std::move(mine);
        run.steps = steps;
      }
    });
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();

  const ChannelSample* first = nullptr;
  double sum = 0, count = 0, low = INFINITY, high = 0;
  for (const ChannelSample& s : run.samples)
  {
    if (s.time + 1e-9 < start)
    {
      continue;
    }
    first = first ? first : &s;
    sum += static_cast<double>(s.particles);
    count += 1;
    low = std::min(low, static_cast<double>(s.particles));
    high = std::max(high, static_cast<double>(s.particles));
  }
  if (!first || count < 2)
  {
    throw InvalidInput("start = " + std::to_string(start) + ": fewer than two samples after it");
  }
  const ChannelSample& last = run.samples.back();
  run.mean = sum / count;
  run.lowest = low / run.mean - 1.0;
  run.highest = high / run.mean - 1.0;
  const double s = parameters.particleSpacing;
  const double volume = s * s * s; // a lattice site's
  const double span = last.time - first->time;
  run.inflow = static_cast<double>(last.released - first->released) * volume / span;
  run.outflow = static_cast<double>(last.removed - first->removed) * volume / span;
  return run;
}

} // namespace pbf::validation
