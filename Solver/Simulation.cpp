#include "Simulation.h"

#include <chrono>
#include <cmath>

namespace pbf
{

Simulation::Simulation(
  const Scene& scene, const Parameters& parameters, Backend backend, Precision precision)
  : Simulation(scene, parameters, backend, precision,
      fillScene(scene, withSceneDomain(parameters, scene)))
{
}

Simulation::Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
  Precision precision, const ParticleBatch& initial)
  : scene_(scene)
  , parameters_(withSceneDomain(parameters, scene))
  , layersEmitted_(scene.emitters.size(), 0)
{
  parameters_.validate();
  if (initial.position.empty() && scene_.emitters.empty())
  {
    throw InvalidInput("particle count = 0: the fluid is empty");
  }
  stepper_ = makeStepper(backend, precision, parameters_, initial);
  nextId_ = static_cast<std::int64_t>(initial.position.size());
  emit();
}

AdvanceReport Simulation::advance(std::uint64_t steps)
{
  AdvanceReport report;
  const auto start = std::chrono::steady_clock::now();
  for (std::uint64_t k = 0; k < steps; ++k)
  {
    stepper_->step();
    ++steps_;
    emit();
    const StepReport step = stepper_->lastStep();
    report.iterations += step.iterations;
    report.densityError = step.densityError;
  }
  stepper_->synchronize();
  report.steps = steps;
  report.milliseconds =
    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return report;
}

std::size_t SimulationCheckpoint::bytes() const
{
  return std::visit(
    [this](const auto& s) {
      return s.position.size() * sizeof(s.position[0]) + s.velocity.size() * sizeof(s.velocity[0]) +
        s.density.size() * sizeof(s.density[0]) + s.lambda.size() * sizeof(s.lambda[0]) +
        s.id.size() * sizeof(s.id[0]) + layersEmitted.size() * sizeof(std::int64_t);
    },
    state);
}

SimulationCheckpoint Simulation::checkpoint() const
{
  SimulationCheckpoint c;
  c.steps = steps_;
  c.nextId = nextId_;
  c.layersEmitted = layersEmitted_;
  if (stepper_->precision() == Precision::Single)
  {
    Snapshot<float> s;
    stepper_->read(s);
    c.state = std::move(s);
  }
  else
  {
    Snapshot<double> s;
    stepper_->read(s);
    c.state = std::move(s);
  }
  return c;
}

void Simulation::restore(const SimulationCheckpoint& c)
{
  if (c.layersEmitted.size() != layersEmitted_.size())
  {
    throw InvalidInput("checkpoint emitters = " + std::to_string(c.layersEmitted.size()) +
      ": the scene has " + std::to_string(layersEmitted_.size()));
  }
  std::visit([this](const auto& s) { stepper_->load(s); }, c.state);
  steps_ = c.steps;
  nextId_ = c.nextId;
  layersEmitted_ = c.layersEmitted;
}

// Each emitter releases one disk of lattice sites every s / speed seconds. A layer released
// between steps is advanced along the jet by the time it has already travelled, so layers stay
// one spacing apart whatever the time step.
void Simulation::emit()
{
  const double s = parameters_.particleSpacing;
  const double t = time();
  ParticleBatch batch;
  for (std::size_t e = 0; e < scene_.emitters.size(); ++e)
  {
    const Emitter& emitter = scene_.emitters[e];
    if (t < emitter.start)
    {
      continue;
    }
    const double interval = s / emitter.speed;
    const double until = std::min(t, emitter.stop - 1e-12);
    const auto due = static_cast<std::int64_t>(std::floor((until - emitter.start) / interval)) + 1;
    // Two unit vectors across the jet.
    const Vec3d d = emitter.direction;
    const Vec3d helper = std::abs(d.x) < 0.9 ? Vec3d{ 1, 0, 0 } : Vec3d{ 0, 1, 0 };
    Vec3d u = cross(d, helper);
    u *= 1.0 / length(u);
    const Vec3d w = cross(d, u);
    const long n = static_cast<long>(std::floor(emitter.radius / s));
    for (; layersEmitted_[e] < due; ++layersEmitted_[e])
    {
      const double released = emitter.start + static_cast<double>(layersEmitted_[e]) * interval;
      const Vec3d origin = emitter.center + d * (emitter.speed * (t - released));
      for (long a = -n; a <= n; ++a)
      {
        for (long b = -n; b <= n; ++b)
        {
          if ((a * a + b * b) * s * s <= emitter.radius * emitter.radius)
          {
            batch.position.push_back(origin + u * (s * a) + w * (s * b));
            batch.velocity.push_back(d * emitter.speed);
            batch.id.push_back(nextId_++);
          }
        }
      }
    }
  }
  if (!batch.position.empty())
  {
    stepper_->append(batch);
  }
}

} // namespace pbf
