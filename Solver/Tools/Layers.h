// Two liquids in a tank, the checks of several liquids (Documentation/ValidationInterfaces.md, "Several
// liquids"): water under oil at rest, whose interface must stay flat and whose liquids must stay
// apart, and the same layers turned over (heavy on light), which must change places.
#pragma once

#include "Simulation.h"

#include <vector>

namespace pbf::validation
{

// The tank: 0.4 m long (x), 0.5 m high, 0.16 m across (z); each layer is `depth` deep.
constexpr double kLayerTankLength = 0.4, kLayerTankHeight = 0.5, kLayerTankWidth = 0.16;

// Liquid 0 ("lower", rho 0) fills [0, depth] and liquid 1 ("upper", rho 1) [depth, 2 depth].
Scene layeredScene(double lowerDensity, double upperDensity, double depth);

// Where the two liquids of a state meet, measured in columns one spacing wide along x and z. In
// each column that holds both, the interface is the height below which lie as many particles as
// the column holds of liquid 0, the one that starts below (midway between that particle and the
// next): for layers that have not mixed, midway between liquid 0's top and liquid 1's bottom.
struct LayerMeasure
{
  double interface = 0;    // the columns' mean interface height [m]
  double interfaceRms = 0; // the RMS of the columns' interface heights about their mean [m]
  double wrongSide = 0;    // the share of particles on the other liquid's side of their column's
  // Each column's (x, interface height, z) [m].
  std::vector<Vec3d> levels;
  int columns = 0;         // columns that hold both liquids
  // Per liquid: the mean height [m] and the mean compression max(rho_i / rho_l - 1, 0), from the
  // state's densities (each in its liquid's units).
  double meanHeight[2] = { 0, 0 };
  double compression[2] = { 0, 0 };
  std::size_t particles[2] = { 0, 0 };
};
LayerMeasure measureLayers(const Snapshot<double>& state, const Parameters& parameters);

// Rayleigh-Taylor: the heavier liquid over the lighter in a thin slab, 0.4 m long (x), two
// layers `depth` deep (x from 0 to kRayleighTaylorLength), `thickness` across (z), the interface
// at depth + amplitude cos(k x), k = 2 pi / kRayleighTaylorLength. The scene gives the domain and
// the liquids ("light" 0, below; "heavy" 1, above); the particles come from rayleighTaylorFluid.
constexpr double kRayleighTaylorLength = 0.4;
Scene rayleighTaylorScene(double light, double heavy, double depth, double thickness);
ParticleBatch rayleighTaylorFluid(
  const Scene& scene, const Parameters& parameters, double depth, double amplitude);

// The interface's cosine mode of wave number k: 2 / N sum over columns of (y_c - mean) cos(k x_c)
// [m].
double modeAmplitude(const LayerMeasure& m, double k);

// The linear growth rate n of Rayleigh-Taylor for these densities and wave number, with the
// liquids' kinematic viscosity nu [m^2/s] (equal in both): n = sqrt(A k g + nu^2 k^4) - nu k^2,
// A = (heavy - light) / (heavy + light) (the layers deep against 1 / k).
double rayleighTaylorRate(double light, double heavy, double k, double g, double nu);

// A run of rayleighTaylorScene at parameters' spacing: the mode's amplitude every `sample`
// seconds to `until`, and the growth rate fitted to it.
struct RayleighTaylorRun
{
  std::size_t particles = 0;
  double k = 0, amplitude0 = 0;
  std::vector<double> t, amplitude; // [s], [m]
  // n and a_0 of a_0 cosh(n t) fitted (least squares of the logarithm) over the samples after
  // kSettling while the amplitude stays linear, k a <= kLinearLimit; 0 where fewer than 4.
  double rate = 0, fittedAmplitude0 = 0;
  int fitted = 0; // samples the fit used
  double nu = 0;  // the liquids' XSPH viscosity (Parameters::xsphNu) [m^2/s]
};
constexpr double kLinearLimit = 0.4;
// The lattice settles under its new weight for its first few hundredths of a second (the
// amplitude holds still, then jumps): the fit starts after it.
constexpr double kSettling = 0.06; // [s]
RayleighTaylorRun runRayleighTaylor(const Parameters& parameters, Backend backend,
  Precision precision, double light, double heavy, double depth, double thickness,
  double amplitude, double until, double sample);

} // namespace pbf::validation
