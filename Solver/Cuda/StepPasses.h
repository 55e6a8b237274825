// The per-particle passes of the CUDA backend's step (StepSchedule.h) over an executor: the mask
// rebuild of a pass that first sees new positions, the density, vorticity, colour and confinement
// passes with their optional terms compiled in or out, the fused correction, the solids' loads and
// the end of an adaptive solve.
#pragma once

#include "Equations.h"
#include "HostDevice.h"
#include "NeighborMasks.h"
#include "StepBuffers.h"
#include "WallLoads.h"

#include <cstdint>

namespace pbf
{
namespace cuda
{
namespace detail
{

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

// The colour gradients averaged into the normals (TensionPasses.h's smoothColour), after the
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

// One particle's correction (correctionPassOf): delta p_i, its mirror images' terms to onWall,
// and the Jacobi update; returns how far the particle moved, for the masks.
template <bool Accelerate, bool Liquids, bool Solids, class Real, class OnWall>
PBF_HD PBF_INLINE double correctParticle(std::uint32_t i,
  const FluidView<Real, MaskedNeighbors<Real>>& f, bool last, const AdaptiveState* state,
  Real omega, const MovedSinceSort& local, OnWall& onWall)
{
  FluidView<Real, MaskedNeighbors<Real>> apply = f;
  apply.p = f.scratch;
  apply.scratch = f.p;
  if (state && state->done)
  {
    // Adaptive mode is done: the positions stay where they are (finishAdaptiveSolve).
    return 0.0;
  }
  Vec3<Real> twoBack{};
  if constexpr (Accelerate)
  {
    twoBack = f.scratch[i];
  }
  // delta p_i lands in the other position buffer (f.scratch), which nobody reads in this
  // pass; applyCorrection then adds p_i to it in place. IEEE addition is commutative, so
  // this is exactly x*_i + delta p_i, and no particle reads a position that moved.
  positionCorrection<Real, MaskedNeighbors<Real>, OnWall&, Liquids, Solids>(i, f, onWall);
  const Vec3<Real> delta = f.scratch[i];
  applyCorrection<Solids>(i, apply);
  if constexpr (Accelerate)
  {
    f.scratch[i] = acceleratedCorrection<Solids>(f.scratch[i], twoBack, omega, f);
  }
  if (last)
  {
    updateVelocity(i, apply); // line 21 needs only particle i's own corrected position
  }
  // What the masks must allow for: delta p_i, or more where a solid or the blend moved the
  // particle on.
  const Real moved = Solids || Accelerate ? length(f.scratch[i] - f.p[i]) : Real(0);
  const double distance = static_cast<double>(length(delta) > moved ? length(delta) : moved);
  if (local.moved)
  {
    local.add(i, f.grid.cells.particleKeys[i], distance);
  }
  return distance;
}

// Lines 10-19 and, in the last iteration, 21: delta p_i (eq. 14) into f.scratch, then the Jacobi
// update in place there, so f.scratch holds the corrected positions afterwards; the largest
// |delta p_i| goes to maxMoved[iteration] for the mask schedule. With Chebyshev's acceleration
// (Accelerate: a projection after the first, Chebyshev.h) the update is blended with omega:
// f.scratch holds p^{k-1} when the pass starts (the projection before the last wrote there), so
// each particle reads its own before overwriting it, and no buffer is added. Accelerate false
// compiles the blend out, as withPass does for the optional terms of other passes: its registers
// would cost the plain projections. With Walls each warp also adds what its particles push the
// mirror walls with (WallLoads.h) to its sums in b.wallWarps, for sumWallLoads. Solids false
// compiles the obstacles out (a scene without them).
template <bool Accelerate, bool Liquids, bool Walls, bool Solids, class Real, class Exec,
  class Visit>
void correctionPassOf(Exec& exec, const StepBuffers<Real>& b, std::uint32_t n,
  const FluidView<Real, MaskedNeighbors<Real>>& f, int iteration, bool last,
  const AdaptiveState* state, Real omega, Visit visit)
{
  const MovedSinceSort local{ b.moved, b.cellMoved };
  if constexpr (Walls)
  {
    exec.forEachMaxSum(CorrectionStage{}, n, b.maxMoved + iteration, WallLoadPart<Real>{},
      b.wallWarps, [=] PBF_HD(std::uint32_t k, WallLoadPart<Real>& part) -> double {
        const std::uint32_t i = visit(k);
        WallTerms<Real> terms{ part.push, f.c.boxMin };
        const double distance =
          correctParticle<Accelerate, Liquids, Solids>(i, f, last, state, omega, local, terms);
        if (part.push.any())
        {
          part.p = f.p[i];
          part.boxMin = f.c.boxMin;
          part.boxMax = f.c.boxMax;
          part.scale = wallLoadScale<Real>(f);
        }
        return distance;
      });
  }
  else
  {
    exec.forEachMax(CorrectionStage{}, n, b.maxMoved + iteration,
      [=] PBF_HD(std::uint32_t k) -> double {
        NoWallTerms none;
        return correctParticle<Accelerate, Liquids, Solids>(
          visit(k), f, last, state, omega, local, none);
      });
  }
}

template <bool Walls, bool Solids, class Real, class Exec, class Visit>
void correctionPassWith(Exec& exec, const StepBuffers<Real>& b, std::uint32_t n,
  const FluidView<Real, MaskedNeighbors<Real>>& f, int iteration, bool last,
  const AdaptiveState* state, bool accelerate, Real omega, Visit visit)
{
  // The liquids' terms compiled in only where the particles carry liquids (positionCorrection).
  const bool liquids = f.liquid != nullptr;
  if (accelerate && liquids)
  {
    correctionPassOf<true, true, Walls, Solids>(
      exec, b, n, f, iteration, last, state, omega, visit);
  }
  else if (accelerate)
  {
    correctionPassOf<true, false, Walls, Solids>(
      exec, b, n, f, iteration, last, state, omega, visit);
  }
  else if (liquids)
  {
    correctionPassOf<false, true, Walls, Solids>(
      exec, b, n, f, iteration, last, state, omega, visit);
  }
  else
  {
    correctionPassOf<false, false, Walls, Solids>(
      exec, b, n, f, iteration, last, state, omega, visit);
  }
}

// The walls' sums are compiled in where the buffers hold a place for them (TankLoads), the
// obstacles where the scene has some.
template <class Real, class Exec, class Visit = AllParticles>
void correctionPass(Exec& exec, const StepBuffers<Real>& b, std::uint32_t n,
  const FluidView<Real, MaskedNeighbors<Real>>& f, int iteration, bool last,
  const AdaptiveState* state, bool accelerate, Real omega, Visit visit = Visit{})
{
  const bool walls = b.wallWarps.flags != nullptr, solids = f.obstacleCount > 0;
  if (walls && solids)
  {
    correctionPassWith<true, true>(
      exec, b, n, f, iteration, last, state, accelerate, omega, visit);
  }
  else if (walls)
  {
    correctionPassWith<true, false>(
      exec, b, n, f, iteration, last, state, accelerate, omega, visit);
  }
  else if (solids)
  {
    correctionPassWith<false, true>(
      exec, b, n, f, iteration, last, state, accelerate, omega, visit);
  }
  else
  {
    correctionPassWith<false, false>(
      exec, b, n, f, iteration, last, state, accelerate, omega, visit);
  }
}

static_assert(kWallLoadValues == kLoadValues, "a wall's load is a solid's: a force and a torque");

// The walls' loads that a step's corrections summed in the first `warps` warps of b.wallWarps,
// into b.wallLoads (kMirrorWalls loads of force and torque), in sumLoads' fixed order: once a
// step, after the solve (every correction adds to the warps' sums). Visit, the correction's,
// gives each translation unit kernels of its own, as loadsPass's does.
template <class Real, class Exec, class Visit>
void sumWallLoads(Exec& exec, const StepBuffers<Real>& b, std::uint32_t warps, Visit)
{
  if (!b.wallWarps.flags)
  {
    return;
  }
  const WarpSums sums = b.wallWarps;
  exec.sumLoads(warps, kMirrorWalls, nullptr, b.wallBlockSums, b.wallLoads,
    [=] PBF_HD(std::uint32_t w, int o, double* acc) {
      if (sums.flags[w] & (1u << o))
      {
        const double* v = sums.values + static_cast<std::size_t>(w) * kWallLoadDoubles +
          static_cast<std::size_t>(o) * kWallLoadValues;
        for (int k = 0; k < kWallLoadValues; ++k)
        {
          acc[k] += v[k];
        }
      }
    });
}

// What the fluid pushes each solid with in this projection (SolidTerms.h's solidLoads, the same
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

} // namespace cuda
} // namespace pbf
