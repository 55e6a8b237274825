#include "SessileDrop.h"

#include "LatticeShapes.h"

#include <algorithm>
#include <cmath>

namespace pbf::validation
{

namespace
{
constexpr double kPi = 3.14159265358979323846;

// A cap of angle theta on a sphere of radius rho: its volume and its centroid's height over
// its base.
struct Cap
{
  double volume, centroid;
};
Cap capOf(double theta, double rho)
{
  const double c = std::cos(theta);
  const double h = rho * (1 - c);
  return { kPi * h * h * (3 * rho - h) / 3, h * (4 * rho - h) / (4 * (3 * rho - h)) };
}
} // namespace

Scene sessileScene(double radius, double solidAngle)
{
  Scene scene;
  scene.name = "sessile_drop";
  scene.domain = { { 0, 0, 0 }, { 4 * radius, 2 * radius, 4 * radius } };
  if (solidAngle > 0)
  {
    // The floor a solid: a slab under y = 0 wider than the domain, whose own floor lies in it.
    scene.domain.min.y = -radius / 2;
    SolidRegion slab;
    slab.name = "slab";
    slab.box = { { -radius, -radius, -radius }, { 5 * radius, 0, 5 * radius } };
    slab.contactAngle.fill(solidAngle);
    scene.solids.push_back(slab);
  }
  // The region the lattice is cut from (sessileFluid keeps the hemisphere's sites).
  scene.boxes.push_back({ { 0, 0, 0 }, { 4 * radius, 2 * radius, 4 * radius }, {}, 0 });
  return scene;
}

ParticleBatch sessileFluid(const Scene& scene, const Parameters& parameters, double radius)
{
  const Vec3d centre{ 2 * radius, 0, 2 * radius };
  return latticeSitesInside(scene, parameters, [&](const Vec3d& x) {
    const Vec3d d = x - centre;
    return dot(d, d) <= radius * radius;
  });
}

double capContactAngle(double volume, double centroid)
{
  // The centroid over the cube root of the volume does not depend on the sphere's radius.
  const auto ratio = [](double theta) {
    const Cap cap = capOf(theta, 1.0);
    return cap.centroid / std::cbrt(cap.volume);
  };
  const double wanted = centroid / std::cbrt(volume);
  double lo = 1e-6, hi = kPi - 1e-6;
  for (int k = 0; k < 100; ++k)
  {
    const double mid = 0.5 * (lo + hi);
    (ratio(mid) < wanted ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi) * 180 / kPi;
}

SessileRun runSessileDrop(const Parameters& parameters, Backend backend, Precision precision,
  double radius, double until, double average, double sample, bool onSolid)
{
  Parameters p = parameters;
  // On a solid the walls are neutral (the drop is 2 R from them) and the slab takes the angle.
  const double solidAngle = onSolid ? p.contactAngle : 0.0;
  if (onSolid)
  {
    p.contactAngle = 90;
  }
  p.gravity = { 0, 0, 0 };
  // Without gravity the scene's speed is the capillary one, sqrt(sigma / (rho R)), which scales
  // XSPH's viscosity (a drop released far from its angle otherwise rings for long, or jumps off).
  if (!(p.sceneSpeedHint > 0))
  {
    p.sceneSpeedHint = std::sqrt(p.surfaceTension / (p.restDensity * radius));
  }
  const Scene scene = sessileScene(radius, solidAngle);
  Simulation simulation(scene, p, backend, precision, sessileFluid(scene, p, radius));
  SessileRun run;
  const double s = p.particleSpacing;
  double lowest = 180, highest = 0, sum = 0;
  int count = 0;
  const int samples = static_cast<int>(std::lround(until / sample));
  for (int k = 1; k <= samples; ++k)
  {
    const double t = k * sample;
    simulation.advanceTo(t);
    Snapshot<double> state;
    simulation.stepper().read(state);
    if (t < until - average - 1e-12)
    {
      continue;
    }
    run.particles = state.position.size();
    // Each particle stands for a cube of s^3 around its site; the floor's layer sits at s / 2.
    double centroid = 0, top = 0;
    for (const Vec3d& x : state.position)
    {
      centroid += x.y / static_cast<double>(state.position.size());
      top = std::max(top, x.y);
    }
    const double volume = static_cast<double>(state.position.size()) * s * s * s;
    const double angle = capContactAngle(volume, centroid);
    lowest = std::min(lowest, angle);
    highest = std::max(highest, angle);
    sum += angle;
    ++count;
    run.height = top + s / 2;
  }
  run.angle = count > 0 ? sum / count : 0.0;
  run.spread = count > 0 ? highest - lowest : 0.0;
  run.steps = static_cast<double>(simulation.stepCount());
  return run;
}

} // namespace pbf::validation
