// The equations of Position Based Fluids (Macklin & Mueller 2013), one function per particle and
// stage, written once for every backend: the CPU loops and the CUDA kernels call exactly these.
// Equation numbers refer to the paper. Particles are in cell-sorted order; i and j index it.
// What the stages share lives in headers of their own, included here, so that a backend includes
// this one: FluidView.h (the coefficients and the particle arrays), WallMirrors.h (the box's
// walls), SolidTerms.h (the solid obstacles), and the passes after the solve in
// VorticityPasses.h and TensionPasses.h.
#pragma once

#include "Boundary.h"
#include "FluidView.h"
#include "Grid.h"
#include "HostDevice.h"
#include "Kernels.h"
#include "Parameters.h"
#include "SolidTerms.h"
#include "SurfaceTension.h"
#include "TensionPasses.h"
#include "Vec3.h"
#include "VorticityPasses.h"
#include "WallMirrors.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace pbf
{

// Algorithm 1, lines 1-4: apply gravity, predict x*_i = x_i + dt v_i.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void predictPosition(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Real dt = f.time->dt;
  const Vec3<Real> v = f.v[i] + f.c.gravity * dt;
  f.v[i] = v;
  f.p[i] = collideWithObstacles(collideWithBox(f.x[i] + v * dt, f.c), f);
}

// Eq. 2 (poly6 density), eq. 1 (C_i = rho_i / rho_0 - 1), eq. 8 (spiky constraint gradients) and
// eq. 11 (lambda_i with relaxation epsilon), in one pass over the neighbours and their images.
// Liquids false compiles the liquids' weight out (a GPU pass of a scene without liquids: the
// branch's registers made the double-precision passes spill).
template <class Real, class Neighbors, bool Liquids = true>
PBF_HD PBF_INLINE void densityAndLambda(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Vec3<Real> pi = f.p[i];
  const WallMirrors<Real> mirrors = nearWalls(pi, f.c);
  Real rho = Real(0);
  Vec3<Real> gradI{ Real(0), Real(0), Real(0) }; // grad_{p_i} C_i
  Real sumGradJ2 = Real(0);                      // sum_j |grad_{p_j} C_i|^2
  const bool reflections = hasReflections(mirrors);
  const auto add = [&](const Vec3<Real>& r, Real r2) {
    rho += f.c.kernels.poly6Within(r2);
    const Vec3<Real> g = f.c.kernels.spikyGradientWithin(r, r2) * f.c.massOverRho0;
    gradI += g;
    sumGradJ2 += dot(g, g);
  };
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> pj = f.p[j];
    const Vec3<Real> r = pi - pj;
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2)
    {
      add(r, r2);
      if (reflections)
      {
        forEachReflectionWithin(mirrors, pi, pj, f.c.kernels.h2, add);
      }
    }
  });
  // Each solid within h: its share, the lattice continued into it (Boundary.h, SolidTerms.h).
  forEachNearSolid(pi, f,
    [&](const Vec3<Real>&, const SolidSample<Real>& s, const DistanceGridView<Real>&) {
    rho += s.poly6;
    gradI += s.spikyDirection * (s.spiky * f.c.massOverRho0);
    sumGradJ2 += s.spiky2 * f.c.massOverRho0 * f.c.massOverRho0;
  });
  rho *= f.c.mass;
  Real C = rho * f.c.inverseRestDensity - Real(1);
  if (f.c.unilateral && C < Real(0))
  {
    C = Real(0);
  }
  f.density[i] = rho;
  const Real denominator = sumGradJ2 + dot(gradI, gradI) + f.c.relaxation;
  f.lambda[i] = -C * f.c.jacobiRelaxation /
    (Liquids && f.liquid ? denominator * liquidWeight(i, f) : denominator);
}

// The pressure p_i that the step's corrections of particle i stand for [Pa]. SPH's symmetric
// pressure acceleration, -sum_j m (p_i + p_j) / rho_0^2 grad W_ij, moves a particle by dt^2 times
// it in a step; eq. 14 moves it by (m / rho_0) sum_j (lambda_i + lambda_j) grad W_ij. The two
// agree term by term when p_i = -rho_0 lambda_i / dt^2, summed over the projections that were
// applied (a stopped solve applies none after it stops). That sum is then scaled by the
// lattice's gradient moment G (LatticeCalibration::gradientMoment): the discrete gradient
// reads G times a smooth field's, so water at rest holds itself up with 1 / G times rho_0 g d.
// s_corr's push is not part of it: it is an artificial pressure between pairs, not a
// particle's. The step's sum joins the particle's running mean over the frame (StepTime's
// pressureKeep and pressureWeight): the first projection (f.tensile) scales the mean so far,
// or drops it when a new mean starts (keep 0, so that an unset value never leaks in).
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void recordPressure(
  std::uint32_t i, const FluidView<Real, Neighbors>& f, Real lambdaI)
{
  if (f.pressure)
  {
    const StepTime<Real>& t = *f.time;
    const Real p = -f.c.pressureScale * lambdaI * t.inverseDt * t.inverseDt * t.pressureWeight;
    if (!f.tensile)
    {
      f.pressure[i] += p;
    }
    else
    {
      f.pressure[i] = t.pressureKeep == Real(0) ? p : f.pressure[i] * t.pressureKeep + p;
    }
  }
}

