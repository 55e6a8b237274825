// The GPU surface (CudaSurface.h). Compiled without fused multiply-adds (Cuda/CMakeLists.txt):
// the colour sums, the vertices' interpolation and the smoothing then round as the host's do,
// and the mesh is the CPU's bit for bit. Everything device-side lives in an anonymous namespace,
// so that no kernel or predicate is instantiated identically in another CUDA translation unit
// (SubdomainSchedule.h says why that matters).
#include "CudaSurface.h"

#include "CudaRuntime.cuh"
#include "SurfaceCells.h"

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <cub/device/device_select.cuh>
#include <thrust/iterator/counting_iterator.h>

#include <cuda_runtime.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

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

std::string number(double v)
{
  std::ostringstream out;
  out << v;
  return out.str();
}

// A device array that grows and never shrinks. Too little device memory is the input's fault
// (too fine a surface for this GPU): InvalidInput, naming what was asked.
class Scratch
{
public:
  Scratch() = default;
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  ~Scratch() { release(); }

  template <class T>
  T* as(std::size_t count, const char* what)
  {
    const std::size_t bytes = std::max<std::size_t>(count * sizeof(T), 256);
    if (bytes > bytes_)
    {
      release();
      const cudaError_t e = cudaMalloc(&p_, bytes);
      if (e == cudaErrorMemoryAllocation)
      {
        cudaGetLastError();
        p_ = nullptr;
        throw InvalidInput(std::string("Surface: ") + number(static_cast<double>(bytes)) +
          " bytes of GPU memory for the " + what +
          " are not free; coarsen SurfaceResolution or use fewer particles");
      }
      check(e, "cudaMalloc (surface)");
      bytes_ = bytes;
    }
    return static_cast<T*>(p_);
  }
  std::size_t bytes() const { return bytes_; }
  void release()
  {
    if (p_)
    {
      cudaFree(p_);
    }
    p_ = nullptr;
    bytes_ = 0;
  }

private:
  void* p_ = nullptr;
  std::size_t bytes_ = 0;
};

} // namespace

struct SurfaceExtractor::Impl
{
  int device = 0;
  cudaStream_t own = nullptr;
  cudaEvent_t marks[2] = { nullptr, nullptr };
  SurfaceTimes times;

  // Input copies (the host path), the sort, the particles, the band, the cells, the mesh.
  Scratch inX, inV, inRho;
  Scratch keys, keysAlt, index, indexAlt, axisKeys, axisKeysAlt, bad, counter, temp;
  Scratch sortedX, offsets;
  Scratch shapeCentres, shapeMetrics, inputOrder, sortedX2, shapeMetrics2, composedOrder, offsets2;
  Scratch bits, sampled, keptFlags, keptBlockKeys, phi;
  Scratch triangleCount, triangleFirst, vertexCount, vertexFirst, crossings, cuttingCells;
  Scratch position, positionAlt, triangles, edges, edgesAlt, edgeFirst;
  Scratch points, normals, velocity, density;
  Scratch solidNodes, solidViews;

  std::size_t bytes() const
  {
    std::size_t sum = 0;
    for (const Scratch* s : { &inX, &inV, &inRho, &keys, &keysAlt, &index, &indexAlt, &axisKeys,
           &axisKeysAlt, &bad, &counter, &temp, &sortedX, &offsets, &shapeCentres,
           &shapeMetrics, &inputOrder, &sortedX2, &shapeMetrics2, &composedOrder, &offsets2, &bits,
           &sampled, &keptFlags,
           &keptBlockKeys, &phi, &triangleCount, &triangleFirst, &vertexCount,
           &vertexFirst, &crossings, &cuttingCells,
           &position, &positionAlt, &triangles, &edges, &edgesAlt, &edgeFirst, &points, &normals,
           &velocity, &density, &solidNodes, &solidViews })
    {
      sum += s->bytes();
    }
    return sum;
  }

  // CUB's scratch, sized by a query first.
  template <class Call>
  void cub(const char* what, Call&& call)
  {
    std::size_t need = 0;
    check(call(static_cast<void*>(nullptr), need), what);
    void* t = temp.as<unsigned char>(need, "sort and scan scratch");
    check(call(t, need), what);
  }

