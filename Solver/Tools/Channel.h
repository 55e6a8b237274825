// An open channel, the check of the open boundaries (Documentation/ValidationBoundaries.md, "Channel"): an
// inflow released by volume rate and an outflow that removes what reaches it. Once the stream
// has reached the outflow, the particles in the domain must hold steady and what leaves must
// balance what comes in.
#pragma once

#include "Simulation.h"

#include <cstdint>
#include <vector>

namespace pbf::validation
{

struct ChannelSample
{
  double time = 0;          // [s]
  std::size_t particles = 0; // over every rank
  std::uint64_t removed = 0; // through the outflows since t = 0
  std::int64_t released = 0; // ids given: the initial particles and every emitted one
};

// Sampled every `sample` seconds to `until`; the figures over the samples from `start` on.
struct ChannelRun
{
  std::vector<ChannelSample> samples;
  double mean = 0;        // particles
  double lowest = 0;      // min / mean - 1
  double highest = 0;     // max / mean - 1
  double inflow = 0;      // [m^3/s] released volume per second over [start, until]
  double outflow = 0;     // [m^3/s] removed volume per second over [start, until]
  double seconds = 0;     // wall clock
  std::uint64_t steps = 0;
};

// The scene with outflows and emitters run on `ranks` ranks (threads; 1: no decomposition).
ChannelRun runChannel(const Scene& scene, const Parameters& parameters, Backend backend,
  Precision precision, int ranks, double until, double start, double sample);

} // namespace pbf::validation
