// pair_once_probe: does evaluating each pair once pay on a GPU when the other half of the pair must
// reach particle j deterministically? Issue 21's lever table estimated -20 to -25 % from halving
// the pair arithmetic; this measures the trade on a density-like pass, apart from the solver:
//   gather   a thread per particle visits all its candidates and sums its own terms (the
//            structure of the CUDA backend's passes);
//   once+fix a thread visits the candidates j > i only, keeps its own sums in registers and adds
//            j's share with 64-bit fixed-point integer atomics (integer addition is associative,
//            so the sums are the same bits in any order), then its own; a last kernel turns the
//            sums into rho and lambda;
//   once+f32 the same with float atomics (not deterministic: the cost of the scatter alone).
// The particles are a jittered cubic lattice of spacing 1 with h = 2 (28-33 within h, as the
// dam break's), 33 candidates each, found by index arithmetic so both variants see the same ones.
// Then the same gather on the particles sorted by cell, the candidates read from a list or from
// row masks as the solver's: what finding the candidates costs over the lattice's free indices.
// Timed with CUDA events after a warm-up, medians; the last table line compares them.
// Build and run (Utilities/gpu/run.sh does it): nvcc -O3 -arch=sm_90 -o probe pair_once_probe.cu
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace
{

constexpr float kH = 2.0f;
constexpr float kFix = 1099511627776.0f; // 2^40: a sum of 33 terms of at most 1 fits 2^46

#define CHECK(call)                                                                              \
  do                                                                                             \
  {                                                                                              \
    const cudaError_t e = (call);                                                                \
    if (e != cudaSuccess)                                                                        \
    {                                                                                            \
      std::fprintf(stderr, "%s: %s\n", #call, cudaGetErrorString(e));                            \
      std::exit(1);                                                                              \
    }                                                                                            \
  } while (0)

__constant__ int3 cOffsets[33]; // |v|^2 <= 4: itself, then the 16 forward ones, then the rest
__constant__ int cForward;      // how many follow itself in lexicographic order (v > 0)

struct Sums
{
  float rho, gx, gy, gz, g2;
};

// A pair's terms: poly6-like density q^3 and a spiky-like gradient (1 - r/h)^2 r / |r|.
__device__ __forceinline__ void pairTerms(float3 r, float r2, float& w, float3& g)
{
  const float q = 1.0f - r2 * (1.0f / (kH * kH));
  w = q * q * q;
  const float inv = rsqrtf(r2);
  const float a = 1.0f - r2 * inv * (1.0f / kH);
  const float f = r2 > 0.0f ? a * a * inv : 0.0f;
  g = make_float3(r.x * f, r.y * f, r.z * f);
}

__device__ __forceinline__ bool neighbour(int L, int x, int y, int z, int3 v, int& j)
{
  const int a = x + v.x, b = y + v.y, c = z + v.z;
  if (a < 0 || b < 0 || c < 0 || a >= L || b >= L || c >= L)
  {
    return false;
  }
  j = (c * L + b) * L + a;
  return true;
}

__device__ __forceinline__ float lambdaOf(const Sums& s)
{
  const float C = s.rho / 27.0f - 1.0f;
  return -C / (s.g2 + s.gx * s.gx + s.gy * s.gy + s.gz * s.gz + 1e-3f);
}

// One candidate's terms, when it lies within h, added to the particle's sums; true and the
// pair's w and g (for the scatter of the pair-once variants) when it does.
__device__ __forceinline__ bool visit(
  const float3& pi, const float3& pj, Sums& s, float& w, float3& g)
{
  const float3 r = make_float3(pi.x - pj.x, pi.y - pj.y, pi.z - pj.z);
  const float r2 = r.x * r.x + r.y * r.y + r.z * r.z;
  if (!(r2 < kH * kH))
  {
    return false;
  }
  pairTerms(r, r2, w, g);
  s.rho += w;
  s.gx += g.x;
  s.gy += g.y;
  s.gz += g.z;
  s.g2 += g.x * g.x + g.y * g.y + g.z * g.z;
  return true;
}
__device__ __forceinline__ void visit(const float3& pi, const float3& pj, Sums& s)
{
  float w;
  float3 g;
  visit(pi, pj, s, w, g);
}

// This thread's particle i on the L^3 lattice and its site (x, y, z); false past the last one.
__device__ __forceinline__ bool latticeSite(int L, int& i, int& x, int& y, int& z)
{
  i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= L * L * L)
  {
    return false;
  }
  x = i % L;
  y = (i / L) % L;
  z = i / (L * L);
  return true;
}

__global__ void gather(int L, const float3* p, float* rho, float* lambda)
{
  int i, x, y, z;
  if (!latticeSite(L, i, x, y, z))
  {
    return;
  }
  const float3 pi = p[i];
  Sums s{ 0, 0, 0, 0, 0 };
  for (int k = 0; k < 33; ++k)
  {
    int j;
    if (!neighbour(L, x, y, z, cOffsets[k], j))
    {
      continue;
    }
    visit(pi, p[j], s);
  }
  rho[i] = s.rho;
  lambda[i] = lambdaOf(s);
}

// The same pass on the particles sorted by cell (Green 2008, cells of size h, as the solver sorts
// them), its candidates read from a list built once (the 27 cells' particles within h + skin,
// list[k * n + i]) or, as the CUDA backend stores them, from a 32-bit mask per row of 3 cells
// (bit 31 - k: candidate k of the row; NeighborMasks.h).
__global__ void gatherList(int n, const float3* p, const int* count, const int* list, float* rho,
  float* lambda)
{
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n)
  {
    return;
  }
  const float3 pi = p[i];
  Sums s{ 0, 0, 0, 0, 0 };
  const int m = count[i];
  for (int k = 0; k < m; ++k)
  {
    visit(pi, p[list[static_cast<long>(k) * n + i]], s);
  }
  rho[i] = s.rho;
  lambda[i] = lambdaOf(s);
}

