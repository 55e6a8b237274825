// The GPU surface's kernels and device predicates (CudaSurface.cu runs them): the particles
// sorted into cells, the narrow band's blocks, the kept blocks' cells cut into triangles, the
// smoothing and the fields at the vertices. Included by CudaSurface.cu alone, and everything is in
// an anonymous namespace there: no kernel is instantiated identically in another CUDA translation
// unit (SubdomainSchedule.h says why that matters).
#pragma once

#include "CudaRuntime.cuh"
#include "SurfaceCells.h"

#include <cuda_runtime.h>

#include <cstdint>

namespace pbf
{
namespace cuda
{
namespace
{

using surface::kBlock;
using surface::kBlockCells;
using surface::kBlockNodes;

constexpr int kThreads = 256;       // the per-particle and per-vertex kernels
constexpr int kSampleThreads = 256; // a block's 729 nodes, three per thread

unsigned gridFor(std::size_t n, int threads)
{
  return static_cast<unsigned>((n + static_cast<std::size_t>(threads) - 1) / threads);
}

// Order-preserving unsigned bits of a coordinate, for the radix sorts by position.
template <class Real>
struct OrderBits;
template <>
struct OrderBits<float>
{
  using type = std::uint32_t;
  __device__ static type of(float f)
  {
    const std::uint32_t u = __float_as_uint(f);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
  }
};
template <>
struct OrderBits<double>
{
  using type = std::uint64_t;
  __device__ static type of(double f)
  {
    const auto u = static_cast<std::uint64_t>(__double_as_longlong(f));
    return (u >> 63) ? ~u : (u | (std::uint64_t(1) << 63));
  }
};

// What the block and cell kernels read: the grid, the sorted particles, the kernel, the level.
struct Field
{
  surface::NodeGrid grid;
  surface::CellParticles particles;
  Kernels<double> kernels;
  double volume;
  double iso;
  const DistanceGridView<double>* solids; // device copies (SurfaceSolids)
  int solidCount;
};

// The first of the n sorted values that is not less than key (n if none).
template <class T, class Key>
__device__ std::uint32_t lowerBound(const T* sorted, std::uint32_t n, Key key)
{
  std::uint32_t lo = 0, hi = n;
  while (lo < hi)
  {
    const std::uint32_t mid = lo + (hi - lo) / 2;
    if (sorted[mid] < key)
    {
      lo = mid + 1;
    }
    else
    {
      hi = mid;
    }
  }
  return lo;
}

// ---- the particles sorted into cells of h, by position within a cell -------------------------

template <class Real>
__global__ void firstNonFiniteKernel(const Vec3<Real>* x, std::uint32_t n, unsigned long long* firstBad)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n)
  {
    const Vec3d q = Vec3d::from(x[i]);
    if (!isfinite(q.x + q.y + q.z))
    {
      atomicMin(firstBad, static_cast<unsigned long long>(i)); // integers: the least, in any order
    }
  }
}

template <class Real>
__global__ void cellKeysKernel(const Vec3<Real>* x, std::uint32_t n, GridGeometry<double> cells,
  CellKey* keys, std::uint32_t* index)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n)
  {
    keys[i] = cells.keyOf(Vec3d::from(x[i]));
    index[i] = i;
  }
}

// Anisotropic kernels: each sorted particle's centre and metric (SurfaceCells.h).
__global__ void anisotropyKernel(surface::CellParticles particles, std::uint32_t n, double h,
  double fullCount, Vec3d* centres, double* metrics)
{
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < n)
  {
    const surface::Anisotropy a = surface::anisotropyOf(particles, k, h, fullCount);
    centres[k] = a.centre;
    for (int i = 0; i < 6; ++i)
    {
      metrics[6 * static_cast<std::size_t>(k) + i] = a.m[i];
    }
  }
}

// The second sort's gathers: the centres and metrics in the new order, and the order composed
// with the first (to the input's index).
__global__ void gatherShapesKernel(const Vec3d* centres, const double* metrics,
  const std::uint32_t* second, const std::uint32_t* first, std::uint32_t n, Vec3d* sortedCentres,
  double* sortedMetrics, std::uint32_t* order)
{
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < n)
  {
    const std::uint32_t was = second[k];
    sortedCentres[k] = centres[was];
    for (int i = 0; i < 6; ++i)
    {
      sortedMetrics[6 * static_cast<std::size_t>(k) + i] = metrics[6 * static_cast<std::size_t>(was) + i];
    }
    order[k] = first[was];
  }
}

