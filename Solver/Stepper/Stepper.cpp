#include "Stepper.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pbf
{

void Stepper::setObstacles(const std::vector<DistanceGrid>& obstacles, const std::vector<SolidPose>&)
{
  if (!obstacles.empty())
  {
    throw InvalidInput("obstacles: " + std::to_string(obstacles.size()) +
      " solid(s) given to the " + description() +
      " backend, which has no solid obstacles (every backend of this build has them: a stepper "
      "outside it must implement Stepper::setObstacles)");
  }
}

std::size_t Stepper::removeOutflow(const std::vector<Box>& zones)
{
  if (!zones.empty())
  {
    throw InvalidInput("outflows: " + std::to_string(zones.size()) + " zone(s) given to the " +
      description() + " backend, which removes no particles (every backend of this build does: a "
      "stepper outside it must implement Stepper::removeOutflow)");
  }
  return 0;
}

void Stepper::setObstaclePoses(const std::vector<SolidPose>& poses)
{
  checkPoseCount(poses.size(), 0);
}

const char* toString(Backend backend)
{
  switch (backend)
  {
    case Backend::Serial:
      return "Serial";
    case Backend::OpenMP:
      return "OpenMP";
    case Backend::CUDA:
      return "CUDA";
  }
  return "unknown";
}

const char* toString(Precision precision)
{
  return precision == Precision::Single ? "single" : "double";
}

namespace
{

template <class Real>
void readThroughSnapshot(const Stepper& stepper, const SnapshotView<Real>& out)
{
  Snapshot<Real> snapshot;
  stepper.read(snapshot);
  const auto copy = [](const auto& from, auto* to) {
    if (to)
    {
      std::copy(from.begin(), from.end(), to);
    }
  };
  copy(snapshot.position, out.position);
  copy(snapshot.velocity, out.velocity);
  copy(snapshot.density, out.density);
  copy(snapshot.lambda, out.lambda);
  copy(snapshot.pressure, out.pressure);
  copy(snapshot.id, out.id);
  copy(snapshot.liquid, out.liquid); // nothing where the scene names no liquids
}

} // namespace

void Stepper::readInto(const SnapshotView<float>& out) const
{
  readThroughSnapshot(*this, out);
}

void Stepper::readInto(const SnapshotView<double>& out) const
{
  readThroughSnapshot(*this, out);
}

void checkTimeStep(double dt)
{
  if (!(dt > 0.0) || !std::isfinite(dt))
  {
    throw InvalidInput("time step = " + std::to_string(dt) + ": must be a positive finite number");
  }
}

Health Stepper::health() const
{
  const Statistics s = statistics();
  Health h;
  h.nonFinite = s.finite ? 0 : 1;
  h.maxSpeed = s.maxSpeed;
  h.robustSpeed = s.maxSpeed; // no histogram here: the fastest, the safe side
  h.maxDensityError = s.maxDensityError;
  return h;
}

} // namespace pbf
