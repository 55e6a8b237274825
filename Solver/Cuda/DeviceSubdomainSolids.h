// DeviceSubdomainStepper's solid obstacles (Physics/Boundary.h): every rank holds every solid's
// distance grid (small beside the fluid), in one allocation of the device policy with their
// views and the boundary table (DeviceSolids.h, as DeviceStepper on one GPU); the
// passes read them through StepConstants, the masks allow for a particle a solid moves on
// (StepSchedule's correctionPass). Included at the end of DeviceSubdomainStepper.h; not a header
// of its own.
#pragma once

#include "DeviceSolids.h"

namespace pbf::cuda
{

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::setObstacles(
  const std::vector<DistanceGrid>& obstacles, const std::vector<SolidPose>& poses)
{
  solids_ =
    replaceSolids(*device_, solids_, obstacles, poses, parameters_, constants_, solidViews_);
  // As after an append: the state at rest, p = x, evaluated with the solids on every rank.
  cut(xBuffer_, -1);
  evaluateAtRest();
}

// Every rank places every solid alike: a pose is a function of the time alone.
template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::setObstaclePoses(const std::vector<SolidPose>& poses)
{
  placeSolids(*device_, constants_, solidViews_, poses);
}

} // namespace pbf::cuda
