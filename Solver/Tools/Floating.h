// Bodies in still water, the checks of a floating or sinking body (Documentation/ValidationBoundaries.md,
// "Loads and floating bodies"): a 0.2 x 0.16 x 0.2 m box of relative density r (to the water's)
// let go in the middle of a 0.6 x 0.7 x 0.6 m tank of water 0.4 m deep, and its heave over time
// against the free surface away from it.
#pragma once

#include "Marin.h"
#include "Simulation.h"

#include <string>
#include <vector>

namespace pbf::validation
{

constexpr double kFloatingHeight = 0.16; // the box's [m]
constexpr double kFloatingDepth = 0.4;   // the water's at rest [m]

// The box's start: r < 1 at Archimedes' draft r H below the water's surface; r = 1 wholly under
// water, its centre at half the depth; r > 1 half in the water.
Scene floatingScene(double relative);

// A pushed body: at this time, when the water has settled from its lattice, the box is given a
// downward speed (FloatingRun::kick) and let go.
constexpr double kKickTime = 1.0; // [s]

struct FloatingRun
{
  double spacing = 0, relative = 0, kick = 0;
  std::size_t particles = 0;
  TimeSeries draft;   // the water's surface (a gauge in a corner) less the box's bottom [m]
  TimeSeries centre;  // the box's centre of mass, height [m]
  TimeSeries speed;   // the box's vertical velocity [m/s]
  // The whole system's mechanical energy: the particles' kinetic and potential (m g y), and the
  // box's (translation, rotation, M g y) [J].
  TimeSeries energy;
  double mass = 0;    // the box's [kg]
};

// The scene at parameters' spacing to `until`, sampled every `sample` seconds; with kick > 0 the
// box is given kick [m/s] downwards at kKickTime.
FloatingRun runFloating(const Parameters& parameters, Backend backend, Precision precision,
  double relative, double kick, double until, double sample);

// After the kick, against the same run without it (`still`, which the kicked run follows bit for
// bit until the kick): the kick's energy (1/2 M kick^2), how often the box crossed its draft (the
// centre's mean over the last quarter), and the excess of the system's energy over the still
// run's: its largest rise above its lowest so far, and what is left at the end [J].
struct KickResponse
{
  double kickEnergy = 0, worstRise = 0, left = 0;
  int crossings = 0;
};
KickResponse kickResponse(const FloatingRun& run, const FloatingRun& still);

// The mean of a series over [from, to].
double meanOver(const TimeSeries& series, double from, double to);


} // namespace pbf::validation
