// The solid obstacles (Physics/Boundary.h) of a GPU stepper in one block of device memory: the
// grids' views, the boundary table (poly6, spiky, spiky2, tensile), then each grid's nodes. Laid
// out here once for both GPU steppers (DeviceStepperScans.h, DeviceSubdomainSolids.h), on their
// device policy.
#pragma once

#include "Boundary.h"
#include "SignedDistance.h"
#include "StepSchedule.h"

#include <vector>

namespace pbf::cuda
{

// Waits for the queued work, releases the previous block (`old`, may be null), points
// `constants` at the new solids (none: null, 0 and an empty table) and returns their block, or
// nullptr without solids. The copies are done when it returns (the host arrays die here).
template <class Real, class Device>
void* replaceSolids(Device& device, void* old, const std::vector<DistanceGrid>& obstacles,
  const Parameters& parameters, StepConstants<Real>& constants)
{
  device.activate();
  device.synchronize();
  if (old)
  {
    device.release(old);
  }
  constants.obstacles = nullptr;
  constants.obstacleCount = 0;
  constants.boundary = BoundaryTable<Real>{};
  if (obstacles.empty())
  {
    return nullptr;
  }
  const BoundaryTableData t = makeBoundaryTable(parameters);
  const std::vector<Real> table = t.packed<Real>();
  auto aligned = [](std::size_t bytes) { return (bytes + 255) / 256 * 256; };
  const std::size_t viewBytes = aligned(obstacles.size() * sizeof(DistanceGridView<Real>));
  std::size_t total = viewBytes + aligned(table.size() * sizeof(Real));
  std::vector<std::size_t> nodesAt;
  for (const DistanceGrid& g : obstacles)
  {
    nodesAt.push_back(total);
    total += aligned(g.phi.size() * sizeof(float));
  }
  void* block = device.allocate(total);
  char* base = static_cast<char*>(block);
  std::vector<DistanceGridView<Real>> views;
  for (std::size_t k = 0; k < obstacles.size(); ++k)
  {
    const DistanceGrid& g = obstacles[k];
    device.upload(base + nodesAt[k], g.phi.data(), g.phi.size() * sizeof(float));
    views.push_back(g.view<Real>(reinterpret_cast<const float*>(base + nodesAt[k])));
  }
  device.upload(base, views.data(), views.size() * sizeof(DistanceGridView<Real>));
  Real* onDevice = reinterpret_cast<Real*>(base + viewBytes);
  device.upload(onDevice, table.data(), table.size() * sizeof(Real));
  device.synchronize();
  constants.obstacles = reinterpret_cast<const DistanceGridView<Real>*>(base);
  constants.obstacleCount = static_cast<int>(obstacles.size());
  constants.boundary = t.view(onDevice);
  return block;
}

} // namespace pbf::cuda
