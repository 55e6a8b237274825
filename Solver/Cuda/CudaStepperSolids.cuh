// CudaStepper's solid obstacles (Physics/Boundary.h) on the device: the distance grids, their
// views and the boundary table in one allocation (DeviceSolids.h), read by the same stage
// functions as on the CPU.
// Included at the end of CudaStepper.cuh; not a header of its own.
#pragma once

#include "CudaStepper.cuh"
#include "DeviceSolids.h"

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
  solids_ = uploadSolids(
    obstacles, parameters_, constants_,
    [](std::size_t bytes) {
      void* block = nullptr;
      check(cudaMalloc(&block, bytes), "cudaMalloc (obstacles)");
      return block;
    },
    [](void* device, const void* host, std::size_t bytes) {
      check(cudaMemcpy(device, host, bytes, cudaMemcpyHostToDevice), "cudaMemcpy (obstacles)");
    },
    [] {});
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
