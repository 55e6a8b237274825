// DeviceSubdomainStepper's solid obstacles (Physics/Boundary.h): every rank holds every solid's
// distance grid (small beside the fluid), in one allocation of the device policy with their
// views and the boundary table, as CudaStepper does on one GPU (CudaStepperSolids.cuh); the
// passes read them through StepConstants, the masks allow for a particle a solid moves on
// (StepSchedule's correctionPass). Included at the end of DeviceSubdomainStepper.h; not a header
// of its own.
#pragma once

#include "DeviceSubdomainStepper.h"

namespace pbf::cuda
{

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::setObstacles(const std::vector<DistanceGrid>& obstacles)
{
  device_->activate();
  device_->synchronize();
  if (solids_)
  {
    device_->release(solids_);
    solids_ = nullptr;
  }
  constants_.obstacles = nullptr;
  constants_.obstacleCount = 0;
  constants_.boundary = BoundaryTable<Real>{};
  if (!obstacles.empty())
  {
    const BoundaryTableData t = makeBoundaryTable(parameters_);
    const std::vector<Real> table = t.packed<Real>();
    // Layout: the views, the table (poly6, spiky, spiky2, tensile), then each grid's nodes.
    auto aligned = [](std::size_t bytes) { return (bytes + 255) / 256 * 256; };
    const std::size_t viewBytes = aligned(obstacles.size() * sizeof(DistanceGridView<Real>));
    const std::size_t tableBytes = aligned(table.size() * sizeof(Real));
    std::size_t total = viewBytes + tableBytes;
    std::vector<std::size_t> nodesAt;
    for (const DistanceGrid& g : obstacles)
    {
      nodesAt.push_back(total);
      total += aligned(g.phi.size() * sizeof(float));
    }
    solids_ = device_->allocate(total);
    char* base = static_cast<char*>(solids_);
    std::vector<DistanceGridView<Real>> views;
    for (std::size_t k = 0; k < obstacles.size(); ++k)
    {
      const DistanceGrid& g = obstacles[k];
      device_->upload(base + nodesAt[k], g.phi.data(), g.phi.size() * sizeof(float));
      views.push_back(g.view<Real>(reinterpret_cast<const float*>(base + nodesAt[k])));
    }
    device_->upload(base, views.data(), views.size() * sizeof(DistanceGridView<Real>));
    Real* onDevice = reinterpret_cast<Real*>(base + viewBytes);
    device_->upload(onDevice, table.data(), table.size() * sizeof(Real));
    device_->synchronize(); // the host vectors die here
    constants_.obstacles = reinterpret_cast<const DistanceGridView<Real>*>(base);
    constants_.obstacleCount = static_cast<int>(obstacles.size());
    constants_.boundary = t.view(onDevice);
  }
  // As after an append: the state at rest, p = x, evaluated with the solids on every rank.
  cut(xBuffer_, -1);
  evaluateAtRest();
}

} // namespace pbf::cuda
