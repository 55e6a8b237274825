// CudaStepper's solid obstacles (Physics/Boundary.h) on the device: the distance grids, their
// views and the boundary table in one allocation, read by the same stage functions as on the CPU.
// Included at the end of CudaStepper.cuh; not a header of its own.
#pragma once

#include "CudaStepper.cuh"

namespace pbf
{
namespace cuda
{

template <class Real>
void CudaStepper<Real>::setObstacles(const std::vector<DistanceGrid>& obstacles)
{
  selectDevice();
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
  cudaFree(solids_);
  solids_ = nullptr;
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
    check(cudaMalloc(&solids_, total), "cudaMalloc (obstacles)");
    char* base = static_cast<char*>(solids_);
    std::vector<DistanceGridView<Real>> views;
    for (std::size_t k = 0; k < obstacles.size(); ++k)
    {
      const DistanceGrid& g = obstacles[k];
      check(cudaMemcpy(base + nodesAt[k], g.phi.data(), g.phi.size() * sizeof(float),
              cudaMemcpyHostToDevice),
        "cudaMemcpy (obstacle grid)");
      views.push_back(g.view<Real>(reinterpret_cast<const float*>(base + nodesAt[k])));
    }
    check(cudaMemcpy(base, views.data(), views.size() * sizeof(DistanceGridView<Real>),
            cudaMemcpyHostToDevice),
      "cudaMemcpy (obstacle views)");
    Real* onDevice = reinterpret_cast<Real*>(base + viewBytes);
    check(cudaMemcpy(onDevice, table.data(), table.size() * sizeof(Real), cudaMemcpyHostToDevice),
      "cudaMemcpy (boundary table)");
    constants_.obstacles = reinterpret_cast<const DistanceGridView<Real>*>(base);
    constants_.obstacleCount = static_cast<int>(obstacles.size());
    constants_.boundary = t.view(onDevice);
  }
  // The captured step holds the constants it was captured with.
  if (n_ > 0)
  {
    evaluateAtRest();
  }
  captureGraphs();
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
}

} // namespace cuda
} // namespace pbf