template <class Real>
__global__ void axisKeysKernel(const Vec3<Real>* x, const std::uint32_t* index, std::uint32_t n,
  int axis, typename OrderBits<Real>::type* out)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n)
  {
    const Vec3<Real> p = x[index[i]];
    out[i] = OrderBits<Real>::of(axis == 0 ? p.x : (axis == 1 ? p.y : p.z));
  }
}

__global__ void gatherKeysKernel(
  const CellKey* keys, const std::uint32_t* index, std::uint32_t n, CellKey* out)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n)
  {
    out[i] = keys[index[i]];
  }
}

template <class Real>
__global__ void gatherPositionsKernel(
  const Vec3<Real>* x, const std::uint32_t* order, std::uint32_t n, Vec3d* sorted)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n)
  {
    sorted[i] = Vec3d::from(x[order[i]]);
  }
}

// offsets[c] = the first sorted particle of cell c or beyond (c = 0..cells).
__global__ void cellOffsetsKernel(
  const CellKey* sorted, std::uint32_t n, std::uint32_t cells, std::uint32_t* offsets)
{
  const std::uint64_t c = static_cast<std::uint64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (c > cells)
  {
    return;
  }
  offsets[c] = lowerBound(sorted, n, c);
}

// ---- the narrow band: blocks within h of a particle -------------------------------------------

__global__ void markBlocksKernel(
  const Vec3d* x, std::uint32_t n, surface::NodeGrid grid, double h, std::uint32_t* bits)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n)
  {
    return;
  }
  std::int64_t first[3], last[3];
  surface::blocksNear(grid, h, x[i], first, last);
  for (std::int64_t z = first[2]; z <= last[2]; ++z)
  {
    for (std::int64_t y = first[1]; y <= last[1]; ++y)
    {
      for (std::int64_t b = first[0]; b <= last[0]; ++b)
      {
        const std::uint64_t key = grid.blockKey(b, y, z);
        const std::uint32_t bit = 1u << (key & 31);
        // Neighbouring particles (neighbouring threads) mark the same blocks: read first, and
        // only set what is not set yet (a stale read costs an atomic that changes nothing). The
        // atomics on the same words cost 1.4 ms of 9.4 at 1.15M before.
        if (!(bits[key >> 5] & bit))
        {
          atomicOr(bits + (key >> 5), bit); // integers: the same bits in any order
        }
      }
    }
  }
}

struct HasTriangles
{
  const std::uint32_t* count;
  __host__ __device__ bool operator()(std::uint32_t slot) const { return count[slot] != 0; }
};

struct MarkedBlock
{
  const std::uint32_t* bits;
  __host__ __device__ bool operator()(std::uint32_t b) const { return (bits[b >> 5] >> (b & 31)) & 1u; }
};

// One thread block per surface block: its nodes' colour. Store: into phi (the kept blocks);
// otherwise only whether the level passes through the block.
template <bool Store>
__global__ void __launch_bounds__(kSampleThreads) sampleBlocksKernel(
  Field f, const std::uint32_t* blocks, std::uint8_t* kept, double* phi)
{
  std::int64_t b[3];
  f.grid.blockOf(blocks[blockIdx.x], b);
  bool any = false, all = true;
  for (int s = threadIdx.x; s < kBlockNodes; s += blockDim.x)
  {
    const std::int64_t g0 = b[0] * kBlock + s % (kBlock + 1);
    const std::int64_t g1 = b[1] * kBlock + (s / (kBlock + 1)) % (kBlock + 1);
    const std::int64_t g2 = b[2] * kBlock + s / ((kBlock + 1) * (kBlock + 1));
    double value = 0; // beyond the grid: outside, as the padding is
    if (g0 < f.grid.n[0] && g1 < f.grid.n[1] && g2 < f.grid.n[2])
    {
      const Vec3d q = f.grid.at(g0, g1, g2);
      value = surface::clipped(surface::colour(f.particles, f.kernels, f.volume, q), f.solids,
        f.solidCount, q, f.iso, 1.0 / f.grid.cell);
    }
    if (Store)
    {
      phi[static_cast<std::size_t>(blockIdx.x) * kBlockNodes + s] = value;
    }
    any = any || value > f.iso;
    all = all && value > f.iso;
  }
  if (!Store)
  {
    any = __syncthreads_or(any);
    all = __syncthreads_and(all);
    if (threadIdx.x == 0)
    {
      kept[blockIdx.x] = any && !all ? 1 : 0;
    }
  }
}

