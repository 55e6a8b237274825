// The floating sphere of Kramer et al. (2021, Energies 14(2) 269; Testing/Validation/kramer_*.csv,
// the set-up in Testing/Validation/README.md): a sphere of D = 0.300 m and 7.056 kg, half under
// water at rest, held above its rest position and let go; its free heave decays as it radiates
// waves. The scene: a square tank of water 0.9 m deep (by default 2.4 m a side, so that the waves
// the sphere sends out, about 0.6 m/s, come back from the walls after the compared window), the
// sphere at its middle on a vertical guide (heave only: "degreesOfFreedom": ["y"]), held while the
// water settles from its lattice (kKramerHold) and released from rest.
#pragma once

#include "Marin.h"
#include "Simulation.h"

#include <string>
#include <vector>

namespace pbf::validation
{

constexpr double kKramerDiameter = 0.300;   // [m]
constexpr double kKramerMass = 7.056;       // [kg]
constexpr double kKramerWater = 998.2;      // the basin's water [kg/m^3]
constexpr double kKramerGravity = 9.82;     // [m/s^2]
constexpr double kKramerHold = 0.5;         // the water settles this long before the release [s]

struct KramerTank
{
  double side = 2.4;  // [m], square
  double depth = 0.9; // the water's [m]
};

// The scene with the sphere's centre at `centre` [m] above the floor, held until kKramerHold,
// at the basin's density and gravity (set in `parameters`).
Scene kramerScene(const KramerTank& tank, double centre);
Parameters kramerParameters(Parameters parameters);

struct KramerRun
{
  double spacing = 0, start = 0; // the centre's height at the release [m]
  std::size_t particles = 0;
  TimeSeries centre; // the sphere's centre's height from the release [s], [m]
};

// The sphere held with its centre at `start` [m], let go at kKramerHold, sampled every `sample`
// seconds to `window` seconds after the release.
KramerRun runKramer(const Parameters& parameters, Backend backend, Precision precision,
  const KramerTank& tank, double start, double window, double sample);

// Where a run let go at its rest settles: its centre's mean height over the second half of its
// window [m].
double settledCentre(const KramerRun& run);

// How many particles a run with the sphere's centre at `start` has: the water's volume, which
// sets the level the sphere floats at.
std::size_t kramerParticles(const Parameters& parameters, const KramerTank& tank, double start);

// Where the floating sphere rests in a run of `particles`, from a run let go at its rest
// (`settled`: the mean height of its centre over the second half of its window, `settledParticles`
// its particles): the same plus the level's rise by the water the sphere displaced less at the
// start of this run [m].
double kramerRest(const KramerTank& tank, double spacing, double settled,
  std::size_t settledParticles, std::size_t particles);

// A heave against the record: the first three periods of each (from the first crossing of zero,
// the time to the third, the third to the fifth, the fifth to the seventh; NaN where the window
// ends first) and the RMS of their difference over the window, both from the release.
struct KramerComparison
{
  double period[3], recordPeriod[3];
  double rms = 0; // [m]
};
KramerComparison compareKramer(const TimeSeries& heave, const TimeSeries& record, double window);

// The record's heave from its release (t >= 0), from a kramer_2021_sphere_*.csv.
TimeSeries readKramerRecord(const std::string& csvPath);

} // namespace pbf::validation
