// The stages of the CUDA backend's step as per-particle passes over an executor: DeviceStepLoop.h
// runs them in StepLoop.h's order for the CUDA stepper, DeviceSubdomainSolve.h for one rank's GPU
// sub-domain. The executor is the device policy's (kernels, CUB and CUDA graphs on CUDA) or the
// host policy in the tests, where the step must reproduce the serial backend bit for bit
// (Testing/Cuda/DeviceStepperHostTest.cpp). The step's buffers and constants are in StepBuffers.h,
// its passes in StepPasses.h; here are the views the passes read, the sort and the entry points.
//
// They are the CPU's stages with the memory of a GPU in mind:
// - Algorithm 1's arrays rotate through four Vec3 buffers instead of six plus gather copies;
//   between steps x and v live in vec[0] and vec[1] (in either order, see Roles).
// - The sort is stable and keyed like the CPU's counting sort, so the permutation is the same.
// - The Jacobi update (applyCorrection) is fused into positionCorrection by writing the corrected
//   positions to the other of two position buffers, and updateVelocity into the last correction
//   (with a fixed count; in adaptive mode into the pass after the solve, finishAdaptiveSolve).
// - Algorithm 1, line 23 (x_i = x*_i) is a relabelling: the corrected positions' buffer becomes x.
// - The neighbour passes walk row masks (NeighborMasks.h) or, with masks off, the 27 cells.
//
// Executor interface (Exec):
//   forEach(Stage, n, f)                 f(i) for i in [0, n), in any order
//   forEachMax(Stage, n, maxBits, f)     as forEach; *maxBits = max(*maxBits, bits of f(i) >= 0)
//   forEachMaxSum(Stage, n, maxBits, Part{}, sums, f)   a neighbour pass as forEachMax, f(i, part)
//                                        also filling a Part (WallLoads.h's WallLoadPart) whose
//                                        groups each warp of 32 adds (lane l + 16, then + 8, ...)
//                                        to its sums over the step (WarpSums: a bit per group
//                                        in flags, zeroed by the step)
//   sortByKey(keys, keysAlt, values, valuesAlt, n, keyBits) -> SortedPairs (stable radix sort)
//   maxScan(data, count)                 inclusive max-scan in place
//   fillZero(pointer, bytes), copy(destination, source, bytes)
//   reduceCompression(density, liquid, n, state, blockSums, constants, tolerance[, next])
//                                        adaptive mode, see AdaptiveState (blockSums: 2 per block
//                                        of kCompressionBlock, 2 liquids + 1 with several liquids:
//                                        the mean is the most compressed liquid's); a negative
//                                        tolerance never finishes;
//                                        next (a Branch) is set to whether the solve goes on
//   Branch, branch() -> Branch           a condition for one body of runIfChain, off unless a
//                                        reduction sets it (Exec::noBranch() names none)
//   sumLoads(n, count, state, blockSums, loads, f)   loads[o * kLoadValues + v] += the sum over
//                                        i in [0, n) of what f(i, o, acc) adds to acc[v], for
//                                        o in [0, count): per load, kLoadBlocks blocks of 256
//                                        lanes, particle i in lane i % 256 of block
//                                        (i / 256) % kLoadBlocks, each block's lanes added in a
//                                        fixed tree, then the blocks' sums likewise (blockSums:
//                                        kLoadValues per block and load); nothing once state
//                                        (may be null) is done
//   runIfChain(branches, first, end, body)   body(exec', k) for k = first, first + 1, ... < end,
//                                        each only when branches[k] is set and every body before
//                                        it ran: while the step is captured, CUDA graph conditional
//                                        nodes nested in each other, so that the first condition
//                                        not set skips the rest at once; elsewhere every body at
//                                        once (on the GPU its kernels then return at once after
//                                        done, see AdaptiveState)
#pragma once

