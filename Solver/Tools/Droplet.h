// A droplet without gravity, the check of surface tension (Documentation/ValidationInterfaces.md, "Surface
// tension"): a spheroid of liquid, longer along x than across, pulls itself towards a sphere and
// oscillates about it in Rayleigh's l = 2 mode, whose period for a sphere of radius R is
// T = 2 pi sqrt(rho R^3 / (8 sigma)) (Rayleigh 1879; Lamb, Hydrodynamics, section 275). A
// spheroid starts that mode alone; a block (a cube) starts l = 4 and more as well, and
// the crossings of its deformation wander by a quarter of a period between runs.
#pragma once

#include "Simulation.h"

#include <vector>

namespace pbf::validation
{

// The domain, a cube 4 radii wide with the drop at its centre (2 R, 2 R, 2 R), away from the
// origin; no gravity.
Scene dropletScene(double radius);
// The lattice's sites inside the spheroid x^2 / a^2 + (y^2 + z^2) / b^2 <= 1 about the centre,
// a = R (1 + elongation), b = R / sqrt(1 + elongation): the volume of the sphere of radius R.
ParticleBatch dropletFluid(
  const Scene& scene, const Parameters& parameters, double radius, double elongation);

// Rayleigh's l = 2 period [s] of a drop of this radius, rest density and surface tension.
double rayleighPeriod(double radius, double density, double sigma);

// The l = 2 deformation of a state: <(x - c)^2> - (<(y - c)^2> + <(z - c)^2>) / 2 over its
// particles [m^2] (c their centre): positive while the drop is long along x.
double deformation(const Snapshot<double>& state);

// A run of dropletFluid to `until`, sampling the deformation every `sample` seconds, and the
// period fitted to it: D(t) = m + e^(-gamma t) (a cos(omega t) + b sin(omega t)) by least
// squares over every sample, T = 2 pi / omega.
struct DropletRun
{
  std::size_t particles = 0;
  std::vector<double> t, deformation;
  double period = 0;  // [s]
  double damping = 0; // gamma [1/s]
  int crossings = 0;  // of the fitted mean m
  double theory = 0;  // Rayleigh's period [s]
  double steps = 0;   // solver steps taken
  // The mean pressure of the particles within half a radius of the centre at the end [Pa], and
  // Laplace's 2 sigma / R.
  double pressure = 0, laplace = 0;
};
DropletRun runDroplet(const Parameters& parameters, Backend backend, Precision precision,
  double radius, double elongation, double until, double sample);

} // namespace pbf::validation
