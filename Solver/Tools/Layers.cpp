#include "Layers.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace pbf::validation
{

namespace
{

constexpr double kPi = 3.14159265358979323846;

// Two named liquids, liquid 0 the one that starts below.
std::vector<Liquid> twoLiquids(
  const char* lowerName, double lowerDensity, const char* upperName, double upperDensity)
{
  Liquid lower, upper;
  lower.name = lowerName;
  lower.restDensity = lowerDensity;
  upper.name = upperName;
  upper.restDensity = upperDensity;
  return { lower, upper };
}

} // namespace

Scene layeredScene(double lowerDensity, double upperDensity, double depth)
{
  Scene scene;
  scene.name = "two layers";
  scene.domain = { { 0, 0, 0 }, { kLayerTankLength, kLayerTankHeight, kLayerTankWidth } };
  scene.liquids = twoLiquids("lower", lowerDensity, "upper", upperDensity);
  scene.boxes.push_back({ { 0, 0, 0 }, { kLayerTankLength, depth, kLayerTankWidth }, {}, 0 });
  scene.boxes.push_back(
    { { 0, depth, 0 }, { kLayerTankLength, 2 * depth, kLayerTankWidth }, {}, 1 });
  return scene;
}

LayerMeasure measureLayers(const Snapshot<double>& state, const Parameters& parameters)
{
  LayerMeasure m;
  const double s = parameters.particleSpacing;
  const int heavy = 0; // the liquid below at the start
  // Each column's particles: (height, liquid).
  std::map<std::pair<long, long>, std::vector<std::pair<double, int>>> columns;
  for (std::size_t i = 0; i < state.position.size(); ++i)
  {
    const Vec3d& x = state.position[i];
    const int l = state.liquid.empty() ? 0 : state.liquid[i];
    const auto key = std::make_pair(static_cast<long>(std::floor((x.x - parameters.domain.min.x) / s)),
      static_cast<long>(std::floor((x.z - parameters.domain.min.z) / s)));
    columns[key].emplace_back(x.y, l);
    m.meanHeight[l] += x.y;
    m.compression[l] +=
      std::max(state.density[i] / parameters.liquidRestDensity(l) - 1.0, 0.0);
    ++m.particles[l];
  }
  for (int l = 0; l < 2; ++l)
  {
    m.meanHeight[l] /= std::max<std::size_t>(m.particles[l], 1);
    m.compression[l] /= std::max<std::size_t>(m.particles[l], 1);
  }
  std::vector<double> levels;
  std::size_t wrong = 0, counted = 0;
  for (auto& [key, column] : columns)
  {
    std::sort(column.begin(), column.end());
    const auto below = static_cast<std::size_t>(std::count_if(column.begin(), column.end(),
      [heavy](const std::pair<double, int>& p) { return p.second == heavy; }));
    if (below == 0 || below == column.size())
    {
      continue;
    }
    const double level = 0.5 * (column[below - 1].first + column[below].first);
    levels.push_back(level);
    m.levels.push_back({ parameters.domain.min.x + s * (key.first + 0.5), level,
      parameters.domain.min.z + s * (key.second + 0.5) });
    for (const auto& [y, l] : column)
    {
      wrong += (l == heavy) != (y < level) ? 1 : 0;
    }
    counted += column.size();
  }
  m.columns = static_cast<int>(levels.size());
  if (levels.empty())
  {
    return m;
  }
  for (double y : levels)
  {
    m.interface += y;
  }
  m.interface /= static_cast<double>(levels.size());
  for (double y : levels)
  {
    m.interfaceRms += (y - m.interface) * (y - m.interface);
  }
  m.interfaceRms = std::sqrt(m.interfaceRms / static_cast<double>(levels.size()));
  m.wrongSide = static_cast<double>(wrong) / static_cast<double>(counted);
  return m;
}

Scene rayleighTaylorScene(double light, double heavy, double depth, double thickness)
{
  Scene scene;
  scene.name = "Rayleigh-Taylor";
  scene.domain = { { 0, 0, 0 }, { kRayleighTaylorLength, 2.5 * depth, thickness } };
  scene.liquids = twoLiquids("light", light, "heavy", heavy);
  scene.boxes.push_back({ { 0, 0, 0 }, { kRayleighTaylorLength, 2 * depth, thickness }, {}, 0 });
  return scene;
}

ParticleBatch rayleighTaylorFluid(
  const Scene& scene, const Parameters& parameters, double depth, double amplitude)
{
  ParticleBatch batch = fillScene(scene, withSceneDomain(parameters, scene));
  const double k = 2 * kPi / kRayleighTaylorLength;
  for (std::size_t i = 0; i < batch.position.size(); ++i)
  {
    const Vec3d& x = batch.position[i];
    batch.liquid[i] = x.y < depth + amplitude * std::cos(k * x.x) ? 0 : 1;
  }
  return batch;
}

double modeAmplitude(const LayerMeasure& m, double k)
{
  double sum = 0;
  for (const Vec3d& level : m.levels)
  {
    sum += (level.y - m.interface) * std::cos(k * level.x);
  }
  return m.levels.empty() ? 0.0 : 2.0 * sum / static_cast<double>(m.levels.size());
}

double rayleighTaylorRate(double light, double heavy, double k, double g, double nu)
{
  const double atwood = (heavy - light) / (heavy + light);
  return std::sqrt(atwood * k * g + nu * nu * k * k * k * k) - nu * k * k;
}

RayleighTaylorRun runRayleighTaylor(const Parameters& parameters, Backend backend,
  Precision precision, double light, double heavy, double depth, double thickness,
  double amplitude, double until, double sample)
{
  const Scene scene = rayleighTaylorScene(light, heavy, depth, thickness);
  const ParticleBatch fluid = rayleighTaylorFluid(scene, parameters, depth, amplitude);
  Simulation simulation(scene, parameters, backend, precision, fluid);
  RayleighTaylorRun run;
  run.particles = fluid.position.size();
  run.k = 2 * kPi / kRayleighTaylorLength;
  run.nu = simulation.parameters().xsphNu();
  const int samples = static_cast<int>(std::lround(until / sample));
  for (int s = 0; s <= samples; ++s)
  {
    simulation.advanceTo(s * sample);
    Snapshot<double> state;
    simulation.stepper().read(state);
    run.t.push_back(s * sample);
    run.amplitude.push_back(modeAmplitude(measureLayers(state, simulation.parameters()), run.k));
  }
  run.amplitude0 = run.amplitude.front();
  // The samples of the linear stage, after the lattice has settled.
  std::vector<std::pair<double, double>> linear; // (t, ln a)
  for (std::size_t s = 1; s < run.t.size(); ++s)
  {
    const double a = run.amplitude[s];
    if (run.k * std::abs(a) > kLinearLimit)
    {
      break;
    }
    if (run.t[s] >= kSettling && a > 0)
    {
      linear.emplace_back(run.t[s], std::log(a));
    }
  }
  run.fitted = static_cast<int>(linear.size());
  if (linear.size() < 4)
  {
    return run;
  }
  // ln a_0 + ln cosh(n t) against the samples: for each n the best ln a_0 is the mean residual;
  // the least squares over n by golden section (the misfit is unimodal in n).
  const auto lnAmplitude0 = [&](double n) {
    double sum = 0;
    for (const auto& [t, value] : linear)
    {
      sum += value - std::log(std::cosh(n * t));
    }
    return sum / static_cast<double>(linear.size());
  };
  const auto misfit = [&](double n) {
    const double offset = lnAmplitude0(n);
    double e = 0;
    for (const auto& [t, value] : linear)
    {
      const double d = offset + std::log(std::cosh(n * t)) - value;
      e += d * d;
    }
    return e;
  };
  double lo = 0, hi = 100;
  const double golden = 0.5 * (std::sqrt(5.0) - 1);
  for (int i = 0; i < 200; ++i)
  {
    const double left = hi - golden * (hi - lo), right = lo + golden * (hi - lo);
    if (misfit(left) < misfit(right))
    {
      hi = right;
    }
    else
    {
      lo = left;
    }
  }
  run.rate = 0.5 * (lo + hi);
  run.fittedAmplitude0 = std::exp(lnAmplitude0(run.rate));
  return run;
}

} // namespace pbf::validation
