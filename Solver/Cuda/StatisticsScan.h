// What a GPU stepper's statistics() reduces over its particles, in double: the inputs (the
// particles, and their positions sorted into a grid of their own for the neighbour count, as the
// CPU counts them) and the order of the values the device policy's scanStatistics writes. The
// CUDA policy reduces per block and then by one block in a fixed order (CudaReductions.cuh); the
// host policy of the tests in one loop.
#pragma once

#include "Grid.h"
#include "HostDevice.h"
#include "Parameters.h"
#include "Vec3.h"

#include <cstdint>

namespace pbf
{
namespace cuda
{

enum StatisticsValue
{
  kErrorSum,
  kErrorMax,
  kNeighborSum,
  kSpeedMax,
  kKinetic,
  kMomentumX,
  kMomentumY,
  kMomentumZ,
  kNonFinite, // max of 0/1
  kStatisticsValues
};

template <class Real>
struct StatisticsScan
{
  const Vec3<Real>* x;
  const Vec3<Real>* v;
  const Real* density;
  const Vec3<Real>* sorted; // x sorted by cell: `grid`'s order
  GridView<Real> grid;
  std::uint32_t n;
  double h2;
  double mass;
  double restDensity;
  // Each particle's liquid and the liquids' masses (LiquidMasses); null: every particle `mass`.
  const std::uint8_t* liquid;
  double masses[kMaxLiquids];
  PBF_HD PBF_INLINE double massOf(std::uint32_t i) const { return liquid ? masses[liquid[i]] : mass; }
};

} // namespace cuda
} // namespace pbf
