// Simulation's checkpoints: the whole state copied, and restored to continue bit-identically.
#include "Simulation.h"

#include <limits>
#include <variant>

namespace pbf
{

std::size_t SimulationCheckpoint::bytes() const
{
  return std::visit(
    [this](const auto& s) {
      return s.position.size() * sizeof(s.position[0]) + s.velocity.size() * sizeof(s.velocity[0]) +
        s.density.size() * sizeof(s.density[0]) + s.lambda.size() * sizeof(s.lambda[0]) +
        s.pressure.size() * sizeof(s.pressure[0]) +
        s.id.size() * sizeof(s.id[0]) + s.liquid.size() + layersEmitted.size() * sizeof(std::int64_t) +
        bodyStates.size() * sizeof(RigidState) + bodyLoads.size() * sizeof(SolidLoad);
    },
    state);
}

SimulationCheckpoint Simulation::checkpoint() const
{
  SimulationCheckpoint c;
  c.steps = steps_;
  c.time = time_;
  c.nextId = nextId_;
  c.removed = removed_;
  c.pressureElapsed = pressureElapsed_;
  c.layersEmitted = layersEmitted_;
  for (const Body& body : bodies_)
  {
    c.bodyStates.push_back(body.state);
    c.bodyLoads.push_back(body.load);
  }
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
  if (c.bodyStates.size() != bodies_.size())
  {
    throw InvalidInput("checkpoint bodies = " + std::to_string(c.bodyStates.size()) +
      ": the scene has " + std::to_string(bodies_.size()));
  }
  for (std::size_t k = 0; k < bodies_.size(); ++k)
  {
    bodies_[k].state = c.bodyStates[k];
    bodies_[k].load = c.bodyLoads[k];
  }
  if (!bodies_.empty())
  {
    stepper_->setObstaclePoses(solidPoses(c.time));
  }
  std::visit([this](const auto& s) { stepper_->load(s); }, c.state);
  steps_ = c.steps;
  time_ = c.time;
  nextId_ = c.nextId;
  removed_ = c.removed;
  pressureElapsed_ = c.pressureElapsed;
  stepperElapsed_ = std::numeric_limits<double>::quiet_NaN(); // the next step sets it again
  layersEmitted_ = c.layersEmitted;
  lastGoodStep_ = steps_;
  // The next automatic step needs the fastest particle, which a fresh scan gives exactly as the
  // straight run had it (the scan reads only the restored state).
  healthValid_ = false;
  if (checkInterval_ > 0 || parameters_.timeStepping == TimeStepping::Automatic)
  {
    health_ = stepper_->health();
    healthValid_ = true;
    lastGoodSpeed_ = health_.maxSpeed;
  }
  else
  {
    lastGoodSpeed_ = std::numeric_limits<double>::quiet_NaN();
  }
}

} // namespace pbf
