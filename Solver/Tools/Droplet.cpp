#include "Droplet.h"

#include <cmath>

namespace pbf::validation
{

namespace
{
constexpr double kPi = 3.14159265358979323846;

// The mean pressure of the particles within `within` of the particles' centre.
double interiorPressure(const Snapshot<double>& state, double within)
{
  Vec3d c{ 0, 0, 0 };
  for (const Vec3d& x : state.position)
  {
    c += x * (1.0 / static_cast<double>(state.position.size()));
  }
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < state.position.size(); ++i)
  {
    const Vec3d d = state.position[i] - c;
    if (dot(d, d) < within * within && i < state.pressure.size())
    {
      sum += state.pressure[i];
      ++n;
    }
  }
  return n > 0 ? sum / n : 0.0;
}
} // namespace

Scene dropletScene(double radius)
{
  Scene scene;
  scene.name = "droplet";
  scene.domain = { { 0, 0, 0 }, { 4 * radius, 4 * radius, 4 * radius } };
  // The region the lattice is cut from (dropletFluid keeps the spheroid's sites).
  scene.boxes.push_back({ { 0, 0, 0 }, { 4 * radius, 4 * radius, 4 * radius }, {}, 0 });
  return scene;
}

ParticleBatch dropletFluid(
  const Scene& scene, const Parameters& parameters, double radius, double elongation)
{
  const ParticleBatch lattice = fillScene(scene, withSceneDomain(parameters, scene));
  const double a = radius * (1 + elongation), b = radius / std::sqrt(1 + elongation);
  const Vec3d centre{ 2 * radius, 2 * radius, 2 * radius };
  ParticleBatch batch;
  for (const Vec3d& x : lattice.position)
  {
    const Vec3d d = x - centre;
    if (d.x * d.x / (a * a) + (d.y * d.y + d.z * d.z) / (b * b) <= 1)
    {
      batch.position.push_back(x);
      batch.velocity.push_back({ 0, 0, 0 });
      batch.id.push_back(static_cast<std::int64_t>(batch.id.size()));
    }
  }
  return batch;
}

double rayleighPeriod(double radius, double density, double sigma)
{
  return 2 * kPi * std::sqrt(density * radius * radius * radius / (8 * sigma));
}

double deformation(const Snapshot<double>& state)
{
  Vec3d c{ 0, 0, 0 };
  const double n = static_cast<double>(state.position.size());
  for (const Vec3d& x : state.position)
  {
    c += x * (1.0 / n);
  }
  double xx = 0, yy = 0, zz = 0;
  for (const Vec3d& x : state.position)
  {
    const Vec3d d = x - c;
    xx += d.x * d.x;
    yy += d.y * d.y;
    zz += d.z * d.z;
  }
  return (xx - 0.5 * (yy + zz)) / n;
}

DropletRun runDroplet(const Parameters& parameters, Backend backend, Precision precision,
  double radius, double elongation, double until, double sample)
{
  Parameters p = parameters;
  p.gravity = { 0, 0, 0 };
  const Scene scene = dropletScene(radius);
  Simulation simulation(scene, p, backend, precision, dropletFluid(scene, p, radius, elongation));
  DropletRun run;
  run.theory = rayleighPeriod(radius, p.restDensity, p.surfaceTension);
  const int samples = static_cast<int>(std::lround(until / sample));
  for (int s = 0; s <= samples; ++s)
  {
    simulation.advanceTo(s * sample);
    Snapshot<double> state;
    simulation.stepper().read(state);
    run.particles = state.position.size();
    run.t.push_back(s * sample);
    run.deformation.push_back(deformation(state));
    if (s == samples)
    {
      run.pressure = interiorPressure(state, radius / 2);
    }
  }
  run.laplace = 2 * p.surfaceTension / radius;
  run.steps = static_cast<double>(simulation.stepCount());
  // The mean the drop oscillates about: that of the second half (the sphere of particles is not
  // exactly round on the lattice's scale).
  double mean = 0;
  int counted = 0;
  for (std::size_t s = run.t.size() / 2; s < run.t.size(); ++s)
  {
    mean += run.deformation[s];
    ++counted;
  }
  mean /= counted > 0 ? counted : 1;
  std::vector<double> crossings;
  for (std::size_t s = 1; s < run.t.size(); ++s)
  {
    const double a = run.deformation[s - 1] - mean, b = run.deformation[s] - mean;
    if ((a > 0) != (b > 0) && a != b)
    {
      crossings.push_back(run.t[s - 1] + (run.t[s] - run.t[s - 1]) * a / (a - b));
    }
  }
  run.crossings = static_cast<int>(crossings.size());
  if (crossings.size() >= 3)
  {
    run.period = 2 * (crossings.back() - crossings.front()) /
      static_cast<double>(crossings.size() - 1);
  }
  return run;
}

} // namespace pbf::validation
