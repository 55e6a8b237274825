#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace pbf::test
{

PresetFluid presetFluid(const std::string& name, double spacing)
{
  return sceneFluid(presetScene(name), spacing);
}

PresetFluid sceneFluid(const Scene& scene, double spacing)
{
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

std::map<std::int64_t, int> liquidsById(const Snapshot<double>& snapshot)
{
  std::map<std::int64_t, int> out;
  for (std::size_t i = 0; i < snapshot.id.size(); ++i)
  {
    out[snapshot.id[i]] = snapshot.liquid.at(i);
  }
  return out;
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

double maxRelativePressureError(const Snapshot<double>& a, const Snapshot<double>& b)
{
  const auto index = indexById(b);
  double scale = 0, worst = 0;
  for (double p : b.pressure)
  {
    scale = std::max(scale, std::abs(p));
  }
  for (std::size_t i = 0; i < a.id.size(); ++i)
  {
    const auto it = index.find(a.id[i]);
    if (it == index.end())
    {
      ADD_FAILURE() << "particle id " << a.id[i] << " missing";
      return INFINITY;
    }
    const double error = std::abs(a.pressure[i] - b.pressure[it->second]) / scale;
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
    all.pressure.insert(all.pressure.end(), part.pressure.begin(), part.pressure.end());
    all.id.insert(all.id.end(), part.id.begin(), part.id.end());
    all.liquid.insert(all.liquid.end(), part.liquid.begin(), part.liquid.end());
  }
  return all;
}

Scene twoLiquids()
{
  return parseScene(R"({
    "domain": { "min": [0, 0, 0], "max": [0.8, 0.6, 0.24] },
    "liquids": [
      { "name": "water", "restDensity": 1000 },
      { "name": "oil", "restDensity": 800, "xsphViscosity": 0.05 }
    ],
    "fluid": [
      { "type": "box", "min": [0, 0, 0], "max": [0.24, 0.4, 0.24], "liquid": "water" },
      { "type": "box", "min": [0.4, 0, 0], "max": [0.8, 0.12, 0.24], "liquid": "oil" }
    ],
    "emitters": [ { "center": [0.6, 0.45, 0.12], "direction": [0, -1, 0], "radius": 0.05,
      "speed": 1.0, "start": 0.1, "stop": 0.3, "liquid": "oil" } ]
  })");
}

Scene sideBySideLiquids()
{
  // twoLiquids' tank and liquids, the regions moved side by side, no nozzle.
  Scene scene = twoLiquids();
  scene.name = "water and oil side by side";
  scene.emitters.clear();
  scene.boxes = { FluidBox{ { 0, 0, 0 }, { 0.2, 0.4, 0.24 }, {}, 0 },
    FluidBox{ { 0.2, 0, 0 }, { 0.4, 0.4, 0.24 }, {}, 1 } };
  return scene;
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

// A unit icosahedron subdivided `levels` times and pushed onto the sphere of `radius` about c:
// every triangle's corners are on the sphere, so its faces lie at most r (1 - cos(theta / 2))
// inside it, theta the largest edge's angle.
TriangleMesh icosphere(const Vec3d& c, double radius, int levels)
{
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3d> p = { { -1, t, 0 }, { 1, t, 0 }, { -1, -t, 0 }, { 1, -t, 0 }, { 0, -1, t },
    { 0, 1, t }, { 0, -1, -t }, { 0, 1, -t }, { t, 0, -1 }, { t, 0, 1 }, { -t, 0, -1 },
    { -t, 0, 1 } };
  std::vector<std::array<std::uint32_t, 3>> f = { { 0, 11, 5 }, { 0, 5, 1 }, { 0, 1, 7 },
    { 0, 7, 10 }, { 0, 10, 11 }, { 1, 5, 9 }, { 5, 11, 4 }, { 11, 10, 2 }, { 10, 7, 6 },
    { 7, 1, 8 }, { 3, 9, 4 }, { 3, 4, 2 }, { 3, 2, 6 }, { 3, 6, 8 }, { 3, 8, 9 }, { 4, 9, 5 },
    { 2, 4, 11 }, { 6, 2, 10 }, { 8, 6, 7 }, { 9, 8, 1 } };
  for (Vec3d& q : p)
  {
    q = q * (1.0 / length(q));
  }
  for (int level = 0; level < levels; ++level)
  {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
    auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = middle.find(key);
      if (it != middle.end())
      {
        return it->second;
      }
      const Vec3d m = (p[a] + p[b]) * 0.5;
      p.push_back(m * (1.0 / length(m)));
      return middle[key] = static_cast<std::uint32_t>(p.size() - 1);
    };
    std::vector<std::array<std::uint32_t, 3>> g;
    for (const auto& tri : f)
    {
      const std::uint32_t a = mid(tri[0], tri[1]), b = mid(tri[1], tri[2]), d = mid(tri[2], tri[0]);
      g.push_back({ tri[0], a, d });
      g.push_back({ tri[1], b, a });
      g.push_back({ tri[2], d, b });
      g.push_back({ a, b, d });
    }
    f = g;
  }
  TriangleMesh mesh;
  for (const Vec3d& q : p)
  {
    mesh.points.push_back(c + q * radius);
  }
  mesh.triangles = f;
  return mesh;
}

TriangleMesh boxMesh(const Box& b)
{
  TriangleMesh m;
  for (int k = 0; k < 8; ++k)
  {
    m.points.push_back({ k & 1 ? b.max.x : b.min.x, k & 2 ? b.max.y : b.min.y,
      k & 4 ? b.max.z : b.min.z });
  }
  // Two triangles per face, outward: -x, +x, -y, +y, -z, +z.
  m.triangles = { { 0, 4, 6 }, { 0, 6, 2 }, { 1, 3, 7 }, { 1, 7, 5 }, { 0, 1, 5 }, { 0, 5, 4 },
    { 2, 6, 7 }, { 2, 7, 3 }, { 0, 2, 3 }, { 0, 3, 1 }, { 4, 5, 7 }, { 4, 7, 6 } };
  return m;
}

} // namespace pbf::test
