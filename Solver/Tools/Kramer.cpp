#include "Kramer.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pbf::validation
{

namespace
{

constexpr double kPi = 3.14159265358979323846;
// Above the water: room for the sphere's drop and the splash.
constexpr double kHeadroom = 0.5; // [m]

// The times the series crosses zero, by linear interpolation between its samples.
std::vector<double> zeroCrossings(const TimeSeries& s, double window)
{
  std::vector<double> times;
  for (std::size_t k = 1; k < s.t.size() && s.t[k] <= window; ++k)
  {
    const double a = s.value[k - 1], b = s.value[k];
    if ((a > 0 && b <= 0) || (a < 0 && b >= 0))
    {
      times.push_back(s.t[k - 1] + (s.t[k] - s.t[k - 1]) * a / (a - b));
    }
  }
  return times;
}

// The first three periods: from the first crossing, the time to the third, the third to the
// fifth and the fifth to the seventh.
void periods(const TimeSeries& s, double window, double out[3])
{
  const std::vector<double> c = zeroCrossings(s, window);
  for (int k = 0; k < 3; ++k)
  {
    const std::size_t a = static_cast<std::size_t>(2 * k), b = a + 2;
    out[k] = b < c.size() ? c[b] - c[a] : std::numeric_limits<double>::quiet_NaN();
  }
}

} // namespace

Parameters kramerParameters(Parameters parameters)
{
  parameters.restDensity = kKramerWater;
  parameters.gravity = { 0, -kKramerGravity, 0 };
  return parameters;
}

Scene kramerScene(const KramerTank& tank, double centre)
{
  Scene scene;
  scene.name = "Kramer sphere";
  scene.domain = { { 0, 0, 0 }, { tank.side, tank.depth + kHeadroom, tank.side } };
  scene.boxes.push_back({ { 0, 0, 0 }, { tank.side, tank.depth, tank.side }, { 0, 0, 0 } });
  SolidRegion sphere;
  sphere.kind = SolidRegion::Kind::Sphere;
  sphere.name = "sphere";
  sphere.center = { 0.5 * tank.side, centre, 0.5 * tank.side };
  sphere.radius = 0.5 * kKramerDiameter;
  sphere.density = kKramerMass / (kPi / 6 * std::pow(kKramerDiameter, 3));
  sphere.freeAxes = { false, true, false };
  sphere.turns = false;
  sphere.release = kKramerHold;
  scene.solids.push_back(sphere);
  return scene;
}

std::size_t kramerParticles(const Parameters& parameters, const KramerTank& tank, double start)
{
  Parameters p = kramerParameters(parameters);
  p.exactBoundaries = false; // the count only
  const Simulation simulation(kramerScene(tank, start), p, Backend::Serial, Precision::Double);
  return simulation.stepper().size();
}

KramerRun runKramer(const Parameters& parameters, Backend backend, Precision precision,
  const KramerTank& tank, double start, double window, double sample)
{
  Simulation simulation(
    kramerScene(tank, start), kramerParameters(parameters), backend, precision);
  KramerRun run;
  run.spacing = parameters.particleSpacing;
  run.start = start;
  run.particles = simulation.stepper().size();
  const int samples = static_cast<int>(std::lround(window / sample));
  for (int k = 0; k <= samples; ++k)
  {
    simulation.advanceTo(kKramerHold + k * sample);
    run.centre.t.push_back(k * sample);
    run.centre.value.push_back(simulation.bodies().at(0).state.centre.y);
  }
  return run;
}

double settledCentre(const KramerRun& run)
{
  const double half = 0.5 * run.centre.t.back();
  double sum = 0;
  int n = 0;
  for (std::size_t k = 0; k < run.centre.t.size(); ++k)
  {
    if (run.centre.t[k] >= half)
    {
      sum += run.centre.value[k];
      ++n;
    }
  }
  return n > 0 ? sum / n : std::numeric_limits<double>::quiet_NaN();
}

double kramerRest(const KramerTank& tank, double spacing, double settled,
  std::size_t settledParticles, std::size_t particles)
{
  const double more = (static_cast<double>(particles) - static_cast<double>(settledParticles)) *
    spacing * spacing * spacing;
  return settled + more / (tank.side * tank.side);
}

KramerComparison compareKramer(const TimeSeries& heave, const TimeSeries& record, double window)
{
  KramerComparison c{};
  periods(heave, window, c.period);
  periods(record, window, c.recordPeriod);
  double sum = 0;
  int count = 0;
  for (std::size_t k = 0; k < heave.t.size() && heave.t[k] <= window; ++k)
  {
    const double expected = record.at(heave.t[k]);
    if (std::isfinite(expected))
    {
      sum += (heave.value[k] - expected) * (heave.value[k] - expected);
      ++count;
    }
  }
  c.rms = count > 0 ? std::sqrt(sum / count) : std::numeric_limits<double>::quiet_NaN();
  return c;
}

TimeSeries readKramerRecord(const std::string& csvPath)
{
  const TimeSeries all = readRecordColumns(csvPath).at(0);
  TimeSeries fromRelease;
  for (std::size_t k = 0; k < all.t.size(); ++k)
  {
    if (all.t[k] >= 0)
    {
      fromRelease.t.push_back(all.t[k]);
      fromRelease.value.push_back(all.value[k]);
    }
  }
  return fromRelease;
}

} // namespace pbf::validation
