#include "Floating.h"

#include <cmath>

namespace pbf::validation
{

namespace
{

constexpr double kTank = 0.6, kTankHeight = 0.7, kSide = 0.2;
// The surface gauge: in a corner, a box's side away from the box.
constexpr Gauge kSurfaceGauge{ "surface", 0.06, 0.06 };

// The particles' and the body's kinetic and potential energy [J].
double mechanicalEnergy(const Simulation& simulation)
{
  const Parameters& p = simulation.parameters();
  const double g = length(p.gravity);
  const double m = calibratedParticleMass(p);
  Snapshot<double> state;
  simulation.stepper().read(state);
  double fluid = 0;
  for (std::size_t i = 0; i < state.position.size(); ++i)
  {
    fluid += m * (0.5 * dot(state.velocity[i], state.velocity[i]) + g * state.position[i].y);
  }
  const Body& body = simulation.bodies().at(0);
  const RigidState& s = body.state;
  const double M = body.mass.mass;
  return fluid + 0.5 * M * dot(s.velocity, s.velocity) +
    0.5 * dot(angularVelocity(s, body.mass), s.angularMomentum) + M * g * s.centre.y;
}

} // namespace

Scene floatingScene(double relative)
{
  Scene scene;
  scene.name = "floating box";
  scene.domain = { { 0, 0, 0 }, { kTank, kTankHeight, kTank } };
  scene.boxes.push_back({ { 0, 0, 0 }, { kTank, kFloatingDepth, kTank }, { 0, 0, 0 } });
  double bottom = kFloatingDepth - relative * kFloatingHeight;
  if (relative == 1.0)
  {
    bottom = 0.5 * kFloatingDepth - 0.5 * kFloatingHeight;
  }
  else if (relative > 1.0)
  {
    bottom = kFloatingDepth - 0.5 * kFloatingHeight;
  }
  SolidRegion box;
  box.kind = SolidRegion::Kind::Box;
  const double lo = 0.5 * (kTank - kSide);
  box.box = { { lo, bottom, lo }, { lo + kSide, bottom + kFloatingHeight, lo + kSide } };
  box.density = relative * Parameters().restDensity;
  box.name = "box";
  scene.solids.push_back(box);
  return scene;
}

FloatingRun runFloating(const Parameters& parameters, Backend backend, Precision precision,
  double relative, double kick, double until, double sample)
{
  Scene scene = floatingScene(relative);
  scene.solids[0].density = relative * parameters.restDensity;
  Simulation simulation(scene, parameters, backend, precision);
  FloatingRun run;
  run.spacing = parameters.particleSpacing;
  run.relative = relative;
  run.kick = kick;
  run.particles = simulation.stepper().size();
  run.mass = simulation.bodies().at(0).mass.mass;
  const int samples = static_cast<int>(std::lround(until / sample));
  const long kickSample = std::lround(kKickTime / sample);
  for (int k = 0; k <= samples; ++k)
  {
    const double t = k * sample;
    simulation.advanceTo(t);
    if (kick > 0 && k == kickSample)
    {
      // The push, through a checkpoint: the one way to set a body's state from outside.
      SimulationCheckpoint c = simulation.checkpoint();
      c.bodyStates.at(0).velocity.y -= kick;
      simulation.restore(c);
    }
    const RigidState& s = simulation.bodies()[0].state;
    const double surface = waterHeight(simulation, kSurfaceGauge);
    run.draft.t.push_back(t);
    run.draft.value.push_back(surface - (s.centre.y - 0.5 * kFloatingHeight));
    run.centre.t.push_back(t);
    run.centre.value.push_back(s.centre.y);
    run.speed.t.push_back(t);
    run.speed.value.push_back(s.velocity.y);
    run.energy.t.push_back(t);
    run.energy.value.push_back(mechanicalEnergy(simulation));
  }
  return run;
}

double meanOver(const TimeSeries& series, double from, double to)
{
  double sum = 0;
  int count = 0;
  for (std::size_t k = 0; k < series.t.size(); ++k)
  {
    if (series.t[k] >= from && series.t[k] <= to)
    {
      sum += series.value[k];
      ++count;
    }
  }
  return count > 0 ? sum / count : std::nan("");
}

KickResponse kickResponse(const FloatingRun& run, const FloatingRun& still)
{
  KickResponse r;
  r.kickEnergy = 0.5 * run.mass * run.kick * run.kick;
  const double end = run.centre.t.back();
  const double draft = meanOver(run.centre, end - 0.25 * (end - kKickTime), end);
  double lowest = r.kickEnergy;
  const std::size_t n = std::min(run.energy.t.size(), still.energy.t.size());
  for (std::size_t k = 1; k < n; ++k)
  {
    if (run.energy.t[k] < kKickTime)
    {
      continue;
    }
    const double excess = run.energy.value[k] - still.energy.value[k];
    lowest = std::min(lowest, excess);
    r.worstRise = std::max(r.worstRise, excess - lowest);
    r.left = excess;
    const double a = run.centre.value[k - 1] - draft, b = run.centre.value[k] - draft;
    r.crossings += run.energy.t[k] > kKickTime && a * b < 0 ? 1 : 0;
  }
  return r;
}

} // namespace pbf::validation