// positionCorrection's default: nothing is done with the mirror walls' terms.
struct NoWallTerms
{
  template <class... Any>
  PBF_HD PBF_INLINE void operator()(const Any&...) const
  {
  }
};

// Eq. 13 (s_corr, the artificial pressure against clustering) and eq. 14 (delta p_i). s_corr
// enters in the step's first projection only, with this step's coefficient (StepTime::tensile).
// onWall(term, mirrors, p_i, image, ix, iy, iz) hears each mirror image's term of delta p_i (before
// m / rho_0) with forEachReflection's arguments: what the walls' loads are made of (wallShares).
// Liquids false compiles the liquids' terms out, as densityAndLambda's; Solids false the solids'
// share (a GPU pass of a scene without obstacles: their code cost every correction 8 registers).
template <class Real, class Neighbors, class OnWall = NoWallTerms, bool Liquids = true,
  bool Solids = true>
PBF_HD PBF_INLINE void positionCorrection(
  std::uint32_t i, const FluidView<Real, Neighbors>& f, OnWall&& onWall = OnWall{})
{
  const Vec3<Real> pi = f.p[i];
  const WallMirrors<Real> mirrors = nearWalls(pi, f.c);
  const Real lambdaI = f.lambda[i];
  const Real tensile = f.tensile ? f.time->tensile : Real(0);
  Vec3<Real> delta{ Real(0), Real(0), Real(0) };
  const bool reflections = hasReflections(mirrors);
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> pj = f.p[j];
    const Vec3<Real> r = pi - pj;
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2)
    {
      const Real lambdaJ = f.lambda[j];
      const auto add = [&](const Vec3<Real>& d, Real d2) {
        // s_corr only in the step's first projection: the later ones do not evaluate poly6.
        Real sCorr = Real(0);
        if (tensile != Real(0))
        {
          const Real pair = Liquids && f.liquid ? tensile * tensileDensity(i, j, f) : tensile;
          sCorr = -pair * power(f.c.kernels.poly6Within(d2) * f.c.inverseWDeltaQ, f.c.sCorrN);
        }
        const Vec3<Real> term = f.c.kernels.spikyGradientWithin(d, d2) * (lambdaI + lambdaJ + sCorr);
        delta += term;
        return term;
      };
      // The particle itself needs no test: its gradient at r = 0 is exactly zero
      // (spikyGradientWithin), so it adds a zero to a sum that started at +0.
      add(r, r2);
      if (reflections)
      {
        // A particle's own reflections count: they are the wall's share next to it.
        forEachReflection(mirrors, pj, [&](const Vec3<Real>& image, int ix, int iy, int iz) {
          const Vec3<Real> d = pi - image;
          const Real d2 = dot(d, d);
          if (d2 < f.c.kernels.h2)
          {
            onWall(add(d, d2), mirrors, pi, image, ix, iy, iz);
          }
        });
      }
    }
  });
  if constexpr (Solids)
  {
    // The solid's share carries lambda_i, as a mirror image does (Boundary.h).
    const Real tensileI = solidTensile<Liquids>(i, f);
    forEachNearSolid(pi, f,
      [&](const Vec3<Real>&, const SolidSample<Real>& s, const DistanceGridView<Real>&) {
      delta += solidShare(s, lambdaI, tensileI);
    });
  }
  f.scratch[i] =
    delta * (Liquids && f.liquid ? f.c.massOverRho0 * liquidWeight(i, f) : f.c.massOverRho0);
  recordPressure(i, f, lambdaI);
}

// Algorithm 1, lines 17-19: apply delta p_i and resolve collisions (Jacobi update); Solids false:
// with the domain's walls only (a scene without obstacles).
template <bool Solids = true, class Real, class Neighbors>
PBF_HD PBF_INLINE void applyCorrection(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Vec3<Real> q = collideWithBox(f.p[i] + f.scratch[i], f.c);
  if constexpr (Solids)
  {
    f.p[i] = collideWithObstacles(q, f);
  }
  else
  {
    f.p[i] = q;
  }
}

// Chebyshev's acceleration of that update (Chebyshev.h): the Jacobi result `jacobi` blended with
// the particle's positions two projections back, p^{k+1} = p^{k-1} + omega (jacobi - p^{k-1}),
// then the collisions again (the blend may reach past a wall that jacobi was kept from).
template <bool Solids = true, class Real, class Neighbors>
PBF_HD PBF_INLINE Vec3<Real> acceleratedCorrection(const Vec3<Real>& jacobi,
  const Vec3<Real>& twoBack, Real omega, const FluidView<Real, Neighbors>& f)
{
  const Vec3<Real> q = collideWithBox(twoBack + (jacobi - twoBack) * omega, f.c);
  if constexpr (Solids)
  {
    return collideWithObstacles(q, f);
  }
  else
  {
    return q;
  }
}

// Algorithm 1, line 21: v_i = (x*_i - x_i) / dt. The density is final now, so the volume that the
// vorticity passes read is stored here when the view keeps one.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void updateVelocity(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  f.v[i] = (f.p[i] - f.x[i]) * f.time->inverseDt;
  if (f.volume)
  {
    f.volume[i] = f.c.mass / f.density[i];
  }
}

// Algorithm 1, line 23: x_i = x*_i. The step's start positions become the corrected ones.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void commitPosition(std::uint32_t i, const FluidView<Real, Neighbors>& f, Vec3<Real>* x)
{
  x[i] = f.p[i];
}

} // namespace pbf