// ---- the kept blocks' cells ------------------------------------------------------------------

// Cell (i, j, k) of a kept block: its global index and its corners; false beyond the grid.
__device__ bool cellCorners(const Field& f, const std::uint32_t* kept, const double* phi,
  std::uint32_t slot, std::int64_t cell[3], double corner[8])
{
  const std::uint32_t block = slot / kBlockCells;
  const int c = static_cast<int>(slot % kBlockCells);
  const int i = c % kBlock, j = (c / kBlock) % kBlock, k = c / (kBlock * kBlock);
  std::int64_t b[3];
  f.grid.blockOf(kept[block], b);
  cell[0] = b[0] * kBlock + i;
  cell[1] = b[1] * kBlock + j;
  cell[2] = b[2] * kBlock + k;
  if (cell[0] + 1 >= f.grid.n[0] || cell[1] + 1 >= f.grid.n[1] || cell[2] + 1 >= f.grid.n[2])
  {
    return false;
  }
  const double* p = phi + static_cast<std::size_t>(block) * kBlockNodes;
  for (int q = 0; q < 8; ++q)
  {
    corner[q] = p[surface::nodeSlot(i + (q & 1), j + ((q >> 1) & 1), k + (q >> 2))];
  }
  return true;
}

__global__ void countCellsKernel(Field f, const std::uint32_t* kept, const double* phi,
  std::uint32_t slots, std::uint32_t* triangles, std::uint32_t* vertices, std::uint8_t* crossings)
{
  const std::uint32_t slot = blockIdx.x * blockDim.x + threadIdx.x;
  if (slot >= slots)
  {
    return;
  }
  std::int64_t cell[3];
  double corner[8];
  unsigned owned = 0;
  int count = 0;
  if (cellCorners(f, kept, phi, slot, cell, corner))
  {
    owned = surface::ownedCrossings(corner, f.iso);
    count = surface::cellTriangleCount(corner, f.iso);
  }
  triangles[slot] = static_cast<std::uint32_t>(count);
  vertices[slot] = static_cast<std::uint32_t>(__popc(owned));
  crossings[slot] = static_cast<std::uint8_t>(owned);
}

__global__ void placeVerticesKernel(Field f, const std::uint32_t* kept, const double* phi,
  std::uint32_t slots, const std::uint8_t* crossings, const std::uint32_t* first, Vec3d* position)
{
  const std::uint32_t slot = blockIdx.x * blockDim.x + threadIdx.x;
  if (slot >= slots || crossings[slot] == 0)
  {
    return;
  }
  std::int64_t cell[3];
  double corner[8];
  cellCorners(f, kept, phi, slot, cell, corner);
  std::uint32_t at = first[slot];
  for (int d = 1; d < 8; ++d)
  {
    if ((crossings[slot] >> d) & 1u)
    {
      position[at++] =
        surface::edgeVertex(f.grid, cell[0], cell[1], cell[2], 0, d, corner, f.iso).position;
    }
  }
}

struct VertexNumbering
{
  const std::uint32_t* kept;
  std::uint32_t keptCount;
  const std::uint8_t* crossings;
  const std::uint32_t* first;

  // The index of the vertex on an edge: its owner cell (the edge's lower node) is found in the
  // kept blocks (sorted keys; `block` is the cutting cell's own, where two thirds of the edges
  // are owned), then the vertex among the cell's owned ones by direction.
  __device__ std::uint32_t operator()(
    const surface::NodeGrid& g, std::uint32_t block, const surface::EdgeVertex& e) const
  {
    const std::uint64_t key = g.blockKey(e.node[0] / kBlock, e.node[1] / kBlock, e.node[2] / kBlock);
    const std::uint32_t owner = kept[block] == key ? block : lowerBound(kept, keptCount, key);
    const std::uint32_t slot = owner * kBlockCells +
      static_cast<std::uint32_t>(surface::cellSlot(static_cast<int>(e.node[0] % kBlock),
        static_cast<int>(e.node[1] % kBlock), static_cast<int>(e.node[2] % kBlock)));
    return first[slot] + static_cast<std::uint32_t>(__popc(crossings[slot] & ((1u << e.dir) - 1u)));
  }
};

