// The stages of the CUDA backend's step as per-particle passes over an executor: DeviceStepLoop.h
// runs them in StepLoop.h's order for the CUDA stepper, DeviceSubdomainSolve.h for one rank's GPU
// sub-domain. The executor is the device policy's (kernels, CUB and CUDA graphs on CUDA) or the
// host policy in the tests, where the step must reproduce the serial backend bit for bit
// (Testing/Cuda/DeviceStepperHostTest.cpp).
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

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pbf
{
namespace cuda
{

// Stage tags: they name the kernels (profilers show them) and pick launch bounds; the density
// pass's depends on the precision (CudaRuntime.cuh's Launch).
struct PredictStage {};
struct KeyStage {};
struct GatherStage {};
template <class Real>
struct DensityStage {};
struct CorrectionStage {};
// Friction: the pass that also smooths with the walls' images (VorticityPass<true>), a kernel of
// its own with a launch bound of its own.
// Colour: the pass also sums the colour gradient (surface tension), a kernel of its own too.
template <bool Friction, bool Colour = false>
struct VorticityStage {};
// smoothColour: the colour gradients averaged into the normals (surface tension only).
struct SmoothColourStage {};
template <bool Tension = false>
struct ConfinementStage {};

// Adaptive mode (Parameters::densityErrorTolerance > 0), kept on the device: after each density
// evaluation reduceCompression stores the mean compression mean(max(rho_i / rho_0 - 1, 0)) and
// either counts one more projection or, when it is within the tolerance, sets done. The
// projections after that are not run: in a captured step each one is the body of a conditional
// node that the previous reduction switches off (so a step of 2 projections under a cap of 40
// does not launch 38 empty ones); queued stage by stage, their kernels return at once. Either
// way the corrected positions stay in positions[iterations & 1], and one pass after the solve
// (finishAdaptiveSolve) moves them to where the captured step expects them and updates the
// velocity (line 21).
// Adaptive mode's mean compression is summed in blocks of this many particles, in order (on the
// device each block in a fixed tree, then the block sums by one block): the same on every run.
constexpr int kCompressionBlock = 4096;

// The solids' loads (StepLoop.h's sumLoads) are summed by this many blocks of 256 lanes, whatever
// the particle count (their partial sums then fit beside the solids, DeviceSolids.h): a force and
// a torque, kLoadValues doubles per block and solid.
constexpr int kLoadBlocks = 512;
constexpr int kLoadValues = 6;

struct AdaptiveState
{
  int done;
  int iterations;
  double densityError;    // the mean compression
  double maxDensityError; // the largest, which must also be within k.maxTolerance when > 0
  // With several liquids: each liquid's sum of compressions and its count (the ranks of a
  // decomposed run add them before taking each liquid's mean).
  double liquidSum[kMaxLiquids];
  double liquidCount[kMaxLiquids];
};

struct SortedPairs
{
  const CellKey* keys;
  const std::uint32_t* values;
};

template <class Real>
struct StepBuffers
{
  Vec3<Real>* vec[4];
  Real* density;
  Real* lambda;            // also the sort's values (the permutation) until density is evaluated
  Real* pressure;          // the step's pressure (recordPressure)
  Real* volume;            // m / rho_i for the vorticity passes; may be null (FluidView::volume)
  Real* omegaLength;       // |omega_i| for the confinement; may be null
  std::int64_t* id;
  std::uint8_t* liquid;    // each particle's liquid (Parameters::liquids); null: none named
  CellKey* keys[2];        // cell keys and the sort's alternate buffer
  std::uint32_t* masks;    // kNeighborRows * stride entries; null when masks are off
  std::uint32_t stride;    // capacity of every per-particle array
  std::uint32_t* cellOffsets; // cellCount + 1 entries
  unsigned long long* maxMoved;   // per solver iteration: max |delta p_i|, as double bits
  unsigned long long* maskBuilds; // particles' mask builds, for diagnostics only
  // Per-particle rebuilds (MovedSinceSort, NeighborMasks.h); null: the global bound of
  // MaskSchedule::rebuildAt decides for every particle at once.
  float* moved;                   // per particle
  std::uint32_t* cellMoved;       // cellCount entries
  AdaptiveState* adaptive;        // adaptive mode only
  double* blockSums;              // adaptive mode: the reduction's partial sums
  // Surface tension only (null without): grad c and its smoothed normal (FluidView::colour,
  // FluidView::normal), written and read after the solve.
  Vec3<Real>* colour;
  Vec3<Real>* normal;
};

template <class Real>
struct StepConstants
{
  Coefficients<Real> c;
  GridGeometry<Real> geometry;
  std::uint32_t cellCount;
  int keyBits;       // significant bits of a cell key: the radix sort's passes
  int iterations;    // solver iterations
  Real reach2;       // (h + skin)^2: what a mask marks
  MaskSchedule schedule;
  double tolerance;            // adaptive mode when > 0: densityErrorTolerance as a fraction
  double maxTolerance;         // maxDensityErrorTolerance as a fraction; 0: not a criterion
  double inverseRestDensity;   // 1 / rho_0 in double, for the compression of adaptive mode
  double chebyshevRho;         // Parameters::chebyshevRho: 0, plain Jacobi
  int liquids;                 // Parameters::liquidCount(): the compression's means by liquid
  // This step's dt and what follows from it, in the stepper's memory (device memory on a GPU):
  // the stepper writes it before a step, so a captured step reads the current values.
  const StepTime<Real>* time;
  // Solid obstacles (Physics/Boundary.h), in the stepper's memory; none unless it sets them.
  const DistanceGridView<Real>* obstacles;
  int obstacleCount;
  BoundaryTable<Real> boundary;
  // Per solid, beside them: the step's force and torque about the world's origin (kLoadValues
  // each), summed over its projections, and their block sums (sumLoads).
  double* loads;
  double* loadBlockSums;
};

// The constants of a step for given parameters: skin is how far beyond h the masks reach, as a
// fraction of h; masks off means the 27-cell walk. DeviceStepper and DeviceSubdomainStepper both
// build theirs here.
template <class Real>
StepConstants<Real> makeStepConstants(const Parameters& parameters, double skin, bool masks)
{
  const double h = parameters.smoothingLength();
  StepConstants<Real> k{};
  k.c = Coefficients<Real>::make(parameters);
  k.geometry = makeGridGeometry<Real>(parameters.domain, h);
  k.cellCount = k.geometry.cellCount();
  k.keyBits = 1;
  while (k.keyBits < 32 && (std::uint64_t(1) << k.keyBits) < k.cellCount)
  {
    ++k.keyBits;
  }
  k.iterations = parameters.solverIterations;
  const double reach = h * (1.0 + skin);
  k.reach2 = static_cast<Real>(reach * reach);
  const Box& d = parameters.domain;
  const double maxAbs = std::max({ std::abs(d.min.x), std::abs(d.min.y), std::abs(d.min.z),
    std::abs(d.max.x), std::abs(d.max.y), std::abs(d.max.z) });
  k.schedule.skin = skin * h;
  k.schedule.h = h;
  k.schedule.roundingPerStep = MaskSchedule::roundingBound<Real>(maxAbs);
  k.schedule.enabled = masks ? 1 : 0;
  k.tolerance = parameters.densityErrorTolerance / 100.0;
  k.maxTolerance = parameters.maxDensityErrorTolerance / 100.0;
  k.inverseRestDensity = 1.0 / parameters.restDensity;
  k.chebyshevRho = parameters.chebyshevRho;
  k.liquids = parameters.liquidCount();
  return k;
}

// Which of vec[0], vec[1] hold x and v between steps.
struct Roles
{
  int x = 0;
  int v = 1;
};

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
// gathers every array into cell order. On entry A = x, B = v, C = p (old order), D is free; on
// exit D = x, A = p, C = v (cell order) and B is free. Returns the sorted keys.
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

// A neighbour pass that is the first to see new positions: rebuild the masks first if the
// particles may have moved too far since they were built.
// Which particles a pass visits: all n (AllParticles, the single-GPU step), or those of a list
// (ListedParticles: a decomposed step runs a pass over the border particles first, so that their
// results can travel to the neighbours while the interior ones are computed).
struct AllParticles
{
  PBF_HD PBF_INLINE std::uint32_t operator()(std::uint32_t k) const { return k; }
};

struct ListedParticles
{
  const std::uint32_t* list;
  PBF_HD PBF_INLINE std::uint32_t operator()(std::uint32_t k) const { return list[k]; }
};

// One more particle's mask build in the diagnostics' count (a warp adds its builds at once).
PBF_HD PBF_INLINE void countBuild(unsigned long long* builds, bool rebuild)
{
#if defined(__CUDA_ARCH__)
  const unsigned ballot = __ballot_sync(__activemask(), rebuild);
  if (rebuild && (threadIdx.x & 31u) == static_cast<unsigned>(__ffs(static_cast<int>(ballot)) - 1))
  {
    atomicAdd(builds, static_cast<unsigned long long>(__popc(ballot)));
  }
#else
  *builds += rebuild ? 1u : 0u;
#endif
}

template <class Real, class Exec, class Stage, class Pass, class Visit = AllParticles>
void firstPassOnPositions(Exec& exec, Stage stage, const StepBuffers<Real>& b,
  const StepConstants<Real>& k, std::uint32_t n, const FluidView<Real, MaskedNeighbors<Real>>& f,
  int corrections, bool skipWhenDone, Pass pass, Visit visit = Visit{})
{
  const MaskSchedule schedule = k.schedule;
  const unsigned long long* maxMoved = b.maxMoved;
  unsigned long long* builds = b.maskBuilds;
  std::uint32_t* masks = b.masks;
  const Real reach2 = k.reach2;
  const AdaptiveState* adaptive = skipWhenDone ? b.adaptive : nullptr;
  const MovedSinceSort local{ b.moved, b.cellMoved };
  exec.forEach(stage, n, [=] PBF_HD(std::uint32_t k) {
    const std::uint32_t i = visit(k);
    if (adaptive && adaptive->done)
    {
      return;
    }
    if (!schedule.enabled)
    {
      pass(i, f);
      return;
    }
    bool rebuild;
    if (local.moved)
    {
      rebuild = corrections == 0 || !local.keeps(f.grid.cells, i, schedule, corrections);
      if (rebuild && corrections > 0)
      {
        local.mark(i);
      }
    }
    else
    {
      rebuild = schedule.rebuildAt(corrections, maxMoved);
    }
    countBuild(builds, rebuild);
    if (rebuild)
    {
      buildNeighborMasks(i, f.grid.cells, f.p, reach2, masks, f.grid.stride);
    }
    pass(i, f);
  });
}

// With Liquids false the liquids' weight is compiled out (densityAndLambda says why).
template <bool Liquids>
struct DensityPass
{
  template <class Real, class Neighbors>
  PBF_HD PBF_INLINE void operator()(std::uint32_t i, const FluidView<Real, Neighbors>& f) const
  {
    densityAndLambda<Real, Neighbors, Liquids>(i, f);
  }
};

// With Friction false the walls' friction is compiled out (vorticityAndXsph says why); with
// Colour false the colour gradient (surface tension), for the same reason; with Solids false the
// solids' images of the colour (a scene without solids).
template <bool Friction, bool Colour, bool Solids = false>
struct VorticityPass
{
  using Stage = VorticityStage<Friction, Colour>;

  template <class Real, class Neighbors>
  PBF_HD PBF_INLINE void operator()(std::uint32_t i, const FluidView<Real, Neighbors>& f) const
  {
    vorticityAndXsph<Real, Neighbors, Friction, Colour, Solids>(i, f);
  }
};
template <bool Friction>
using PlainVorticityPass = VorticityPass<Friction, false>;
template <bool Friction>
using ColourVorticityPass = VorticityPass<Friction, true>;
template <bool Friction>
using SolidColourVorticityPass = VorticityPass<Friction, true, true>;

// The colour gradients averaged into the normals (Equations.h's smoothColour), after the
// vorticity pass wrote them and before the confinement reads them; Solids as above. Over all n
// particles, or those of a list (a decomposed step's border, then its interior).
template <bool Solids, class Real, class Exec, class Visit = AllParticles>
void smoothColourPass(Exec& exec, std::uint32_t n, const FluidView<Real, MaskedNeighbors<Real>>& f,
  Visit visit = Visit{})
{
  exec.forEach(SmoothColourStage{}, n, [=] PBF_HD(std::uint32_t k) {
    smoothColour<Real, MaskedNeighbors<Real>, Solids>(visit(k), f);
  });
}

// The confinement pass (XSPH, its bi-Laplacian, eq. 16, surface tension) into velocity[i]; with
// SmoothTwice false the bi-Laplacian is compiled out, with Tension false surface tension, with
// Solids false the solids' images and adhesion.
template <bool SmoothTwice, bool Tension, bool Solids = false>
struct ConfinementPass
{
};
template <bool SmoothTwice>
using PlainConfinementPass = ConfinementPass<SmoothTwice, false>;
template <bool SmoothTwice>
using TensionConfinementPass = ConfinementPass<SmoothTwice, true>;
template <bool SmoothTwice>
using SolidTensionConfinementPass = ConfinementPass<SmoothTwice, true, true>;

template <class Real, class Exec, class Particles, bool SmoothTwice, bool Tension, bool Solids>
void confinementPass(Exec& exec, std::uint32_t n, Particles particles,
  const FluidView<Real, MaskedNeighbors<Real>>& f, Vec3<Real>* velocity,
  ConfinementPass<SmoothTwice, Tension, Solids>)
{
  exec.forEach(ConfinementStage<Tension>{}, n, [=] PBF_HD(std::uint32_t k) {
    vorticityConfinement<Real, MaskedNeighbors<Real>, SmoothTwice, Tension, Solids>(
      particles(k), f, velocity);
  });
}

// run(Pass<true>{}) when `on`, else run(Pass<false>{}): a pass whose optional terms are compiled
// out when unused (VorticityPass: wall friction; ConfinementPass: the bi-Laplacian), because
// their registers cost the kernels that do not need them.
template <template <bool> class Pass, class Run>
void withPass(bool on, Run&& run)
{
  if (on)
  {
    run(Pass<true>{});
  }
  else
  {
    run(Pass<false>{});
  }
}

// run(pass) with the confinement pass the view needs: surface tension only with its buffers
// (FluidView::colour), the solids' images only where the scene has solids.
template <class Real, class Run>
void withConfinementPass(const FluidView<Real, MaskedNeighbors<Real>>& f, Run&& run)
{
  if (f.colour && f.obstacleCount > 0)
  {
    withPass<SolidTensionConfinementPass>(f.c.xsphHyper, run);
  }
  else if (f.colour)
  {
    withPass<TensionConfinementPass>(f.c.xsphHyper, run);
  }
  else
  {
    withPass<PlainConfinementPass>(f.c.xsphHyper, run);
  }
}

// Lines 10-19 and, in the last iteration, 21: delta p_i (eq. 14) into f.scratch, then the Jacobi
// update in place there, so f.scratch holds the corrected positions afterwards; the largest
// |delta p_i| goes to maxMoved[iteration] for the mask schedule. With Chebyshev's acceleration
// (Accelerate: a projection after the first, Chebyshev.h) the update is blended with omega:
// f.scratch holds p^{k-1} when the pass starts (the projection before the last wrote there), so
// each particle reads its own before overwriting it, and no buffer is added. Accelerate false
// compiles the blend out, as withPass does for the optional terms of other passes: its registers
// would cost the plain projections.
template <bool Accelerate, bool Liquids, class Real, class Exec, class Visit>
void correctionPassOf(Exec& exec, const StepBuffers<Real>& b, std::uint32_t n,
  const FluidView<Real, MaskedNeighbors<Real>>& f, int iteration, bool last,
  const AdaptiveState* state, Real omega, Visit visit)
{
  const MovedSinceSort local{ b.moved, b.cellMoved };
  exec.forEachMax(CorrectionStage{}, n, b.maxMoved + iteration,
    [=] PBF_HD(std::uint32_t k) -> double {
      const std::uint32_t i = visit(k);
      FluidView<Real, MaskedNeighbors<Real>> apply = f;
      apply.p = f.scratch;
      apply.scratch = f.p;
      if (state && state->done)
      {
        // Adaptive mode is done: the positions stay where they are (finishAdaptiveSolve).
        return 0.0;
      }
      // omega is named here, outside the constexpr-if: nvcc's extended lambdas may not capture a
      // variable there first.
      const Real weight = omega;
      Vec3<Real> twoBack{};
      if constexpr (Accelerate)
      {
        twoBack = f.scratch[i];
      }
      // delta p_i lands in the other position buffer (f.scratch), which nobody reads in this
      // pass; applyCorrection then adds p_i to it in place. IEEE addition is commutative, so
      // this is exactly x*_i + delta p_i, and no particle reads a position that moved.
      positionCorrection<Real, MaskedNeighbors<Real>, NoWallTerms, Liquids>(i, f);
      const Vec3<Real> delta = f.scratch[i];
      applyCorrection(i, apply);
      if constexpr (Accelerate)
      {
        f.scratch[i] = acceleratedCorrection(f.scratch[i], twoBack, weight, f);
      }
      if (last)
      {
        updateVelocity(i, apply); // line 21 needs only particle i's own corrected position
      }
      // What the masks must allow for: delta p_i, or more where a solid or the blend moved the
      // particle on.
      const Real moved =
        f.obstacleCount > 0 || Accelerate ? length(f.scratch[i] - f.p[i]) : Real(0);
      const double distance = static_cast<double>(length(delta) > moved ? length(delta) : moved);
      if (local.moved)
      {
        local.add(i, f.grid.cells.particleKeys[i], distance);
      }
      return distance;
    });
}

template <class Real, class Exec, class Visit = AllParticles>
void correctionPass(Exec& exec, const StepBuffers<Real>& b, std::uint32_t n,
  const FluidView<Real, MaskedNeighbors<Real>>& f, int iteration, bool last,
  const AdaptiveState* state, bool accelerate, Real omega, Visit visit = Visit{})
{
  // The liquids' terms compiled in only where the particles carry liquids (positionCorrection).
  const bool liquids = f.liquid != nullptr;
  if (accelerate && liquids)
  {
    correctionPassOf<true, true>(exec, b, n, f, iteration, last, state, omega, visit);
  }
  else if (accelerate)
  {
    correctionPassOf<true, false>(exec, b, n, f, iteration, last, state, omega, visit);
  }
  else if (liquids)
  {
    correctionPassOf<false, true>(exec, b, n, f, iteration, last, state, omega, visit);
  }
  else
  {
    correctionPassOf<false, false>(exec, b, n, f, iteration, last, state, omega, visit);
  }
}

// What the fluid pushes each solid with in this projection (Equations.h's solidLoads, the same
// terms the correction that follows adds), into b.loads. The sums for solid o read a view of that
// solid alone, so that each particle looks up o's field only and the terms are added per solid.
template <class Real, class Exec, class Visit = AllParticles>
void loadsPass(Exec& exec, const StepConstants<Real>& k, std::uint32_t n,
  const FluidView<Real, MaskedNeighbors<Real>>& f, const AdaptiveState* state,
  Visit visit = Visit{})
{
  if (k.obstacleCount == 0 || !k.loads)
  {
    return;
  }
  exec.sumLoads(n, k.obstacleCount, state, k.loadBlockSums, k.loads,
    [=] PBF_HD(std::uint32_t k, int o, double* acc) {
      FluidView<Real, MaskedNeighbors<Real>> one = f;
      one.obstacles = f.obstacles + o;
      one.obstacleCount = 1;
      solidLoads(visit(k), one, [&](int, const Vec3<Real>& force, const Vec3<Real>& torque) {
        acc[0] += static_cast<double>(force.x);
        acc[1] += static_cast<double>(force.y);
        acc[2] += static_cast<double>(force.z);
        acc[3] += static_cast<double>(torque.x);
        acc[4] += static_cast<double>(torque.y);
        acc[5] += static_cast<double>(torque.z);
      });
    });
}

// Adaptive mode, after the projections: the corrected positions, in positions[state->iterations
// & 1] (the last projection run wrote there, or the first one not run would have read there), go
// to positions[iterations & 1], where the rest of the step reads them, and line 21 updates the
// velocity from them (the fused update of the last correction when the count is fixed).
template <class Real, class Exec>
void finishAdaptiveSolve(Exec& exec, std::uint32_t n, const FluidView<Real, MaskedNeighbors<Real>>& f,
  Vec3<Real>* const (&positions)[2], int iterations, const AdaptiveState* state)
{
  Vec3<Real>* const even = positions[0];
  Vec3<Real>* const odd = positions[1];
  const int end = iterations & 1;
  exec.forEach(CorrectionStage{}, n, [=] PBF_HD(std::uint32_t i) {
    const int at = state->iterations & 1;
    FluidView<Real, MaskedNeighbors<Real>> apply = f;
    apply.p = end == 0 ? even : odd;
    if (at != end)
    {
      apply.p[i] = (at == 0 ? even : odd)[i];
    }
    updateVelocity(i, apply);
  });
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
  // No step has corrected these positions: no pressure yet.
  exec.fillZero(b.pressure, static_cast<std::size_t>(n) * sizeof(Real));
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
