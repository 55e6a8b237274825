// The solid obstacles (Physics/Boundary.h) of a GPU stepper in one block of device memory: the
// grids' views, the boundary table (poly6, spiky, spiky2, tensile), the loads' sums (StepConstants'
// loads and loadBlockSums), then each grid's nodes, its shape map and its normals. Laid
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
// `constants` at the new solids (none: null, 0 and an empty table) placed at `poses` (none: as
// sampled) and returns their block, or nullptr without solids; `views` receives the views as
// sampled, for placeSolids. The copies are done when it returns (the host arrays die here).
template <class Real, class Device>
void* replaceSolids(Device& device, void* old, const std::vector<DistanceGrid>& obstacles,
  const std::vector<SolidPose>& poses, const Parameters& parameters,
  StepConstants<Real>& constants, std::vector<DistanceGridView<Real>>& views)
{
  checkPoseCount(poses.size(), obstacles.size());
  device.activate();
  device.synchronize();
  if (old)
  {
    device.release(old);
  }
  constants.obstacles = nullptr;
  constants.obstacleCount = 0;
  constants.boundary = BoundaryTable<Real>{};
  constants.loads = nullptr;
  constants.loadBlockSums = nullptr;
  if (obstacles.empty())
  {
    return nullptr;
  }
  const BoundaryTableData t = makeBoundaryTable(parameters);
  const std::vector<Real> table = t.packed<Real>();
  auto aligned = [](std::size_t bytes) { return (bytes + 255) / 256 * 256; };
  const std::size_t viewBytes = aligned(obstacles.size() * sizeof(DistanceGridView<Real>));
  const std::size_t loadsAt = viewBytes + aligned(table.size() * sizeof(Real));
  const std::size_t loadBytes = aligned(obstacles.size() * kLoadValues * sizeof(double));
  const std::size_t blockSumsAt = loadsAt + loadBytes;
  std::size_t total = blockSumsAt +
    aligned(obstacles.size() * std::size_t(kLoadBlocks) * kLoadValues * sizeof(double));
  std::vector<std::size_t> nodesAt, shapeAt, normalAt;
  for (const DistanceGrid& g : obstacles)
  {
    nodesAt.push_back(total);
    total += aligned(g.phi.size() * sizeof(float));
    shapeAt.push_back(total);
    total += aligned(g.shape.size() * sizeof(float));
    normalAt.push_back(total);
    total += aligned(g.normal.size() * sizeof(float));
  }
  void* block = device.allocate(total);
  char* base = static_cast<char*>(block);
  views.clear();
  std::vector<DistanceGridView<Real>> placedViews;
  for (std::size_t k = 0; k < obstacles.size(); ++k)
  {
    const DistanceGrid& g = obstacles[k];
    device.upload(base + nodesAt[k], g.phi.data(), g.phi.size() * sizeof(float));
    const float* shape = nullptr;
    if (!g.shape.empty())
    {
      device.upload(base + shapeAt[k], g.shape.data(), g.shape.size() * sizeof(float));
      shape = reinterpret_cast<const float*>(base + shapeAt[k]);
    }
    const float* normal = nullptr;
    if (!g.normal.empty())
    {
      device.upload(base + normalAt[k], g.normal.data(), g.normal.size() * sizeof(float));
      normal = reinterpret_cast<const float*>(base + normalAt[k]);
    }
    views.push_back(
      g.view<Real>(reinterpret_cast<const float*>(base + nodesAt[k]), shape, normal));
    placedViews.push_back(poses.empty() ? views.back() : placed(views.back(), poses[k]));
  }
  device.upload(base, placedViews.data(), placedViews.size() * sizeof(DistanceGridView<Real>));
  Real* onDevice = reinterpret_cast<Real*>(base + viewBytes);
  device.upload(onDevice, table.data(), table.size() * sizeof(Real));
  auto exec = device.executor();
  exec.fillZero(base + loadsAt, loadBytes);
  device.synchronize();
  constants.obstacles = reinterpret_cast<const DistanceGridView<Real>*>(base);
  constants.loads = reinterpret_cast<double*>(base + loadsAt);
  constants.loadBlockSums = reinterpret_cast<double*>(base + blockSumsAt);
  constants.obstacleCount = static_cast<int>(obstacles.size());
  constants.boundary = t.view(onDevice);
  return block;
}

// The solids' views placed at `poses` (one per solid), copied over those the steps read, ordered
// before the next step (the policy stages the bytes, so the host copy may go at once). A graph
// captured before reads them too: it holds their address, not their values.
template <class Real, class Device>
void placeSolids(Device& device, const StepConstants<Real>& constants,
  const std::vector<DistanceGridView<Real>>& views, const std::vector<SolidPose>& poses)
{
  checkPoseCount(poses.size(), views.size());
  if (poses.empty())
  {
    return;
  }
  std::vector<DistanceGridView<Real>> placedViews;
  for (std::size_t k = 0; k < views.size(); ++k)
  {
    placedViews.push_back(placed(views[k], poses[k]));
  }
  device.activate();
  device.upload(const_cast<DistanceGridView<Real>*>(constants.obstacles), placedViews.data(),
    placedViews.size() * sizeof(DistanceGridView<Real>));
}

} // namespace pbf::cuda