  // Page-locked host memory for the mesh's copy back (grows, never shrinks).
  unsigned char* pinned(std::size_t bytes)
  {
    if (bytes > pinnedBytes)
    {
      if (pinnedMemory)
      {
        cudaFreeHost(pinnedMemory);
        pinnedMemory = nullptr;
        pinnedBytes = 0;
      }
      check(cudaMallocHost(&pinnedMemory, bytes), "cudaMallocHost (surface)");
      pinnedBytes = bytes;
    }
    return static_cast<unsigned char*>(pinnedMemory);
  }
  void* pinnedMemory = nullptr;
  std::size_t pinnedBytes = 0;

  template <class T>
  T read(const T* from, cudaStream_t stream)
  {
    T value{};
    check(cudaMemcpyAsync(&value, from, sizeof(T), cudaMemcpyDeviceToHost, stream), "cudaMemcpyAsync");
    check(cudaStreamSynchronize(stream), "cudaStreamSynchronize");
    return value;
  }

  struct Sorted
  {
    const std::uint32_t* order; // sorted index -> index in the points given
    const CellKey* keys;        // the sorted cells
  };
  // Points by cell, by position within a cell (z, then y, then x, then the cell: stable radix
  // sorts, last key first), ties by index: the CPU's order (sortedIntoCells). The result lives in
  // the sort's arrays until the next call.
  template <class P>
  Sorted sortIntoCells(const Vec3<P>* points, std::uint32_t n, const GridGeometry<double>& cells,
    cudaStream_t stream)
  {
    using Bits = typename OrderBits<P>::type;
    CellKey* key = keys.as<CellKey>(n, "particles' cells");
    CellKey* keyAlt = keysAlt.as<CellKey>(n, "particles' cells");
    std::uint32_t* idx = index.as<std::uint32_t>(n, "particles' order");
    std::uint32_t* idxAlt = indexAlt.as<std::uint32_t>(n, "particles' order");
    Bits* ak = axisKeys.as<Bits>(n, "particles' positions");
    Bits* akAlt = axisKeysAlt.as<Bits>(n, "particles' positions");
    cellKeysKernel<P><<<gridFor(n, kThreads), kThreads, 0, stream>>>(points, n, cells, key, idx);
    check(cudaGetLastError(), "cellKeysKernel");
    for (int axis = 2; axis >= 0; --axis)
    {
      axisKeysKernel<P><<<gridFor(n, kThreads), kThreads, 0, stream>>>(points, idx, n, axis, ak);
      check(cudaGetLastError(), "axisKeysKernel");
      cub("cub::DeviceRadixSort::SortPairs (positions)", [&](void* t, std::size_t& b) {
        return cub::DeviceRadixSort::SortPairs(t, b, ak, akAlt, idx, idxAlt, static_cast<int>(n), 0,
          static_cast<int>(8 * sizeof(Bits)), stream);
      });
      std::swap(idx, idxAlt);
    }
    gatherKeysKernel<<<gridFor(n, kThreads), kThreads, 0, stream>>>(key, idx, n, keyAlt);
    check(cudaGetLastError(), "gatherKeysKernel");
    int cellBits = 1;
    while ((std::uint64_t(1) << cellBits) < cells.cellCount())
    {
      ++cellBits;
    }
    cub("cub::DeviceRadixSort::SortPairs (cells)", [&](void* t, std::size_t& b) {
      return cub::DeviceRadixSort::SortPairs(t, b, keyAlt, key, idx, idxAlt, static_cast<int>(n), 0,
        cellBits, stream);
    });
    return { idxAlt, key };
  }

  // offsets[c]: the first sorted point of cell c or beyond (c = 0..cells).
  std::uint32_t* cellOffsets(const CellKey* sortedKeys, std::uint32_t n,
    const GridGeometry<double>& cells, Scratch& into, cudaStream_t stream)
  {
    const std::uint32_t count = cells.cellCount();
    std::uint32_t* first = into.as<std::uint32_t>(std::size_t(count) + 1, "cell offsets");
    cellOffsetsKernel<<<gridFor(std::size_t(count) + 1, kThreads), kThreads, 0, stream>>>(
      sortedKeys, n, count, first);
    check(cudaGetLastError(), "cellOffsetsKernel");
    return first;
  }

  template <class Real>
  SurfaceMesh run(const DeviceParticles<Real>& in, const Parameters& p,
    const SurfaceOptions& options, const SurfaceSolids& solids, cudaStream_t stream);

