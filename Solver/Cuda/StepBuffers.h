// The state of the CUDA backend's step (StepSchedule.h): the stage tags that name its kernels,
// adaptive mode's state on the device, the buffers and constants every pass reads, and which
// buffers hold x and v between steps.
#pragma once

#include "Equations.h"
#include "Grid.h"
#include "NeighborMasks.h"
#include "Parameters.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace pbf
{
namespace cuda
{

// Stage tags: they name the kernels (profilers show them) and pick launch bounds; the density
// pass's depends on the precision (CudaStageKernels.cuh's Launch).
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

// Per warp of a pass that also sums (StepSchedule.h's forEachMaxSum): which groups its lanes
// added to (a bit each), and the warp's sums (the walls' loads: kGroups kGroupValues a warp).
struct WarpSums
{
  std::uint32_t* flags;
  double* values;
};

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
  Real* pressure;          // the pressure, a mean over the frame (recordPressure)
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
  // With mirror walls (null flags without): the corrections' warps' sums of the walls' loads
  // (their flags zeroed each step), the step's loads, kMirrorWalls of force and torque, and
  // their block sums (sumWallLoads: kLoadBlocks kWallLoadDoubles).
  WarpSums wallWarps;
  double* wallLoads;
  double* wallBlockSums;
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

} // namespace cuda
} // namespace pbf
