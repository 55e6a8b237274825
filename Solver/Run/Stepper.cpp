#include "Stepper.h"

#include "CpuStepper.h"

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

void Stepper::setObstaclePoses(const std::vector<SolidPose>& poses)
{
  checkPoseCount(poses.size(), 0);
}

void checkPoseCount(std::size_t poses, std::size_t solids)
{
  if (poses != 0 && poses != solids)
  {
    throw InvalidInput("obstacle poses = " + std::to_string(poses) + ": there are " +
      std::to_string(solids) + " solid(s), one pose each");
  }
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
  copy(snapshot.id, out.id);
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
  h.maxDensityError = s.maxDensityError;
  return h;
}

#ifdef PBF_WITH_CUDA
// Defined in Cuda/CudaDevice.cu; declared here so that no CUDA header reaches the CPU build.
std::unique_ptr<Stepper> makeCudaStepper(
  Precision precision, const Parameters& parameters, const ParticleBatch& initial);
bool cudaDevicePresent(std::string* why);
#endif

bool cudaAvailable(std::string* why)
{
#ifdef PBF_WITH_CUDA
  return cudaDevicePresent(why);
#else
  if (why)
  {
    *why = "this build has no CUDA backend (CUDA compiler not found at configure time)";
  }
  return false;
#endif
}

std::unique_ptr<Stepper> makeStepper(Backend backend, Precision precision,
  const Parameters& parameters, const ParticleBatch& initial)
{
  switch (backend)
  {
    case Backend::Serial:
    case Backend::OpenMP:
    {
      const bool parallel = backend == Backend::OpenMP;
      if (precision == Precision::Single)
      {
        return std::make_unique<CpuStepper<float>>(parallel, parameters, initial);
      }
      return std::make_unique<CpuStepper<double>>(parallel, parameters, initial);
    }
    case Backend::CUDA:
    {
      std::string why;
      if (!cudaAvailable(&why))
      {
        throw std::runtime_error("CUDA backend unavailable: " + why);
      }
#ifdef PBF_WITH_CUDA
      return makeCudaStepper(precision, parameters, initial);
#endif
    }
  }
  throw std::runtime_error("unknown backend");
}

} // namespace pbf
