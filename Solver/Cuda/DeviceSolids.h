// The solid obstacles (Physics/Boundary.h) of a GPU stepper in one block of device memory: the
// grids' views, the boundary table (poly6, spiky, spiky2, tensile), then each grid's nodes. Laid
// out here once for both GPU steppers (CudaStepperSolids.cuh, DeviceSubdomainSolids.h), which
// differ only in how they allocate and copy.
#pragma once

#include "Boundary.h"
#include "SignedDistance.h"
#include "StepSchedule.h"

#include <vector>

namespace pbf::cuda
{

// Points `constants` at the solids (none: null, 0 and an empty table) and returns the block, or
// nullptr without solids. allocate(bytes) gives device memory, upload(device, host, bytes)
// copies into it, wait() returns once the copies are done (the host arrays die here).
template <class Real, class Allocate, class Upload, class Wait>
void* uploadSolids(const std::vector<DistanceGrid>& obstacles, const Parameters& parameters,
  StepConstants<Real>& constants, Allocate&& allocate, Upload&& upload, Wait&& wait)
{
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
  void* block = allocate(total);
  char* base = static_cast<char*>(block);
  std::vector<DistanceGridView<Real>> views;
  for (std::size_t k = 0; k < obstacles.size(); ++k)
  {
    const DistanceGrid& g = obstacles[k];
    upload(base + nodesAt[k], g.phi.data(), g.phi.size() * sizeof(float));
    views.push_back(g.view<Real>(reinterpret_cast<const float*>(base + nodesAt[k])));
  }
  upload(base, views.data(), views.size() * sizeof(DistanceGridView<Real>));
  Real* onDevice = reinterpret_cast<Real*>(base + viewBytes);
  upload(onDevice, table.data(), table.size() * sizeof(Real));
  wait();
  constants.obstacles = reinterpret_cast<const DistanceGridView<Real>*>(base);
  constants.obstacleCount = static_cast<int>(obstacles.size());
  constants.boundary = t.view(onDevice);
  return block;
}

} // namespace pbf::cuda