// Over the cells that have triangles (listed: a quarter of the kept blocks' cells, so that a
// warp's lanes all cut).
__global__ void cutCellsKernel(Field f, const std::uint32_t* kept, const double* phi,
  const std::uint32_t* cutting, std::uint32_t count, const std::uint32_t* triangleFirst,
  VertexNumbering number, std::uint32_t* triangles)
{
  const std::uint32_t at = blockIdx.x * blockDim.x + threadIdx.x;
  if (at >= count)
  {
    return;
  }
  const std::uint32_t slot = cutting[at];
  const std::uint32_t block = slot / kBlockCells;
  std::int64_t cell[3];
  double corner[8];
  cellCorners(f, kept, phi, slot, cell, corner);
  std::uint32_t* out = triangles + 3 * static_cast<std::size_t>(triangleFirst[slot]);
  surface::triangulateCell(f.grid, cell[0], cell[1], cell[2], corner, f.iso,
    [&](const surface::EdgeVertex& a, const surface::EdgeVertex& b, const surface::EdgeVertex& c) {
      out[0] = number(f.grid, block, a);
      out[1] = number(f.grid, block, b);
      out[2] = number(f.grid, block, c);
      out += 3;
    });
}

// ---- smoothing: the vertices' neighbours from the triangles' edges ---------------------------

__global__ void directedEdgesKernel(
  const std::uint32_t* triangles, std::uint32_t count, std::uint64_t* edges)
{
  const std::uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
  if (t >= count)
  {
    return;
  }
  for (int e = 0; e < 3; ++e)
  {
    const std::uint64_t a = triangles[3 * static_cast<std::size_t>(t) + e];
    const std::uint64_t b = triangles[3 * static_cast<std::size_t>(t) + (e + 1) % 3];
    edges[6 * static_cast<std::size_t>(t) + 2 * e] = a << 32 | b;
    edges[6 * static_cast<std::size_t>(t) + 2 * e + 1] = b << 32 | a;
  }
}

// first[v] = the first edge leaving vertex v or beyond (v = 0..vertices).
__global__ void edgeOffsetsKernel(
  const std::uint64_t* edges, std::uint32_t count, std::uint32_t vertices, std::uint32_t* first)
{
  const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
  if (v > vertices)
  {
    return;
  }
  first[v] = lowerBound(edges, count, static_cast<std::uint64_t>(v) << 32);
}

__global__ void smoothKernel(const Vec3d* position, std::uint32_t vertices,
  const std::uint64_t* edges, const std::uint32_t* first, Vec3d* next)
{
  const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
  if (v >= vertices)
  {
    return;
  }
  const std::uint64_t* around = edges + first[v];
  next[v] = surface::smoothedPosition(position[v], static_cast<int>(first[v + 1] - first[v]),
    [&](int e) { return position[around[e] & 0xffffffffu]; });
}

// ---- the fields at the vertices --------------------------------------------------------------

template <class Real>
__global__ void vertexFieldsKernel(Field f, const Vec3d* position, std::uint32_t vertices,
  const std::uint32_t* order, const Vec3<Real>* v, const Real* rho, Vec3<float>* points,
  Vec3<float>* normals, Vec3<float>* velocity, float* density)
{
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= vertices)
  {
    return;
  }
  const surface::VertexFields fields = surface::vertexFields(f.particles, f.kernels, position[i],
    v != nullptr, rho != nullptr,
    [&](std::uint32_t j) { return Vec3d::from(v[order[j]]); },
    [&](std::uint32_t j) { return static_cast<double>(rho[order[j]]); }, f.volume, f.solids,
    f.solidCount, f.iso, 1.0 / f.grid.cell);
  points[i] = Vec3<float>::from(position[i]);
  normals[i] = fields.normal;
  if (v)
  {
    velocity[i] = fields.velocity;
  }
  if (rho)
  {
    density[i] = fields.density;
  }
}

} // namespace
} // namespace cuda
} // namespace pbf