__global__ void gatherMasks(int n, const float3* p, const int* rowBegin, const unsigned* masks,
  float* rho, float* lambda)
{
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n)
  {
    return;
  }
  const float3 pi = p[i];
  Sums s{ 0, 0, 0, 0, 0 };
  for (int r = 0; r < 9; ++r)
  {
    const int base = rowBegin[r * n + i];
    unsigned mask = masks[r * n + i];
    while (mask)
    {
      const int k = __clz(static_cast<int>(mask));
      mask &= 0x7fffffffu >> k;
      visit(pi, p[base + k], s);
    }
  }
  rho[i] = s.rho;
  lambda[i] = lambdaOf(s);
}

// The row masks walked as the solver walks them (NeighborMasks.h, forEachNeighbor): each lane
// first stages its non-empty rows as (base, mask) words in its own column of shared memory, then
// runs one loop over all of them, so a lane that finishes a row moves on to the next.
// stageRows writes lane i's words to its column (stride 128) and returns how many.
__device__ __forceinline__ int stageRows(
  int n, int i, const int* rowBegin, const unsigned* masks, uint2* word)
{
  int count = 0;
#pragma unroll
  for (int r = 0; r < 9; ++r)
  {
    const unsigned mask = masks[r * n + i];
    if (mask != 0)
    {
      word[count * 128] = make_uint2(rowBegin[r * n + i], mask);
      ++count;
    }
  }
  return count;
}

// The staged walk (gatherStagedAs<float3, false>: the solver's structure) and two variants of
// how a candidate's position reaches the lane (issue 21's lever "positions in 16 bytes", and a
// software pipeline):
//   P = float4: the positions padded to 16 bytes, one 128-bit load a visit instead of three;
//   Prefetch:   the next candidate is found and its position loaded before this one's terms are
//               computed, so the load's latency overlaps the arithmetic.
__device__ __forceinline__ float3 position(const float3* p, unsigned j)
{
  return p[j];
}
__device__ __forceinline__ float3 position(const float4* p, unsigned j)
{
  const float4 q = p[j];
  return make_float3(q.x, q.y, q.z);
}