  // The solids' views with their node values copied to the device.
  const DistanceGridView<double>* uploadSolids(const SurfaceSolids& solids, cudaStream_t stream)
  {
    if (solids.views.empty())
    {
      return nullptr;
    }
    std::size_t total = 0;
    for (const DistanceGridView<double>& v : solids.views)
    {
      total += static_cast<std::size_t>(v.nx) * v.ny * v.nz;
    }
    float* nodes = solidNodes.as<float>(total, "obstacles' distance fields");
    std::vector<DistanceGridView<double>> device(solids.views);
    std::size_t at = 0;
    for (DistanceGridView<double>& v : device)
    {
      const std::size_t count = static_cast<std::size_t>(v.nx) * v.ny * v.nz;
      check(cudaMemcpyAsync(nodes + at, v.phi, count * sizeof(float), cudaMemcpyHostToDevice, stream),
        "cudaMemcpyAsync (obstacles)");
      v.phi = nodes + at;
      at += count;
    }
    auto* views = solidViews.as<DistanceGridView<double>>(device.size(), "obstacles");
    check(cudaMemcpyAsync(views, device.data(), device.size() * sizeof(device[0]),
            cudaMemcpyHostToDevice, stream),
      "cudaMemcpyAsync (obstacles)");
    // The host vector dies here: wait for the copies that read it.
    check(cudaStreamSynchronize(stream), "cudaStreamSynchronize");
    return views;
  }
};

