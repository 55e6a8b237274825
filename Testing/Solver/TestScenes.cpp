#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace pbf::test
{

PresetFluid presetFluid(const std::string& name, double spacing)
{
  const Scene scene = presetScene(name);
  PresetFluid s;
  s.parameters.particleSpacing = spacing;
  // The decomposition tests compare steppers step for step: the paper's fixed count of
  // projections, so that every step does the same work on every backend (the adaptive loop is
  // tested on its own, with densityErrorTolerance set back).
  s.parameters.densityErrorTolerance = 0;
  s.parameters.solverIterations = 4;
  s.parameters = withSceneDomain(s.parameters, scene);
  s.fluid = fillScene(scene, s.parameters);
  return s;
}

Parameters coarseFixedSteps()
{
  Parameters p;
  p.particleSpacing = 0.05;
  p.timeStepping = TimeStepping::Fixed;
  p.densityErrorTolerance = 0;
  p.solverIterations = 4;
  p.xsphViscosity = 0.001; // the paper's c = 0.01 per step at the default 1/240 s
  p.xsphHyperViscosity = 0; // and the paper's XSPH alone
  return p;
}

Parameters hugeFixedStep()
{
  Parameters p = coarseFixedSteps();
  p.timeStep = 0.05;
  return p;
}

Scene restingBlock(int side, double spacing)
{
  const double width = side * spacing;
  Scene scene;
  scene.name = "resting_block";
  scene.domain = { { 0, 0, 0 }, { width, 2 * width, width } };
  scene.boxes.push_back({ { 0, 0, 0 }, { width, width, width }, { 0, 0, 0 } });
  return scene;
}

double potentialEnergy(const Simulation& simulation)
{
  Snapshot<double> snapshot;
  simulation.stepper().read(snapshot);
  const Parameters& p = simulation.parameters();
  const double mass = calibratedParticleMass(p);
  const Vec3d up = p.gravity * (-1.0 / length(p.gravity));
  double energy = 0;
  for (const Vec3d& x : snapshot.position)
  {
    energy += mass * length(p.gravity) * dot(x - p.domain.min, up);
  }
  return energy;
}

std::map<std::int64_t, std::size_t> indexById(const Snapshot<double>& snapshot)
{
  std::map<std::int64_t, std::size_t> index;
  for (std::size_t i = 0; i < snapshot.id.size(); ++i)
  {
    index[snapshot.id[i]] = i;
  }
  return index;
}

double maxRelativePositionError(const Snapshot<double>& a, const Snapshot<double>& b)
{
  EXPECT_EQ(a.id.size(), b.id.size());
  EXPECT_EQ(std::set<std::int64_t>(a.id.begin(), a.id.end()).size(), a.id.size())
    << "an id appears twice";
  const auto index = indexById(b);
  double worst = 0;
  for (std::size_t i = 0; i < a.id.size(); ++i)
  {
    const auto it = index.find(a.id[i]);
    if (it == index.end())
    {
      ADD_FAILURE() << "particle id " << a.id[i] << " missing";
      return INFINITY;
    }
    const Vec3d& xb = b.position[it->second];
    const double error = length(a.position[i] - xb) / length(xb);
    worst = std::isnan(error) ? INFINITY : std::max(worst, error);
  }
  return worst;
}

Snapshot<double> joined(const std::vector<Snapshot<double>>& parts)
{
  Snapshot<double> all;
  for (const Snapshot<double>& part : parts)
  {
    all.position.insert(all.position.end(), part.position.begin(), part.position.end());
    all.velocity.insert(all.velocity.end(), part.velocity.begin(), part.velocity.end());
    all.density.insert(all.density.end(), part.density.begin(), part.density.end());
    all.lambda.insert(all.lambda.end(), part.lambda.begin(), part.lambda.end());
    all.id.insert(all.id.end(), part.id.begin(), part.id.end());
  }
  return all;
}

Scene damBreakWithSolids()
{
  return parseScene(R"({
    "domain": { "min": [0, 0, 0], "max": [1.6, 0.8, 0.6] },
    "fluid": [ { "type": "box", "min": [0, 0, 0], "max": [0.4, 0.6, 0.6] } ],
    "obstacles": [
      { "type": "sphere", "center": [0.9, 0.12, 0.3], "radius": 0.12 },
      { "type": "box", "min": [0.3, -0.5, -0.5], "max": [0.5, 0.2, 0.2] } ] })");
}

} // namespace pbf::test