template <class P, bool Prefetch>
__global__ void gatherStagedAs(int n, const P* p, const int* rowBegin, const unsigned* masks,
  float* rho, float* lambda)
{
  __shared__ uint2 words[9][128];
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n)
  {
    return;
  }
  uint2* word = &words[0][threadIdx.x];
  const int count = stageRows(n, i, rowBegin, masks, word);
  const float3 pi = position(p, i);
  Sums s{ 0, 0, 0, 0, 0 };
  const uint2* const last = word + count * 128;
  unsigned mask = 0, base = 0;
  // The next candidate, false when there is none.
  const auto next = [&](unsigned& j) {
    if (mask == 0)
    {
      if (word == last)
      {
        return false;
      }
      const uint2 w = *word;
      word += 128;
      base = w.x;
      mask = w.y;
    }
    const int k = __clz(static_cast<int>(mask));
    mask &= 0x7fffffffu >> k;
    j = base + k;
    return true;
  };
  unsigned j = 0;
  if (!Prefetch)
  {
    while (next(j))
    {
      visit(pi, position(p, j), s);
    }
  }
  else if (next(j))
  {
    float3 pj = position(p, j);
    for (;;)
    {
      const float3 current = pj;
      const bool more = next(j);
      if (more)
      {
        pj = position(p, j);
      }
      visit(pi, current, s);
      if (!more)
      {
        break;
      }
    }
  }
  rho[i] = s.rho;
  lambda[i] = lambdaOf(s);
}

__device__ __forceinline__ void add(unsigned long long* a, float v)
{
  atomicAdd(a, static_cast<unsigned long long>(__float2ll_rn(v * kFix)));
}
__device__ __forceinline__ void add(float* a, float v)
{
  atomicAdd(a, v);
}

// T: unsigned long long (fixed point, deterministic) or float.
template <class T>
__global__ void once(int L, const float3* p, T* acc)
{
  int i, x, y, z;
  if (!latticeSite(L, i, x, y, z))
  {
    return;
  }
  const float3 pi = p[i];
  Sums s{ 1.0f, 0, 0, 0, 0 }; // itself: w(0) = 1, no gradient
  for (int k = 1; k <= cForward; ++k)
  {
    int j;
    if (!neighbour(L, x, y, z, cOffsets[k], j))
    {
      continue;
    }
    float w;
    float3 g;
    if (visit(pi, p[j], s, w, g))
    {
      const float g2 = g.x * g.x + g.y * g.y + g.z * g.z;
      // j sees -r: the same w and g2, the gradient reversed.
      add(&acc[5 * j + 0], w);
      add(&acc[5 * j + 1], -g.x);
      add(&acc[5 * j + 2], -g.y);
      add(&acc[5 * j + 3], -g.z);
      add(&acc[5 * j + 4], g2);
    }
  }
  add(&acc[5 * i + 0], s.rho);
  add(&acc[5 * i + 1], s.gx);
  add(&acc[5 * i + 2], s.gy);
  add(&acc[5 * i + 3], s.gz);
  add(&acc[5 * i + 4], s.g2);
}

__device__ __forceinline__ float value(unsigned long long a)
{
  return static_cast<float>(static_cast<double>(static_cast<long long>(a)) / kFix);
}
__device__ __forceinline__ float value(float a)
{
  return a;
}

template <class T>
__global__ void finish(int n, const T* acc, float* rho, float* lambda)
{
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n)
  {
    return;
  }
  const Sums s{ value(acc[5 * i]), value(acc[5 * i + 1]), value(acc[5 * i + 2]),
    value(acc[5 * i + 3]), value(acc[5 * i + 4]) };
  rho[i] = s.rho;
  lambda[i] = lambdaOf(s);
}

float median(std::vector<float> v)
{
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

} // namespace