template <class Real>
SurfaceMesh SurfaceExtractor::Impl::run(const DeviceParticles<Real>& in, const Parameters& p,
  const SurfaceOptions& options, const SurfaceSolids& solids, cudaStream_t stream)
{
  options.validate();
  SurfaceMesh mesh;
  times = {};
  if (in.n == 0)
  {
    return mesh;
  }
  if (in.n >= (std::size_t(1) << 31))
  {
    throw InvalidInput("Surface: " + std::to_string(in.n) +
      " particles; the GPU surface takes fewer than 2^31");
  }
  const auto n = static_cast<std::uint32_t>(in.n);
  const double h = p.smoothingLength();
  Field f{};
  f.grid = surface::makeNodeGrid(p, options);
  f.kernels = Kernels<double>::make(h);
  f.volume = calibratedParticleMass(p) / p.restDensity;
  f.iso = options.isoValue;
  f.solids = uploadSolids(solids, stream);
  f.solidCount = static_cast<int>(solids.views.size());
  const GridGeometry<double> cells = surface::particleCells(f.grid, p, h);
  const std::uint64_t blockCount = f.grid.blockCount();
  if (blockCount >= (std::uint64_t(1) << 31))
  {
    throw InvalidInput("SurfaceResolution = " + number(options.resolution) + ": " +
      number(static_cast<double>(blockCount)) +
      " blocks of 8^3 grid cells over the domain; the GPU surface takes fewer than 2^31");
  }
  check(cudaEventRecord(marks[0], stream), "cudaEventRecord");

  auto* firstBad = bad.as<unsigned long long>(1, "checks");
  check(cudaMemsetAsync(firstBad, 0xff, sizeof(unsigned long long), stream), "cudaMemsetAsync");
  firstNonFiniteKernel<Real><<<gridFor(n, kThreads), kThreads, 0, stream>>>(in.x, n, firstBad);
  check(cudaGetLastError(), "firstNonFiniteKernel");
  const unsigned long long badIndex = read(firstBad, stream);
  if (badIndex != ~0ull)
  {
    throw InvalidInput("surface: particle " + std::to_string(badIndex) + " has a non-finite position");
  }
  const Sorted first = sortIntoCells(in.x, n, cells, stream);
  const std::uint32_t* order = first.order; // sorted index -> input index
  Vec3d* sx = sortedX.as<Vec3d>(n, "sorted particles");
  gatherPositionsKernel<Real><<<gridFor(n, kThreads), kThreads, 0, stream>>>(in.x, order, n, sx);
  check(cudaGetLastError(), "gatherPositionsKernel");
  f.particles =
    surface::CellParticles{ cells, cellOffsets(first.keys, n, cells, offsets, stream), sx, nullptr };

  // Anisotropic kernels: shapes from the neighbours within h, then the particles sorted again by
  // their centres into cells as wide as the kernels reach.
  const double reach = surface::reachFactor(options) * h;
  if (options.anisotropic)
  {
    const double fullCount = 4.0 / 3.0 * 3.14159265358979323846 * std::pow(p.smoothingRatio, 3);
    Vec3d* centres = shapeCentres.as<Vec3d>(n, "anisotropic kernels");
    double* metrics = shapeMetrics.as<double>(6 * std::size_t(n), "anisotropic kernels");
    anisotropyKernel<<<gridFor(n, kThreads), kThreads, 0, stream>>>(
      f.particles, n, h, fullCount, centres, metrics);
    check(cudaGetLastError(), "anisotropyKernel");
    // The first order, kept aside: the second sort reuses its arrays.
    std::uint32_t* firstOrder = inputOrder.as<std::uint32_t>(n, "particles' order");
    check(cudaMemcpyAsync(firstOrder, order, n * sizeof(std::uint32_t), cudaMemcpyDeviceToDevice, stream),
      "cudaMemcpyAsync");
    const GridGeometry<double> wide = surface::particleCells(f.grid, p, reach);
    const Sorted second = sortIntoCells(centres, n, wide, stream);
    Vec3d* sortedCentres = sortedX2.as<Vec3d>(n, "anisotropic kernels");
    double* sortedMetrics = shapeMetrics2.as<double>(6 * std::size_t(n), "anisotropic kernels");
    std::uint32_t* composed = composedOrder.as<std::uint32_t>(n, "particles' order");
    gatherShapesKernel<<<gridFor(n, kThreads), kThreads, 0, stream>>>(
      centres, metrics, second.order, firstOrder, n, sortedCentres, sortedMetrics, composed);
    check(cudaGetLastError(), "gatherShapesKernel");
    f.particles = surface::CellParticles{ wide, cellOffsets(second.keys, n, wide, offsets2, stream),
      sortedCentres, sortedMetrics };
    order = composed;
    sx = sortedCentres;
  }

  // The narrow band: the blocks within h of a particle, listed in key order.
  const std::size_t words = static_cast<std::size_t>((blockCount + 31) / 32);
  auto* marked = bits.as<std::uint32_t>(words, "block bitmap");
  check(cudaMemsetAsync(marked, 0, words * sizeof(std::uint32_t), stream), "cudaMemsetAsync");
  markBlocksKernel<<<gridFor(n, kThreads), kThreads, 0, stream>>>(sx, n, f.grid, reach, marked);
  check(cudaGetLastError(), "markBlocksKernel");
  auto* selected = counter.as<std::int64_t>(1, "counts");
  // Four bytes per block of the domain's 8^3 grid cells (a block per 512 nodes; the band's own
  // arrays below grow with the surface).
  std::uint32_t* sampledList = sampled.as<std::uint32_t>(blockCount, "block list");
  cub("cub::DeviceSelect::If (blocks)", [&](void* t, std::size_t& b) {
    return cub::DeviceSelect::If(t, b, thrust::counting_iterator<std::uint32_t>(0), sampledList,
      selected, static_cast<int>(blockCount), MarkedBlock{ marked }, stream);
  });
  const auto sampledCount = static_cast<std::uint32_t>(read(selected, stream));

  // Each listed block sampled; those the level passes through kept, sampled again into memory.
  auto* keep = keptFlags.as<std::uint8_t>(sampledCount, "kept flags");
  if (sampledCount > 0)
  {
    sampleBlocksKernel<false><<<sampledCount, kSampleThreads, 0, stream>>>(f, sampledList, keep, nullptr);
    check(cudaGetLastError(), "sampleBlocksKernel");
  }
  // The kept blocks' keys, selected from the sampled list: sorted, as the list is.
  std::uint32_t* keptKeys = keptBlockKeys.as<std::uint32_t>(sampledCount, "kept blocks");
  cub("cub::DeviceSelect::Flagged (kept blocks)", [&](void* t, std::size_t& b) {
    return cub::DeviceSelect::Flagged(t, b, sampledList, keep, keptKeys, selected,
      static_cast<int>(sampledCount), stream);
  });
  const auto keptCount = static_cast<std::uint32_t>(read(selected, stream));
  mesh.sampledBlocks = sampledCount;
  mesh.keptBlocks = keptCount;
  mesh.sampledNodes = std::size_t(sampledCount) * kBlockNodes;
  if (std::uint64_t(keptCount) * kBlockCells >= (std::uint64_t(1) << 32) / 16)
  {
    throw InvalidInput("SurfaceResolution = " + number(options.resolution) + ": " +
      std::to_string(keptCount) + " blocks hold the surface; the GPU surface takes fewer than 2^24");
  }
  const std::uint32_t slots = keptCount * kBlockCells;
  double* values = phi.as<double>(std::size_t(keptCount) * kBlockNodes, "kept blocks' samples");
  std::uint32_t* tCount = triangleCount.as<std::uint32_t>(slots, "cells' triangle counts");
  std::uint32_t* tFirst = triangleFirst.as<std::uint32_t>(slots, "cells' triangle offsets");
  std::uint32_t* vCount = vertexCount.as<std::uint32_t>(slots, "cells' vertex counts");
  std::uint32_t* vFirst = vertexFirst.as<std::uint32_t>(slots, "cells' vertex offsets");
  std::uint8_t* owned = crossings.as<std::uint8_t>(slots, "cells' crossings");
  std::uint32_t triangleTotal = 0, vertexTotal = 0;
  if (keptCount > 0)
  {
    sampleBlocksKernel<true><<<keptCount, kSampleThreads, 0, stream>>>(f, keptKeys, nullptr, values);
    check(cudaGetLastError(), "sampleBlocksKernel (kept)");
    countCellsKernel<<<gridFor(slots, kThreads), kThreads, 0, stream>>>(
      f, keptKeys, values, slots, tCount, vCount, owned);
    check(cudaGetLastError(), "countCellsKernel");
    cub("cub::DeviceScan::ExclusiveSum (triangles)", [&](void* t, std::size_t& b) {
      return cub::DeviceScan::ExclusiveSum(t, b, tCount, tFirst, static_cast<int>(slots), stream);
    });
    cub("cub::DeviceScan::ExclusiveSum (vertices)", [&](void* t, std::size_t& b) {
      return cub::DeviceScan::ExclusiveSum(t, b, vCount, vFirst, static_cast<int>(slots), stream);
    });
    // The totals: the last offset plus the last count, in one wait.
    const std::uint32_t* ends[4] = { tFirst + slots - 1, tCount + slots - 1, vFirst + slots - 1,
      vCount + slots - 1 };
    std::uint32_t tail[4];
    for (int k = 0; k < 4; ++k)
    {
      check(cudaMemcpyAsync(tail + k, ends[k], sizeof(std::uint32_t), cudaMemcpyDeviceToHost, stream),
        "cudaMemcpyAsync");
    }
    check(cudaStreamSynchronize(stream), "cudaStreamSynchronize");
    triangleTotal = tail[0] + tail[1];
    vertexTotal = tail[2] + tail[3];
  }

  Vec3d* pos = position.as<Vec3d>(vertexTotal, "vertices");
  auto* tri = triangles.as<std::uint32_t>(3 * std::size_t(triangleTotal), "triangles");
  if (triangleTotal > 0)
  {
    placeVerticesKernel<<<gridFor(slots, kThreads), kThreads, 0, stream>>>(
      f, keptKeys, values, slots, owned, vFirst, pos);
    check(cudaGetLastError(), "placeVerticesKernel");
    // The cells with triangles, listed (their slots, in order).
    std::uint32_t* cutting = cuttingCells.as<std::uint32_t>(slots, "cells with triangles");
    cub("cub::DeviceSelect::If (cells)", [&](void* t, std::size_t& b) {
      return cub::DeviceSelect::If(t, b, thrust::counting_iterator<std::uint32_t>(0), cutting,
        selected, static_cast<int>(slots), HasTriangles{ tCount }, stream);
    });
    const auto cuttingCount = static_cast<std::uint32_t>(read(selected, stream));
    cutCellsKernel<<<gridFor(cuttingCount, kThreads), kThreads, 0, stream>>>(f, keptKeys, values,
      cutting, cuttingCount, tFirst, VertexNumbering{ keptKeys, keptCount, owned, vFirst }, tri);
    check(cudaGetLastError(), "cutCellsKernel");
  }

  // Laplacian smoothing over the vertices' neighbours (the directed edges, sorted and unique).
  if (options.smoothing > 0 && triangleTotal > 0)
  {
    const std::uint32_t directed = 6 * triangleTotal;
    auto* e = edges.as<std::uint64_t>(directed, "surface edges");
    auto* eAlt = edgesAlt.as<std::uint64_t>(directed, "surface edges");
    directedEdgesKernel<<<gridFor(triangleTotal, kThreads), kThreads, 0, stream>>>(tri, triangleTotal, e);
    check(cudaGetLastError(), "directedEdgesKernel");
    cub("cub::DeviceRadixSort::SortKeys (edges)", [&](void* t, std::size_t& b) {
      return cub::DeviceRadixSort::SortKeys(t, b, e, eAlt, static_cast<int>(directed), 0, 64, stream);
    });
    cub("cub::DeviceSelect::Unique (edges)", [&](void* t, std::size_t& b) {
      return cub::DeviceSelect::Unique(t, b, eAlt, e, selected, static_cast<int>(directed), stream);
    });
    const auto unique = static_cast<std::uint32_t>(read(selected, stream));
    auto* around = edgeFirst.as<std::uint32_t>(std::size_t(vertexTotal) + 1, "surface edges");
    edgeOffsetsKernel<<<gridFor(std::size_t(vertexTotal) + 1, kThreads), kThreads, 0, stream>>>(
      e, unique, vertexTotal, around);
    check(cudaGetLastError(), "edgeOffsetsKernel");
    Vec3d* next = positionAlt.as<Vec3d>(vertexTotal, "vertices");
    for (int pass = 0; pass < options.smoothing; ++pass)
    {
      smoothKernel<<<gridFor(vertexTotal, kThreads), kThreads, 0, stream>>>(
        pos, vertexTotal, e, around, next);
      check(cudaGetLastError(), "smoothKernel");
      std::swap(pos, next);
    }
  }

  // The fields at the vertices.
  auto* pts = points.as<Vec3<float>>(vertexTotal, "vertex points");
  auto* nrm = normals.as<Vec3<float>>(vertexTotal, "vertex normals");
  auto* vel = in.v ? velocity.as<Vec3<float>>(vertexTotal, "vertex velocities") : nullptr;
  auto* den = in.rho ? density.as<float>(vertexTotal, "vertex densities") : nullptr;
  if (vertexTotal > 0)
  {
    vertexFieldsKernel<Real><<<gridFor(vertexTotal, kThreads), kThreads, 0, stream>>>(
      f, pos, vertexTotal, order, in.v, in.rho, pts, nrm, vel, den);
    check(cudaGetLastError(), "vertexFieldsKernel");
  }
  check(cudaEventRecord(marks[1], stream), "cudaEventRecord");

  // The mesh to the host through page-locked memory (a pageable copy of 90 MB ran at a third of
  // the bus's speed), then into the mesh's vectors.
  check(cudaEventSynchronize(marks[1]), "cudaEventSynchronize");
  const auto downloadStart = std::chrono::steady_clock::now();
  mesh.points.resize(vertexTotal);
  mesh.normals.resize(vertexTotal);
  mesh.velocity.resize(in.v ? vertexTotal : 0);
  mesh.density.resize(in.rho ? vertexTotal : 0);
  mesh.triangles.resize(triangleTotal);
  static_assert(sizeof(std::array<std::uint32_t, 3>) == 3 * sizeof(std::uint32_t), "packed triangles");
  struct Part
  {
    void* to;
    const void* from;
    std::size_t bytes;
  };
  const Part parts[] = {
    { mesh.points.data(), pts, vertexTotal * sizeof(Vec3<float>) },
    { mesh.normals.data(), nrm, vertexTotal * sizeof(Vec3<float>) },
    { mesh.velocity.data(), vel, vel ? vertexTotal * sizeof(Vec3<float>) : 0 },
    { mesh.density.data(), den, den ? vertexTotal * sizeof(float) : 0 },
    { mesh.triangles.data(), tri, std::size_t(triangleTotal) * 3 * sizeof(std::uint32_t) },
  };
  std::size_t total = 0;
  for (const Part& part : parts)
  {
    total += part.bytes;
  }
  unsigned char* staging = pinned(total);
  std::size_t at = 0;
  for (const Part& part : parts)
  {
    if (part.bytes > 0)
    {
      check(cudaMemcpyAsync(staging + at, part.from, part.bytes, cudaMemcpyDeviceToHost, stream),
        "cudaMemcpyAsync (surface)");
    }
    at += part.bytes;
  }
  check(cudaStreamSynchronize(stream), "cudaStreamSynchronize");
  at = 0;
  for (const Part& part : parts)
  {
    if (part.bytes > 0)
    {
      std::memcpy(part.to, staging + at, part.bytes);
    }
    at += part.bytes;
  }
  float a = 0;
  check(cudaEventElapsedTime(&a, marks[0], marks[1]), "cudaEventElapsedTime");
  times.extractMs = a;
  times.downloadMs =
    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - downloadStart).count();
  mesh.peakBytes = bytes();
  return mesh;
}

