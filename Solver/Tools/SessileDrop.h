// A drop resting on a flat solid without gravity, the check of adhesion (Documentation/
// ValidationInterfaces.md, "Adhesion"): a hemisphere of liquid on the domain's floor (y = 0) under surface
// tension spreads or beads up until its surface meets the floor at the contact angle
// (Parameters::contactAngle), and rests as a spherical cap. The angle is read from the cap's
// volume and the height of its centroid, sums over every particle rather than the few at its
// rim or top.
#pragma once

#include "Simulation.h"

#include <vector>

namespace pbf::validation
{

// The domain, 4 R wide and 2 R high, the drop's centre on the floor at (2 R, 0, 2 R); no
// gravity. solidAngle > 0: the floor is a solid slab under y = 0 with that contact angle
// [degrees] (the domain reaches R / 2 below it), the check of adhesion at obstacles.
Scene sessileScene(double radius, double solidAngle = 0);
// The lattice's sites inside the hemisphere of `radius` on the floor.
ParticleBatch sessileFluid(const Scene& scene, const Parameters& parameters, double radius);

// The contact angle [degrees] of the spherical cap of volume `volume` whose centroid lies
// `centroid` above its base: the centroid's height over the volume's cube root grows
// monotonically with the angle, solved by bisection.
double capContactAngle(double volume, double centroid);

// A run to `until`, the angle sampled every `sample` seconds over the last `average` seconds
// and averaged.
struct SessileRun
{
  std::size_t particles = 0;
  double angle = 0;     // mean [degrees]
  double spread = 0;    // the samples' largest minus smallest [degrees]
  double height = 0;    // the top particle's height plus half a spacing at the end [m]
  double steps = 0;
};
// onSolid: on sessileScene's solid slab, at parameters.contactAngle (the walls neutral).
SessileRun runSessileDrop(const Parameters& parameters, Backend backend, Precision precision,
  double radius, double until, double average, double sample, bool onSolid = false);

} // namespace pbf::validation
