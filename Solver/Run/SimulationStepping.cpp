// Simulation's time stepping: the size of the next step, a step with the solids moved and the
// outflows emptied, advance() and advanceTo(), and the emitters' layers released between steps.
#include "Simulation.h"

#include "SimulationText.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace pbf
{

using simulationtext::number;

void AdvanceReport::add(const AdvanceReport& more)
{
  if (more.steps == 0)
  {
    return;
  }
  minTimeStep = steps == 0 ? more.minTimeStep : std::min(minTimeStep, more.minTimeStep);
  maxTimeStep = std::max(maxTimeStep, more.maxTimeStep);
  steps += more.steps;
  iterations += more.iterations;
  removed += more.removed;
  densityError = more.densityError;
  milliseconds += more.milliseconds;
  seconds += more.seconds;
  impulses.resize(std::max(impulses.size(), more.impulses.size()));
  for (std::size_t k = 0; k < more.impulses.size(); ++k)
  {
    impulses[k].force += more.impulses[k].force;
    impulses[k].torque += more.impulses[k].torque;
  }
}

double Simulation::nextTimeStep() const
{
  const Parameters& p = parameters_;
  if (p.timeStepping == TimeStepping::Fixed)
  {
    return p.timeStep;
  }
  const double s = p.particleSpacing;
  const double v = std::max(
    { healthValid_ ? health_.robustSpeed : 0.0, limits_.sceneSpeed, fastestSolidPoint() });
  double dt = std::min({ p.timeStep, xsphStepLimit_, capillaryStepLimit_ });
  if (v > 0)
  {
    dt = std::min(dt, p.cflNumber * s / v);
  }
  // With solids the fastest moves at most cflNumber spacings, as every particle did before the
  // percentile: a prediction collides only where it lands, so a particle that crosses more than
  // half a solid's thickness in a step would be put out on its far side.
  const double fastest = healthValid_ ? health_.maxSpeed : 0.0;
  if (fastest > 0)
  {
    const double spacings = solidFields_.empty() ? kFastestStepSpacings : p.cflNumber;
    dt = std::min(dt, spacings * s / fastest);
  }
  const double g = length(p.gravity);
  if (g > 0)
  {
    dt = std::min(dt, p.cflNumber * std::sqrt(s / g));
  }
  return dt;
}

double Simulation::checkedTimeStep() const
{
  const double dt = nextTimeStep();
  // A largest step below the bound is the caller's own choice (validatePrecision checked it).
  if (!(dt >= std::min(kSmallestTimeStep, parameters_.timeStep)))
  {
    const std::string cause = "a particle moves at " + number(health_.maxSpeed) +
      " m/s; lower the initial speeds or gravity";
    throw SimulationDiverged("simulation diverged at step " + std::to_string(steps_) + " (t = " +
        number(time()) + " s): the automatic time step fell to " + number(dt) + " s, below " +
        number(kSmallestTimeStep) + " s. Likely cause: " + cause,
      steps_, time(), lastGoodStep_, cause);
  }
  return dt;
}

void Simulation::stepOnce(double dt, double end, AdvanceReport& report)
{
  if (dt != stepper_->timeStep() || !(pressureElapsed_ == stepperElapsed_))
  {
    stepper_->setTimeStep(dt, pressureElapsed_);
    stepperElapsed_ = pressureElapsed_;
  }
  moveBodies(dt, end);
  // The constraints hold at the step's end, with the solids where they are then.
  const std::vector<SolidPose> poses = solidPoses(end);
  if (!poses.empty())
  {
    stepper_->setObstaclePoses(poses);
  }
  stepper_->step();
  ++steps_;
  pressureElapsed_ += dt;
  healthValid_ = false;
  const StepReport step = stepper_->lastStep();
  report.iterations += step.iterations;
  report.densityError = step.densityError;
  report.minTimeStep = report.steps == 0 ? dt : std::min(report.minTimeStep, dt);
  report.maxTimeStep = std::max(report.maxTimeStep, dt);
  report.seconds += dt;
  ++report.steps;
  addLoads(step.loads, poses, dt, report);
  if (!outflowZones_.empty())
  {
    const std::size_t gone = stepper_->removeOutflow(outflowZones_);
    removed_ += gone;
    report.removed += gone;
  }
}

AdvanceReport Simulation::advance(std::uint64_t steps)
{
  AdvanceReport report;
  const auto start = std::chrono::steady_clock::now();
  const bool automatic = parameters_.timeStepping == TimeStepping::Automatic;
  for (std::uint64_t k = 0; k < steps; ++k)
  {
    pressureElapsed_ = 0; // each step's pressure is its own: the state after step k is one
    if (automatic && !healthValid_)
    {
      checkDivergence(); // the fastest particle, and the check for free
    }
    const double dt = checkedTimeStep();
    stepOnce(dt, time_ + dt, report);
    time_ += dt;
    if (automatic || (checkInterval_ > 0 && steps_ % checkInterval_ == 0))
    {
      checkDivergence();
    }
    emit();
  }
  pressureElapsed_ = 0;
  stepper_->synchronize();
  report.milliseconds =
    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return report;
}

bool Simulation::stepToward(double until, AdvanceReport& report)
{
  if (!(time_ < until))
  {
    return true;
  }
  const auto start = std::chrono::steady_clock::now();
  const bool automatic = parameters_.timeStepping == TimeStepping::Automatic;
  if (automatic && !healthValid_)
  {
    checkDivergence();
  }
  // A whole number of steps of at most nextTimeStep() to `until`; the relative slack keeps a
  // remaining time that is a multiple of a fixed step in rounding from costing one more step.
  const double remaining = until - time_;
  const double largest = checkedTimeStep();
  const double count = std::max(1.0, std::ceil(remaining / largest * (1.0 - 1e-9)));
  const bool fixedFits = !automatic && count * largest <= remaining * (1.0 + 1e-9);
  // Fixed steps stay exactly timeStep; only a remainder that is no multiple of it is shortened.
  const double dt = fixedFits || count == 1.0 ? (count == 1.0 ? remaining : largest)
                                              : remaining / count;
  const bool landed = count == 1.0;
  stepOnce(dt, landed ? until : time_ + dt, report);
  time_ = landed ? until : time_ + dt;
  if (landed)
  {
    pressureElapsed_ = 0; // the frame's mean is complete: the next step starts another
  }
  if (automatic || landed || (checkInterval_ > 0 && steps_ % checkInterval_ == 0))
  {
    checkDivergence();
  }
  emit();
  report.milliseconds +=
    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return landed;
}

AdvanceReport Simulation::advanceTo(double until)
{
  AdvanceReport report;
  while (!stepToward(until, report))
  {
  }
  stepper_->synchronize();
  return report;
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
            if (!scene_.liquids.empty())
            {
              batch.liquid.push_back(static_cast<std::uint8_t>(emitter.liquid));
            }
          }
        }
      }
    }
  }
  if (!batch.position.empty())
  {
    stepper_->append(batch);
    // The new particles (and the densities evaluated again at rest) are not in the last scan; a
    // run resumed from a checkpoint taken now scans them too, so the straight run does the same.
    healthValid_ = false;
  }
}

} // namespace pbf