SurfaceExtractor::SurfaceExtractor(int device)
  : impl_(std::make_unique<Impl>())
{
  std::string why;
  if (!cudaDevicePresent(&why))
  {
    throw std::runtime_error("CUDA surface unavailable: " + why);
  }
  impl_->device = device;
  check(cudaSetDevice(device), "cudaSetDevice");
  check(cudaStreamCreate(&impl_->own), "cudaStreamCreate");
  for (cudaEvent_t& e : impl_->marks)
  {
    check(cudaEventCreate(&e), "cudaEventCreate");
  }
}

SurfaceExtractor::~SurfaceExtractor()
{
  if (impl_->own)
  {
    cudaStreamSynchronize(impl_->own);
    cudaStreamDestroy(impl_->own);
  }
  for (cudaEvent_t e : impl_->marks)
  {
    if (e)
    {
      cudaEventDestroy(e);
    }
  }
  if (impl_->pinnedMemory)
  {
    cudaFreeHost(impl_->pinnedMemory);
  }
}

template <class Real>
SurfaceMesh SurfaceExtractor::extract(const Vec3<Real>* x, const Vec3<Real>* v, const Real* rho,
  std::size_t n, const Parameters& parameters, const SurfaceOptions& options,
  const SurfaceSolids& solids)
{
  options.validate();
  check(cudaSetDevice(impl_->device), "cudaSetDevice");
  cudaStream_t s = impl_->own;
  DeviceParticles<Real> in;
  in.n = n;
  if (n > 0)
  {
    auto up = [&](Scratch& to, const auto* from, std::size_t bytes, const char* what) {
      using T = std::remove_cv_t<std::remove_pointer_t<decltype(from)>>;
      T* device = to.as<T>(n, what);
      check(cudaMemcpyAsync(device, from, bytes, cudaMemcpyHostToDevice, s), "cudaMemcpyAsync (particles)");
      return device;
    };
    in.x = up(impl_->inX, x, n * sizeof(Vec3<Real>), "particles");
    in.v = v ? up(impl_->inV, v, n * sizeof(Vec3<Real>), "particles' velocities") : nullptr;
    in.rho = rho ? up(impl_->inRho, rho, n * sizeof(Real), "particles' densities") : nullptr;
  }
  return impl_->run(in, parameters, options, solids, s);
}