int main(int argc, char** argv)
{
  const int L = argc > 1 ? std::atoi(argv[1]) : 100;
  const int n = L * L * L;
  const int warmup = 5, timed = 30, block = 128, grid = (n + block - 1) / block;

  // Offsets with |v|^2 <= 4, itself first, then those after it in index order (the forward half).
  std::vector<int3> forward, backward;
  for (int z = -2; z <= 2; ++z)
    for (int y = -2; y <= 2; ++y)
      for (int x = -2; x <= 2; ++x)
      {
        const int d2 = x * x + y * y + z * z;
        if (d2 == 0 || d2 > 4)
          continue;
        const long key = (static_cast<long>(z) * L + y) * L + x;
        (key > 0 ? forward : backward).push_back(make_int3(x, y, z));
      }
  std::vector<int3> offsets{ make_int3(0, 0, 0) };
  offsets.insert(offsets.end(), forward.begin(), forward.end());
  offsets.insert(offsets.end(), backward.begin(), backward.end());
  const int forwardCount = static_cast<int>(forward.size());
  CHECK(cudaMemcpyToSymbol(cOffsets, offsets.data(), sizeof(int3) * offsets.size()));
  CHECK(cudaMemcpyToSymbol(cForward, &forwardCount, sizeof(int)));

  // The lattice jittered by up to 0.05 spacings (a fixed hash, so every run sees the same): no
  // pair beyond the 33 offsets (|v|^2 = 5 is 2.24 apart) comes within h, so every variant sums
  // the same pairs.
  std::vector<float3> host(n);
  std::uint32_t state = 12345;
  auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return (static_cast<float>(state >> 8) / 16777216.0f - 0.5f) * 0.1f;
  };
  for (int i = 0; i < n; ++i)
  {
    host[i] = make_float3(i % L + next(), (i / L) % L + next(), i / (L * L) + next());
  }
  float3* p;
  float *rhoA, *lamA, *rhoB, *lamB, *accF;
  unsigned long long* accI;
  CHECK(cudaMalloc(&p, sizeof(float3) * n));
  CHECK(cudaMalloc(&rhoA, sizeof(float) * n));
  CHECK(cudaMalloc(&lamA, sizeof(float) * n));
  CHECK(cudaMalloc(&rhoB, sizeof(float) * n));
  CHECK(cudaMalloc(&lamB, sizeof(float) * n));
  CHECK(cudaMalloc(&accI, sizeof(unsigned long long) * 5 * n));
  CHECK(cudaMalloc(&accF, sizeof(float) * 5 * n));
  CHECK(cudaMemcpy(p, host.data(), sizeof(float3) * n, cudaMemcpyHostToDevice));

  // The same particles sorted by cell, with each one's candidates as a list and as row masks.
  const int nc = (L + 1) / 2 + 1; // cells of size h = 2 along each axis (jitter reaches -0.15)
  auto cellOf = [&](const float3& q) {
    auto c = [&](float v) { return std::min(nc - 1, std::max(0, static_cast<int>((v + 0.5f) / kH))); };
    return (c(q.z) * nc + c(q.y)) * nc + c(q.x);
  };
  std::vector<int> order(n), cellStart(static_cast<std::size_t>(nc) * nc * nc + 1, 0);
  for (int i = 0; i < n; ++i)
  {
    order[i] = i;
    ++cellStart[cellOf(host[i]) + 1];
  }
  std::stable_sort(order.begin(), order.end(),
    [&](int a, int b) { return cellOf(host[a]) < cellOf(host[b]); });
  for (std::size_t c = 1; c < cellStart.size(); ++c)
    cellStart[c] += cellStart[c - 1];
  std::vector<float3> sorted(n);
  for (int k = 0; k < n; ++k)
    sorted[k] = host[order[k]];
  const float reach2 = (1.075f * kH) * (1.075f * kH); // the solver's skin, 0.075 h
  std::vector<int> count(n, 0), rowBegin(9 * static_cast<std::size_t>(n), 0);
  std::vector<unsigned> masks(9 * static_cast<std::size_t>(n), 0u);
  std::vector<std::vector<int>> lists(n);
  long lost = 0, listed = 0;
  for (int i = 0; i < n; ++i)
  {
    const float3 q = sorted[i];
    const int c = cellOf(q);
    const int cx = c % nc, cy = (c / nc) % nc, cz = c / (nc * nc);
    for (int r = 0; r < 9; ++r)
    {
      const int z = cz - 1 + r / 3, y = cy - 1 + r % 3;
      if (z < 0 || y < 0 || z >= nc || y >= nc)
        continue;
      const int row = (z * nc + y) * nc;
      const int b = cellStart[row + std::max(cx - 1, 0)];
      const int e = cellStart[row + std::min(cx + 1, nc - 1) + 1];
      rowBegin[static_cast<std::size_t>(r) * n + i] = b;
      for (int j = b; j < e; ++j)
      {
        const float dx = q.x - sorted[j].x, dy = q.y - sorted[j].y, dz = q.z - sorted[j].z;
        if (dx * dx + dy * dy + dz * dz >= reach2)
          continue;
        lists[i].push_back(j);
        if (j - b < 32)
          masks[static_cast<std::size_t>(r) * n + i] |= 0x80000000u >> (j - b);
        else
          ++lost;
      }
    }
    count[i] = static_cast<int>(lists[i].size());
    listed += count[i];
  }
  const int width = *std::max_element(count.begin(), count.end());
  std::vector<int> list(static_cast<std::size_t>(width) * n, 0);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < count[i]; ++k)
      list[static_cast<std::size_t>(k) * n + i] = lists[i][k];
  lists.clear();
  float3* ps;
  int *dCount, *dList, *dRowBegin;
  unsigned* dMasks;
  float *rhoL, *rhoM;
  CHECK(cudaMalloc(&ps, sizeof(float3) * n));
  CHECK(cudaMalloc(&dCount, sizeof(int) * n));
  CHECK(cudaMalloc(&dList, sizeof(int) * list.size()));
  CHECK(cudaMalloc(&dRowBegin, sizeof(int) * rowBegin.size()));
  CHECK(cudaMalloc(&dMasks, sizeof(unsigned) * masks.size()));
  CHECK(cudaMalloc(&rhoL, sizeof(float) * n));
  CHECK(cudaMalloc(&rhoM, sizeof(float) * n));
  CHECK(cudaMemcpy(ps, sorted.data(), sizeof(float3) * n, cudaMemcpyHostToDevice));
  CHECK(cudaMemcpy(dCount, count.data(), sizeof(int) * n, cudaMemcpyHostToDevice));
  CHECK(cudaMemcpy(dList, list.data(), sizeof(int) * list.size(), cudaMemcpyHostToDevice));
  CHECK(cudaMemcpy(dRowBegin, rowBegin.data(), sizeof(int) * rowBegin.size(), cudaMemcpyHostToDevice));
  CHECK(cudaMemcpy(dMasks, masks.data(), sizeof(unsigned) * masks.size(), cudaMemcpyHostToDevice));

  cudaEvent_t t0, t1;
  CHECK(cudaEventCreate(&t0));
  CHECK(cudaEventCreate(&t1));
  auto timeIt = [&](auto&& run) {
    std::vector<float> ms;
    for (int k = 0; k < warmup + timed; ++k)
    {
      CHECK(cudaEventRecord(t0));
      run();
      CHECK(cudaEventRecord(t1));
      CHECK(cudaEventSynchronize(t1));
      float m;
      CHECK(cudaEventElapsedTime(&m, t0, t1));
      if (k >= warmup)
        ms.push_back(m);
    }
    CHECK(cudaGetLastError());
    return median(ms);
  };
  const float gatherMs = timeIt([&] { gather<<<grid, block>>>(L, p, rhoA, lamA); });
  const float fixedMs = timeIt([&] {
    cudaMemsetAsync(accI, 0, sizeof(unsigned long long) * 5 * n);
    once<<<grid, block>>>(L, p, accI);
    finish<<<grid, block>>>(n, accI, rhoB, lamB);
  });
  std::vector<float> a(n), b(n), b2(n);
  CHECK(cudaMemcpy(a.data(), rhoA, sizeof(float) * n, cudaMemcpyDeviceToHost));
  CHECK(cudaMemcpy(b.data(), rhoB, sizeof(float) * n, cudaMemcpyDeviceToHost));
  // A second run of the fixed-point variant: the same bits whatever the atomics' order.
  cudaMemset(accI, 0, sizeof(unsigned long long) * 5 * n);
  once<<<grid, block>>>(L, p, accI);
  finish<<<grid, block>>>(n, accI, rhoB, lamB);
  CHECK(cudaMemcpy(b2.data(), rhoB, sizeof(float) * n, cudaMemcpyDeviceToHost));
  const float floatMs = timeIt([&] {
    cudaMemsetAsync(accF, 0, sizeof(float) * 5 * n);
    once<<<grid, block>>>(L, p, accF);
    finish<<<grid, block>>>(n, accF, rhoB, lamB);
  });
  const float listMs = timeIt([&] { gatherList<<<grid, block>>>(n, ps, dCount, dList, rhoL, lamB); });
  const float maskMs =
    timeIt([&] { gatherMasks<<<grid, block>>>(n, ps, dRowBegin, dMasks, rhoM, lamB); });
  const float stagedMs =
    timeIt([&] { gatherStagedAs<float3, false><<<grid, block>>>(n, ps, dRowBegin, dMasks, rhoM, lamB); });
  std::vector<float> l(n), mk(n);
  CHECK(cudaMemcpy(l.data(), rhoL, sizeof(float) * n, cudaMemcpyDeviceToHost));
  CHECK(cudaMemcpy(mk.data(), rhoM, sizeof(float) * n, cudaMemcpyDeviceToHost));
  double worstSorted = 0;
  const auto compare = [&](const std::vector<float>& sortedRho) {
    for (int k = 0; k < n; ++k)
    {
      const double ref = a[order[k]];
      worstSorted = std::max(worstSorted, std::fabs(ref - sortedRho[k]) / std::fabs(ref));
    }
  };
  compare(l);
  compare(mk);
  // The staged walk with positions in 16 bytes and/or the next position loaded ahead.
  std::vector<float4> padded(n);
  for (int k = 0; k < n; ++k)
    padded[k] = make_float4(sorted[k].x, sorted[k].y, sorted[k].z, 0.0f);
  float4* ps4;
  CHECK(cudaMalloc(&ps4, sizeof(float4) * n));
  CHECK(cudaMemcpy(ps4, padded.data(), sizeof(float4) * n, cudaMemcpyHostToDevice));
  const auto timeVariant = [&](auto&& launch) {
    const float ms = timeIt(launch);
    std::vector<float> r(n);
    CHECK(cudaMemcpy(r.data(), rhoM, sizeof(float) * n, cudaMemcpyDeviceToHost));
    compare(r);
    return ms;
  };
  const float prefetchMs = timeVariant(
    [&] { gatherStagedAs<float3, true><<<grid, block>>>(n, ps, dRowBegin, dMasks, rhoM, lamB); });
  const float wideMs = timeVariant(
    [&] { gatherStagedAs<float4, false><<<grid, block>>>(n, ps4, dRowBegin, dMasks, rhoM, lamB); });
  const float wideAheadMs = timeVariant(
    [&] { gatherStagedAs<float4, true><<<grid, block>>>(n, ps4, dRowBegin, dMasks, rhoM, lamB); });
  double worst = 0;
  bool same = true;
  for (int i = 0; i < n; ++i)
  {
    worst = std::max(worst, std::fabs(static_cast<double>(a[i]) - b[i]) / std::fabs(a[i]));
    same = same && b[i] == b2[i];
  }
  int device;
  cudaDeviceProp prop;
  CHECK(cudaGetDevice(&device));
  CHECK(cudaGetDeviceProperties(&prop, device));
  std::printf("pair_once_probe: %s, %d particles, %d forward of 32 candidates, medians of %d\n",
    prop.name, n, forwardCount, timed);
  std::printf("rho, once+fix against gather: largest relative difference %.2e; two once+fix "
              "runs %s\n",
    worst, same ? "bit-identical" : "DIFFER");
  std::printf("pair_once_probe ms: gather %.4f, once+fix %.4f (%+.1f %%), once+f32 %.4f "
              "(%+.1f %%)\n",
    gatherMs, fixedMs, 100.0 * (fixedMs / gatherMs - 1.0), floatMs,
    100.0 * (floatMs / gatherMs - 1.0));
  std::printf("cell-sorted: %.2f candidates within h + skin a particle (%ld beyond a mask's 32), "
              "list and masks against gather: largest relative difference %.2e\n",
    static_cast<double>(listed) / n, lost, worstSorted);
  std::printf("pair_once_probe ms, cell-sorted: list %.4f (%+.1f %%), row masks row by row %.4f "
              "(%+.1f %%), row masks staged as the solver's %.4f (%+.1f %%)\n",
    listMs, 100.0 * (listMs / gatherMs - 1.0), maskMs, 100.0 * (maskMs / gatherMs - 1.0), stagedMs,
    100.0 * (stagedMs / gatherMs - 1.0));
  std::printf("pair_once_probe ms, staged: next position loaded ahead %.4f (%+.1f %% against "
              "staged), positions in 16 bytes %.4f (%+.1f %%), both %.4f (%+.1f %%)\n",
    prefetchMs, 100.0 * (prefetchMs / stagedMs - 1.0), wideMs, 100.0 * (wideMs / stagedMs - 1.0),
    wideAheadMs, 100.0 * (wideAheadMs / stagedMs - 1.0));
  return worst < 1e-4 && worstSorted < 1e-4 && same && lost == 0 ? 0 : 1;
}
