// The uniform grid of Green 2008 ("CUDA Particles"): cells of size h over the domain, particles
// sorted by cell key so that a particle's neighbours lie in the 27 cells around its own.
#pragma once

#include "HostDevice.h"
#include "Parameters.h"
#include "Vec3.h"

#include <cmath>
#include <cstdint>
#include <string>

namespace pbf
{

using CellKey = std::uint32_t;

template <class Real>
struct GridGeometry
{
  Vec3<Real> origin;
  Real inverseCellSize;
  int nx, ny, nz;
  // The first of the domain's columns along x that the grid holds: a rank's window of its slab
  // and ghosts (DeviceSubdomainStepper), so that its cells are its share of the domain's. A
  // column is found from the domain's origin as with the whole grid and then offset, so the
  // window sorts its particles in the same order, bit for bit; 0: the whole domain.
  int firstColumn = 0;

  std::uint32_t cellCount() const { return static_cast<std::uint32_t>(nx) * ny * nz; }

  // Points outside the domain clamp into the border cells, so every particle has a valid key.
  PBF_HD PBF_INLINE int clampedCell(Real coordinate, Real originAxis, int n) const
  {
    const Real f = (coordinate - originAxis) * inverseCellSize;
    // NaN and huge values compare false against everything: route them to cell n - 1 too,
    // before the conversion (converting them to int is undefined).
    if (!(f < static_cast<Real>(n)))
    {
      return n - 1;
    }
    return f >= Real(0) ? static_cast<int>(f) : 0;
  }

  PBF_HD PBF_INLINE CellKey keyOf(const Vec3<Real>& p) const
  {
    const int column = clampedCell(p.x, origin.x, nx + firstColumn) - firstColumn;
    const int cx = column > 0 ? column : 0;
    const int cy = clampedCell(p.y, origin.y, ny);
    const int cz = clampedCell(p.z, origin.z, nz);
    return (static_cast<CellKey>(cz) * ny + cy) * nx + cx;
  }
};

// Cell count limit: keys are 32-bit and cellOffsets holds one entry per cell.
constexpr std::uint64_t kMaxGridCells = std::uint64_t(1) << 30;

// Throws InvalidInput when the domain holds too many cells of size h.
template <class Real>
GridGeometry<Real> makeGridGeometry(const Box& domain, double h)
{
  auto cells = [h](double lo, double hi) {
    const double n = std::ceil((hi - lo) / h);
    return n < 1.0 ? 1.0 : n;
  };
  const double nx = cells(domain.min.x, domain.max.x);
  const double ny = cells(domain.min.y, domain.max.y);
  const double nz = cells(domain.min.z, domain.max.z);
  if (nx * ny * nz > static_cast<double>(kMaxGridCells))
  {
    throw InvalidInput("domain / smoothing length = " + std::to_string(nx * ny * nz) +
      " grid cells: more than the " + std::to_string(kMaxGridCells) +
      " supported; enlarge particleSpacing or shrink the domain");
  }
  GridGeometry<Real> g;
  g.origin = Vec3<Real>::from(domain.min);
  g.inverseCellSize = static_cast<Real>(1.0 / h);
  g.nx = static_cast<int>(nx);
  g.ny = static_cast<int>(ny);
  g.nz = static_cast<int>(nz);
  return g;
}

// What a neighbour loop reads: the geometry, cellOffsets[c]..cellOffsets[c+1] as the sorted
// index range of cell c (cellCount + 1 entries, so empty cells need no marker), and each sorted
// particle's own cell key.
template <class Real>
struct GridView
{
  GridGeometry<Real> geometry;
  const std::uint32_t* cellOffsets;
  const CellKey* particleKeys;
};

// Calls visit(j) for every particle j in the 27 cells around particle i's cell (i included), in
// ascending sorted index, the same order on every backend. Cells along x are adjacent keys, so
// each of the 9 rows is one contiguous index range.
template <class Real, class Visit>
PBF_HD PBF_INLINE void forEachNeighbor(const GridView<Real>& grid, std::uint32_t i, Visit&& visit)
{
  const GridGeometry<Real>& g = grid.geometry;
  const CellKey key = grid.particleKeys[i];
  const int cx = static_cast<int>(key % static_cast<CellKey>(g.nx));
  const int cy = static_cast<int>((key / static_cast<CellKey>(g.nx)) % static_cast<CellKey>(g.ny));
  const int cz = static_cast<int>(key / (static_cast<CellKey>(g.nx) * g.ny));
  const int x0 = cx > 0 ? cx - 1 : 0;
  const int x1 = cx + 1 < g.nx ? cx + 1 : cx;
  for (int z = cz - 1; z <= cz + 1; ++z)
  {
    if (z < 0 || z >= g.nz)
    {
      continue;
    }
    for (int y = cy - 1; y <= cy + 1; ++y)
    {
      if (y < 0 || y >= g.ny)
      {
        continue;
      }
      const CellKey row = (static_cast<CellKey>(z) * g.ny + y) * g.nx;
      const std::uint32_t begin = grid.cellOffsets[row + x0];
      const std::uint32_t end = grid.cellOffsets[row + x1 + 1];
      for (std::uint32_t j = begin; j < end; ++j)
      {
        visit(j);
      }
    }
  }
}

} // namespace pbf