template <class Real>
SurfaceMesh SurfaceExtractor::extract(const DeviceParticles<Real>& particles,
  const Parameters& parameters, const SurfaceOptions& options, void* stream,
  const SurfaceSolids& solids)
{
  check(cudaSetDevice(impl_->device), "cudaSetDevice");
  cudaStream_t s = static_cast<cudaStream_t>(stream);
  if (!s)
  {
    check(cudaDeviceSynchronize(), "cudaDeviceSynchronize");
    s = impl_->own;
  }
  return impl_->run(particles, parameters, options, solids, s);
}

const SurfaceTimes& SurfaceExtractor::lastTimes() const
{
  return impl_->times;
}

std::size_t SurfaceExtractor::deviceBytes() const
{
  return impl_->bytes();
}

template SurfaceMesh SurfaceExtractor::extract<float>(const Vec3<float>*, const Vec3<float>*,
  const float*, std::size_t, const Parameters&, const SurfaceOptions&, const SurfaceSolids&);
template SurfaceMesh SurfaceExtractor::extract<double>(const Vec3<double>*, const Vec3<double>*,
  const double*, std::size_t, const Parameters&, const SurfaceOptions&, const SurfaceSolids&);
template SurfaceMesh SurfaceExtractor::extract<float>(const DeviceParticles<float>&,
  const Parameters&, const SurfaceOptions&, void*, const SurfaceSolids&);
template SurfaceMesh SurfaceExtractor::extract<double>(const DeviceParticles<double>&,
  const Parameters&, const SurfaceOptions&, void*, const SurfaceSolids&);

} // namespace cuda
} // namespace pbf