#include "Chebyshev.h"
#include "Equations.h"
#include "Grid.h"
#include "HostDevice.h"
#include "NeighborMasks.h"
#include "StepBuffers.h"
#include "StepPasses.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pbf
{
namespace cuda
{
namespace detail
{

template <class Real>
FluidView<Real> plainView(const StepConstants<Real>& k)
{
  FluidView<Real> f{};
  f.grid = GridView<Real>{ k.geometry, nullptr, nullptr };
  f.c = k.c;
  f.time = k.time;
  f.obstacles = k.obstacles;
  f.obstacleCount = k.obstacleCount;
  f.boundary = k.boundary;
  return f;
}

// to[i] = from[perm[i]], and the grid's cell offsets from the sorted keys: offsets[c] = the
// particles with key < c. Each run of equal keys writes its end at key + 1 and a max-scan fills
// the empty cells in between: every entry is written once, no atomics.
template <class Real, class Exec>
void gatherWithOffsets(Exec& exec, const StepConstants<Real>& k, std::uint32_t n,
  const CellKey* keys, const std::uint32_t* perm, const Vec3<Real>* from, Vec3<Real>* to,
  std::uint32_t* offsets)
{
  exec.fillZero(offsets, (static_cast<std::size_t>(k.cellCount) + 1) * sizeof(std::uint32_t));
  exec.forEach(GatherStage{}, n, [=] PBF_HD(std::uint32_t i) {
    to[i] = from[perm[i]];
    if (i + 1 == n || keys[i] != keys[i + 1])
    {
      offsets[keys[i] + 1] = i + 1;
    }
  });
  exec.maxScan(offsets, static_cast<std::size_t>(k.cellCount) + 1);
}

// Sorts by the keys in keys[0] (values: the identity in lambda), builds the cell offsets and
// gathers every array into cell order (density and lambda aside: the step computes them again;
// the pressure is a mean over the frame's steps so far). On entry A = x, B = v, C = p (old
// order), D is free; on exit D = x, A = p, C = v (cell order) and B is free. Returns the sorted
// keys.
template <class Real, class Exec>
const CellKey* sortAndGather(Exec& exec, const StepBuffers<Real>& b, const StepConstants<Real>& k,
  std::uint32_t n, Vec3<Real>* A, Vec3<Real>* B, Vec3<Real>* C, Vec3<Real>* D)
{
  const SortedPairs sorted = exec.sortByKey(b.keys[0], b.keys[1],
    reinterpret_cast<std::uint32_t*>(b.lambda), reinterpret_cast<std::uint32_t*>(b.density), n,
    k.keyBits);
  const CellKey* keys = sorted.keys;
  const std::uint32_t* perm = sorted.values;

  gatherWithOffsets(exec, k, n, keys, perm, A, D, b.cellOffsets);
  exec.forEach(GatherStage{}, n, [=] PBF_HD(std::uint32_t i) { A[i] = C[perm[i]]; });
  exec.forEach(GatherStage{}, n, [=] PBF_HD(std::uint32_t i) { C[i] = B[perm[i]]; });
  // B is free now; it holds the gathered ids until they are copied back.
  std::int64_t* id = b.id;
  std::int64_t* idSorted = reinterpret_cast<std::int64_t*>(B);
  exec.forEach(GatherStage{}, n, [=] PBF_HD(std::uint32_t i) { idSorted[i] = id[perm[i]]; });
  exec.copy(id, idSorted, static_cast<std::size_t>(n) * sizeof(std::int64_t));
  if (b.liquid)
  {
    // B again, for the liquids.
    std::uint8_t* liquid = b.liquid;
    std::uint8_t* liquidSorted = reinterpret_cast<std::uint8_t*>(B);
    exec.forEach(GatherStage{}, n, [=] PBF_HD(std::uint32_t i) { liquidSorted[i] = liquid[perm[i]]; });
    exec.copy(liquid, liquidSorted, static_cast<std::size_t>(n));
  }
  Real* pressure = b.pressure;
  Real* pressureSorted = reinterpret_cast<Real*>(B);
  exec.forEach(
    GatherStage{}, n, [=] PBF_HD(std::uint32_t i) { pressureSorted[i] = pressure[perm[i]]; });
  exec.copy(pressure, pressureSorted, static_cast<std::size_t>(n) * sizeof(Real));
  return keys;
}

template <class Real>
FluidView<Real, MaskedNeighbors<Real>> solverView(const StepBuffers<Real>& b,
  const StepConstants<Real>& k, const CellKey* sortedKeys)
{
  FluidView<Real, MaskedNeighbors<Real>> f{};
  f.density = b.density;
  f.lambda = b.lambda;
  f.pressure = b.pressure;
  f.liquid = b.liquid;
  f.grid = MaskedNeighbors<Real>{ GridView<Real>{ k.geometry, b.cellOffsets, sortedKeys }, b.masks,
    b.stride, k.schedule.enabled != 0 };
  f.c = k.c;
  f.time = k.time;
  f.obstacles = k.obstacles;
  f.obstacleCount = k.obstacleCount;
  f.boundary = k.boundary;
  return f;
}

// Jacobi iteration `iteration` reads x and v and corrects the predicted positions, which
// alternate between two buffers: it reads positions[iteration & 1] and writes the other one
// (scratch), which the next iteration reads.
template <class Real>
FluidView<Real, MaskedNeighbors<Real>> iterationView(const StepBuffers<Real>& b,
  const StepConstants<Real>& k, const CellKey* sortedKeys, Vec3<Real>* x, Vec3<Real>* v,
  Vec3<Real>* const (&positions)[2], int iteration)
{
  FluidView<Real, MaskedNeighbors<Real>> f = solverView(b, k, sortedKeys);
  f.x = x;
  f.v = v;
  f.p = positions[iteration & 1];
  f.scratch = positions[(iteration + 1) & 1];
  f.volume = b.volume; // written by the last iteration's updateVelocity
  f.tensile = iteration == 0; // s_corr once per step, in the first projection
  return f;
}

// After the iterations (vorticity, XSPH, confinement): the corrected positions are
// positions[k.iterations & 1]; the other buffer (scratch) and x's, which the step no longer
// needs, hold omega and XSPH's sum: omega in x's and the sum in scratch here (the decomposed
// step's layout; the single-GPU step swaps them, see DeviceStepLoop::afterView).
template <class Real>
FluidView<Real, MaskedNeighbors<Real>> afterIterationsView(const StepBuffers<Real>& b,
  const StepConstants<Real>& k, const CellKey* sortedKeys, Vec3<Real>* x, Vec3<Real>* v,
  Vec3<Real>* const (&positions)[2])
{
  FluidView<Real, MaskedNeighbors<Real>> f = solverView(b, k, sortedKeys);
  f.p = positions[k.iterations & 1];
  f.v = v;
  f.omega = x;
  f.scratch = positions[(k.iterations + 1) & 1];
  f.smoothing = f.scratch;
  f.volume = b.volume;
  f.omegaLength = b.omegaLength;
  f.colour = b.colour;
  f.normal = b.normal;
  return f;
}

} // namespace detail

// CpuStepper::evaluateDensityAtRest: density and lambda of the current positions, nothing moves.
// Used after particles are added; x and v keep their buffers.
template <class Real, class Exec>
void enqueueEvaluateAtRest(Exec& exec, const StepBuffers<Real>& b, const StepConstants<Real>& k,
  std::uint32_t n, Roles roles, const CellKey** sortedKeysOut)
{
  Vec3<Real>* const A = b.vec[roles.x];
  Vec3<Real>* const B = b.vec[roles.v];
  Vec3<Real>* const C = b.vec[2];
  Vec3<Real>* const D = b.vec[3];
  exec.copy(C, A, static_cast<std::size_t>(n) * sizeof(Vec3<Real>)); // p = x
  {
    CellKey* keys = b.keys[0];
    std::uint32_t* order = reinterpret_cast<std::uint32_t*>(b.lambda);
    const GridGeometry<Real> geometry = k.geometry;
    exec.forEach(KeyStage{}, n, [=] PBF_HD(std::uint32_t i) {
      keys[i] = geometry.keyOf(C[i]);
      order[i] = i;
    });
  }
  const CellKey* sortedKeys = detail::sortAndGather(exec, b, k, n, A, B, C, D);
  *sortedKeysOut = sortedKeys;
  // A = x (sorted, equal to D), C = v.
  FluidView<Real, MaskedNeighbors<Real>> f = detail::solverView(b, k, sortedKeys);
  f.p = A;
  detail::withPass<detail::DensityPass>(b.liquid != nullptr, [&](auto pass) {
    detail::firstPassOnPositions(exec, DensityStage<Real>{}, b, k, n, f, 0, false, pass);
  });
  exec.copy(B, C, static_cast<std::size_t>(n) * sizeof(Vec3<Real>));
  // The pressure's mean goes on (sortAndGather carried it); appended particles start at 0.
}

// Sorts the positions x (n particles) into cell order on a grid of their own, as statistics()
// counts neighbours: keys, scratch for the permutation (2 n entries), the sorted positions and
// the grid's cell offsets are written; the state is not touched. Returns the sorted keys.
template <class Real, class Exec>
const CellKey* enqueueSortedCopy(Exec& exec, const StepConstants<Real>& k, std::uint32_t n,
  const Vec3<Real>* x, CellKey* keys, CellKey* keysAlt, std::uint32_t* order,
  std::uint32_t* orderAlt, Vec3<Real>* sorted, std::uint32_t* offsets)
{
  const GridGeometry<Real> geometry = k.geometry;
  exec.forEach(KeyStage{}, n, [=] PBF_HD(std::uint32_t i) {
    keys[i] = geometry.keyOf(x[i]);
    order[i] = i;
  });
  const SortedPairs s = exec.sortByKey(keys, keysAlt, order, orderAlt, n, k.keyBits);
  const CellKey* sortedKeys = s.keys;
  const std::uint32_t* perm = s.values;
  detail::gatherWithOffsets(exec, k, n, sortedKeys, perm, x, sorted, offsets);
  return sortedKeys;
}

} // namespace cuda
} // namespace pbf
