// The GPU surface (CudaSurface.h). Compiled without fused multiply-adds (Cuda/CMakeLists.txt):
// the colour sums, the vertices' interpolation and the smoothing then round as the host's do,
// and the mesh is the CPU's bit for bit. Everything device-side lives in an anonymous namespace,
// so that no kernel or predicate is instantiated identically in another CUDA translation unit
// (SubdomainSchedule.h says why that matters).
#include "CudaSurface.h"

#include "CudaRuntime.cuh"
#include "CudaSurfaceKernels.cuh"
#include "CudaSurfaceScratch.cuh"
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

  // The particles sorted into cells of h (and, with anisotropic kernels, again by their kernels'
  // centres into cells as wide as they reach): sets f.particles and sx (the sorted positions or
  // centres), returns the sorted order (sorted index -> input index).
  template <class Real>
  const std::uint32_t* sortParticles(const DeviceParticles<Real>& in, std::uint32_t n,
    const Parameters& p, const SurfaceOptions& options, Field& f, Vec3d*& sx,
    cudaStream_t stream);

  // The narrow band: the blocks within reach of a particle, listed in key order and sampled; the
  // keys of those the level passes through.
  struct Band
  {
    std::uint32_t* keptKeys = nullptr;
    std::uint32_t sampled = 0;
    std::uint32_t kept = 0;
  };
  Band keptBlocks(const Field& f, const Vec3d* sx, std::uint32_t n, double reach,
    std::uint64_t blockCount, const SurfaceOptions& options, cudaStream_t stream);

  // The kept blocks sampled into memory, their cells counted, scanned and cut into triangles
  // whose vertices are numbered from the scans.
  struct Cut
  {
    Vec3d* position = nullptr;
    std::uint32_t* triangles = nullptr;
    std::uint32_t vertexTotal = 0;
    std::uint32_t triangleTotal = 0;
  };
  Cut cutCells(const Field& f, const Band& band, cudaStream_t stream);

  // Laplacian smoothing over the vertices' neighbours (the directed edges, sorted and unique).
  void smooth(Cut& cut, int passes, cudaStream_t stream);

  // The fields at the vertices, then the mesh to the host through page-locked memory (a pageable
  // copy of 90 MB ran at a third of the bus's speed) and into the mesh's vectors.
  template <class Real>
  void deliver(const Field& f, const Cut& cut, const std::uint32_t* order,
    const DeviceParticles<Real>& in, SurfaceMesh& mesh, cudaStream_t stream);

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
const std::uint32_t* SurfaceExtractor::Impl::sortParticles(const DeviceParticles<Real>& in,
  std::uint32_t n, const Parameters& p, const SurfaceOptions& options, Field& f, Vec3d*& sx,
  cudaStream_t stream)
{
  const double h = p.smoothingLength();
  const GridGeometry<double> cells = surface::particleCells(f.grid, p, h);
  const Sorted first = sortIntoCells(in.x, n, cells, stream);
  const std::uint32_t* order = first.order; // sorted index -> input index
  sx = sortedX.as<Vec3d>(n, "sorted particles");
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
  return order;
}

SurfaceExtractor::Impl::Band SurfaceExtractor::Impl::keptBlocks(const Field& f,
  const Vec3d* sx, std::uint32_t n, double reach, std::uint64_t blockCount,
  const SurfaceOptions& options, cudaStream_t stream)
{
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
  if (std::uint64_t(keptCount) * kBlockCells >= (std::uint64_t(1) << 32) / 16)
  {
    throw InvalidInput("SurfaceResolution = " + number(options.resolution) + ": " +
      std::to_string(keptCount) + " blocks hold the surface; the GPU surface takes fewer than 2^24");
  }
  return Band{ keptKeys, sampledCount, keptCount };
}

SurfaceExtractor::Impl::Cut SurfaceExtractor::Impl::cutCells(const Field& f, const Band& band,
  cudaStream_t stream)
{
  const std::uint32_t* keptKeys = band.keptKeys;
  const std::uint32_t keptCount = band.kept;
  auto* selected = counter.as<std::int64_t>(1, "counts");
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
  return Cut{ pos, tri, vertexTotal, triangleTotal };
}

void SurfaceExtractor::Impl::smooth(Cut& cut, int passes, cudaStream_t stream)
{
  const std::uint32_t triangleTotal = cut.triangleTotal, vertexTotal = cut.vertexTotal;
  const std::uint32_t* tri = cut.triangles;
  Vec3d*& pos = cut.position;
  auto* selected = counter.as<std::int64_t>(1, "counts");
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
  for (int pass = 0; pass < passes; ++pass)
  {
    smoothKernel<<<gridFor(vertexTotal, kThreads), kThreads, 0, stream>>>(
      pos, vertexTotal, e, around, next);
    check(cudaGetLastError(), "smoothKernel");
    std::swap(pos, next);
  }
}

template <class Real>
void SurfaceExtractor::Impl::deliver(const Field& f, const Cut& cut, const std::uint32_t* order,
  const DeviceParticles<Real>& in, SurfaceMesh& mesh, cudaStream_t stream)
{
  const std::uint32_t vertexTotal = cut.vertexTotal, triangleTotal = cut.triangleTotal;
  const Vec3d* pos = cut.position;
  const std::uint32_t* tri = cut.triangles;
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
}

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
  Vec3d* sx = nullptr;
  const std::uint32_t* order = sortParticles(in, n, p, options, f, sx, stream);
  const double reach = surface::reachFactor(options) * h;
  const Band band = keptBlocks(f, sx, n, reach, blockCount, options, stream);
  mesh.sampledBlocks = band.sampled;
  mesh.keptBlocks = band.kept;
  mesh.sampledNodes = std::size_t(band.sampled) * kBlockNodes;
  Cut cut = cutCells(f, band, stream);
  if (options.smoothing > 0 && cut.triangleTotal > 0)
  {
    smooth(cut, options.smoothing, stream);
  }
  deliver(f, cut, order, in, mesh, stream);
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
