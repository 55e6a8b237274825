// Simulation's divergence check: the scan's findings against DivergenceLimits, and the likely
// cause that SimulationDiverged names.
#include "Simulation.h"

#include "SimulationText.h"

#include <string>
#include <vector>

namespace pbf
{

using simulationtext::number;


void Simulation::checkDivergence()
{
  const Health health = stepper_->health();
  health_ = health;
  healthValid_ = true;
  std::vector<std::string> found;
  const auto which = [&](std::size_t count, const std::string& what) {
    std::string text = std::to_string(count) + (count == 1 ? " particle " : " particles ") + what;
    if (health.firstBadId >= 0)
    {
      text += " (particle id " + std::to_string(health.firstBadId) + " among them)";
    }
    found.push_back(text);
  };
  if (health.nonFinite > 0)
  {
    which(health.nonFinite, "with a non-finite position or velocity");
  }
  if (health.outside > 0)
  {
    which(health.outside, "farther than one spacing outside the domain");
  }
  if (health.maxSpeed > limits_.maxSpeed)
  {
    found.push_back("the fastest particle moves at " + number(health.maxSpeed) +
      " m/s, beyond the limit of " + number(limits_.maxSpeed) +
      " m/s (20 x the scene's speed sqrt(v0^2 + 2 |g| L) = " + number(limits_.sceneSpeed) +
      " m/s, or 2 h / dt)");
  }
  if (health.maxDensityError > limits_.maxDensityError)
  {
    found.push_back("the densest particle reads " +
      number((1.0 + health.maxDensityError) * parameters_.restDensity) + " kg/m^3, " +
      number(1.0 + health.maxDensityError) + " x restDensity (the limit is " +
      number(1.0 + limits_.maxDensityError) + " x): particles are piling up");
  }
  if (found.empty())
  {
    lastGoodStep_ = steps_;
    lastGoodSpeed_ = health.maxSpeed;
    return;
  }
  std::string text;
  for (const std::string& f : found)
  {
    text += (text.empty() ? "" : "; ") + f;
  }
  const std::string cause = likelyCause();
  throw SimulationDiverged("simulation diverged at step " + std::to_string(steps_) + " (t = " +
      number(time()) + " s; last good check at step " + std::to_string(lastGoodStep_) + "): " +
      text + ". Likely cause: " + cause,
    steps_, time(), lastGoodStep_, cause);
}

// Rules of thumb, from runs that blew up (dam break at s = 0.05 m): dt = 0.05 s (12 x the
// default); gravity 1e4 m/s^2; one iteration at dt = 1/60 s; Unilateral off. A tiny relaxation
// alone did not blow up, but it removes the damping the others need.
std::string Simulation::likelyCause() const
{
  const Parameters& p = parameters_;
  const double h = p.smoothingLength();
  const double dt = stepper_->timeStep();
  const double cfl = lastGoodSpeed_ * dt / h;
  const double fall = length(p.gravity) * dt * dt / p.particleSpacing;
  std::vector<std::string> causes;
  if (!p.unilateral)
  {
    causes.push_back("Unilateral is off: C_i < 0 at the free surface pulls particles together; "
                     "turn it on");
  }
  if (cfl > 1.0 || fall > 0.1)
  {
    std::string why;
    if (cfl > 1.0)
    {
      why = "at the last good check (step " + std::to_string(lastGoodStep_) +
        ") the fastest particle moved " + number(cfl) +
        " smoothing lengths in a step (CFL dt v_max / h; PBF needs well under 1)";
    }
    if (fall > 0.1)
    {
      why += (why.empty() ? "" : ", and ") + std::string("gravity alone moves a particle ") +
        number(fall) + " spacings per step (|g| dt^2 / s)";
    }
    causes.push_back("the time step dt = " + number(dt) + " s is too large: " + why +
      (p.timeStepping == TimeStepping::Fixed
          ? "; lower timeStep (more substeps per frame) or use automatic time stepping"
          : "; lower cflNumber or the largest time step"));
  }
  if (p.solverIterations < 3)
  {
    causes.push_back("too few solver iterations (solverIterations = " +
      std::to_string(p.solverIterations) +
      "): the density constraint is not enforced; raise it (paper: 2-4, default 4)");
  }
  if (p.relaxation < 1e-3)
  {
    causes.push_back("the relaxation epsilon = " + number(p.relaxation) +
      " is too small: lambda is left undamped where neighbours are few; raise relaxation "
      "(default 0.01)");
  }
  if (causes.empty())
  {
    causes.push_back("no parameter stands out: lower timeStep first, then check the initial "
                     "velocities, gravity and emitters against the spacing");
  }
  std::string text;
  for (const std::string& c : causes)
  {
    text += (text.empty() ? "" : "; ") + c;
  }
  return text;
}

} // namespace pbf
