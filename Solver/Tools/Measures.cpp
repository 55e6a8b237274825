#include "Backends.h"
#include "Measures.h"

#include <cmath>
#include <vector>

namespace pbf::validation
{

DensityError densityErrorNow(const Simulation& simulation)
{
  Snapshot<double> state;
  simulation.stepper().read(state);
  ParticleBatch batch{ state.position, state.velocity, state.id };
  // A fresh CPU stepper of the same parameters and precision evaluates the density at rest on
  // construction: the solver's own density, walls mirrored, on exactly these positions.
  const Backend backend =
    simulation.stepper().backend() == Backend::Serial ? Backend::Serial : Backend::OpenMP;
  const auto fresh =
    makeStepper(backend, simulation.stepper().precision(), simulation.parameters(), batch);
  const Statistics s = fresh->statistics();
  return { s.averageDensityError, s.maxDensityError, s.averageNeighbors };
}

double potentialEnergy(const Simulation& simulation)
{
  Snapshot<double> state;
  simulation.stepper().read(state);
  const Parameters& p = simulation.parameters();
  const double mass = calibratedParticleMass(p);
  double sum = 0;
  for (const Vec3d& x : state.position)
  {
    sum += -mass * dot(p.gravity, x - p.domain.min);
  }
  return sum;
}

std::string conservationViolation(const Simulation& simulation, std::int64_t expectedCount)
{
  Snapshot<double> s;
  simulation.stepper().read(s);
  const auto n = static_cast<std::int64_t>(s.id.size());
  if (n != expectedCount)
  {
    return "particle count " + std::to_string(n) + ", expected " + std::to_string(expectedCount);
  }
  std::vector<char> seen(static_cast<std::size_t>(n), 0);
  // The walls the solver clamps to, rounded to its precision: a particle on a wall sits there.
  const Box& d = simulation.parameters().domain;
  const bool single = simulation.stepper().precision() == Precision::Single;
  const auto round = [single](double v) { return single ? double(float(v)) : v; };
  for (std::size_t i = 0; i < s.id.size(); ++i)
  {
    const std::int64_t id = s.id[i];
    if (id < 0 || id >= n || seen[static_cast<std::size_t>(id)])
    {
      return "id " + std::to_string(id) + " out of 0.." + std::to_string(n - 1) + " or repeated";
    }
    seen[static_cast<std::size_t>(id)] = 1;
    const Vec3d& x = s.position[i];
    const Vec3d& v = s.velocity[i];
    if (!std::isfinite(x.x + x.y + x.z + v.x + v.y + v.z + s.density[i] + s.lambda[i]))
    {
      return "particle id " + std::to_string(id) + " is not finite";
    }
    if (x.x < round(d.min.x) || x.y < round(d.min.y) || x.z < round(d.min.z) ||
      x.x > round(d.max.x) || x.y > round(d.max.y) || x.z > round(d.max.z))
    {
      return "particle id " + std::to_string(id) + " outside the domain";
    }
  }
  return "";
}

} // namespace pbf::validation
