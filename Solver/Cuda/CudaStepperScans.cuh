// CudaStepper's scans of its particles: statistics() and health(), over the reductions of
// CudaReductions.cuh (per block, then one block in a fixed order: no float atomics).
// Included at the end of CudaStepper.cuh; not a header of its own.
#pragma once

#include "CudaStepper.cuh"

namespace pbf
{
namespace cuda
{

template <class Real>
Statistics CudaStepper<Real>::statistics() const
{
  Statistics s;
  s.particles = n_;
  if (n_ == 0)
  {
    return s;
  }
  selectDevice();
  const double h = parameters_.smoothingLength();
  // Neighbours at the current positions on a grid of their own, as the CPU counts them. Between
  // steps the keys, C, D and the cell offsets are free: the next step rebuilds them.
  const StepBuffers<Real>& b = buffers_;
  const auto n = static_cast<std::uint32_t>(n_);
  std::uint32_t* order = reinterpret_cast<std::uint32_t*>(b.vec[2]);
  KernelExecutor exec = executor();
  const CellKey* keys = enqueueSortedCopy(exec, constants_, n, b.vec[roles_.x], b.keys[0],
    b.keys[1], order, order + capacity_, b.vec[3], b.cellOffsets);
  const GridView<Real> grid{ constants_.geometry, b.cellOffsets, keys };
  statisticsKernel<Real><<<kStatisticsBlocks, kStatisticsThreads, 0, stream_>>>(
    b.vec[roles_.x], b.vec[roles_.v], b.density, b.vec[3], grid, n, h * h,
    calibratedParticleMass(parameters_), parameters_.restDensity, statisticsPartials_);
  check(cudaGetLastError(), "kernel launch (statistics)");
  statisticsFinalKernel<Real><<<1, kStatisticsThreads, 0, stream_>>>(
    statisticsPartials_, kStatisticsBlocks, statisticsResult_);
  check(cudaGetLastError(), "kernel launch (statistics)");
  double r[kStatisticsValues];
  check(cudaMemcpyAsync(r, statisticsResult_, sizeof r, cudaMemcpyDeviceToHost, stream_),
    "cudaMemcpyAsync");
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
  const double count = static_cast<double>(n_);
  s.averageDensityError = r[kErrorSum] / count;
  s.maxDensityError = r[kErrorMax];
  s.averageNeighbors = r[kNeighborSum] / count;
  s.maxSpeed = r[kSpeedMax];
  s.kineticEnergy = r[kKinetic];
  s.momentum = Vec3d{ r[kMomentumX], r[kMomentumY], r[kMomentumZ] };
  s.finite = r[kNonFinite] == 0.0;
  return s;
}

template <class Real>
Health CudaStepper<Real>::health() const
{
  Health h;
  if (n_ == 0)
  {
    return h;
  }
  selectDevice();
  const StepBuffers<Real>& b = buffers_;
  healthKernel<Real><<<kHealthBlocks, kStatisticsThreads, 0, stream_>>>(b.vec[roles_.x],
    b.vec[roles_.v], b.density, static_cast<std::uint32_t>(n_), 1.0 / parameters_.restDensity,
    statisticsPartials_);
  check(cudaGetLastError(), "kernel launch (health)");
  healthFinalKernel<<<1, 1, 0, stream_>>>(statisticsPartials_, kHealthBlocks, statisticsResult_);
  check(cudaGetLastError(), "kernel launch (health)");
  double r[kHealthValues];
  check(cudaMemcpyAsync(r, statisticsResult_, sizeof r, cudaMemcpyDeviceToHost, stream_),
    "cudaMemcpyAsync");
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
  h.maxSpeed = std::sqrt(r[0]);
  h.maxDensityError = r[1];
  h.nonFinite = r[2] > 0.0 ? 1 : 0;
  return h;
}

} // namespace cuda
} // namespace pbf
