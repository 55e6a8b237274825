// The solid obstacles (Boundary.h) as the stages see them: their distance fields near a particle,
// the collision with them, a solid's share of the density and the correction, what the fluid
// pushes each solid with, and the nearest solid as a mirror for surface tension.
#pragma once

#include "Boundary.h"
#include "FluidView.h"
#include "HostDevice.h"
#include "Vec3.h"

#include <cstdint>

namespace pbf
{

// A solid's s_corr with particle i: its image in the solid is of i's liquid (tensileDensity).
// Liquids false: one liquid, whatever f.liquid holds (the GPU compiles the liquids' terms out).
template <bool Liquids = true, class Real, class Neighbors>
PBF_HD PBF_INLINE Real solidTensile(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Real tensile = f.tensile ? f.time->tensile : Real(0);
  return Liquids && f.liquid ? tensile * f.time->liquidDensityRatio[f.liquid[i]] : tensile;
}

// Calls visit(o, d, gradient, g) for each solid o whose grid holds q (DistanceGridView::within):
// d the field there, gradient its gradient and g that gradient's length. A particle beyond a
// solid's grid skips it, so a solid costs the particles near it.
template <class Real, class Neighbors, class Visit>
PBF_HD PBF_INLINE void forEachSolidField(
  const Vec3<Real>& q, const FluidView<Real, Neighbors>& f, Visit&& visit)
{
  for (int o = 0; o < f.obstacleCount; ++o)
  {
    Vec3<Real> gradient;
    Real d;
    if (f.obstacles[o].within(q, &d, &gradient))
    {
      visit(o, d, gradient, length(gradient));
    }
  }
}

// What a solid adds to the sums of a particle at q, at outward normal n with the table's sums b
// at q's distance: the table's sums, the spiky and s_corr ones along their directions. Without a
// shape map both directions are n, the tangent plane's; with one (Scene/ShapeMap.h) the sums are
// the table's times the solid's factors there, 1 and n on a flat face.
template <class Real>
struct SolidSample
{
  Real poly6;            // density, before the mass
  Real spiky;            // eq. 8 and 14 along spikyDirection, before m / rho_0
  Real spiky2;           // eq. 11's denominator
  Real tensile;          // s_corr along tensileDirection, before this step's coefficient
  Vec3<Real> spikyDirection, tensileDirection;
  bool shaped;           // false: both directions are n
};

template <class Real>
PBF_HD PBF_INLINE SolidSample<Real> solidSample(const DistanceGridView<Real>& solid,
  const Vec3<Real>& q, const Vec3<Real>& n, const BoundarySample<Real>& b)
{
  if (!solid.shape)
  {
    return { b.poly6, b.spiky, b.spiky2, b.tensile, n, n, false };
  }
  Real r[kShapeValues];
  solid.shapeAt(q, r);
  return { b.poly6 * r[0], b.spiky, b.spiky2 * r[4], b.tensile, Vec3<Real>{ r[1], r[2], r[3] },
    Vec3<Real>{ r[5], r[6], r[7] }, true };
}

// Calls visit(n, s, solid) for each solid within h of q: n its outward unit normal there (the
// field's gradient), s what it adds to q's sums (SolidSample), solid its view (for its velocity).
template <class Real, class Neighbors, class Visit>
PBF_HD PBF_INLINE void forEachNearSolid(
  const Vec3<Real>& q, const FluidView<Real, Neighbors>& f, Visit&& visit)
{
  forEachSolidField(q, f, [&](int o, Real d, const Vec3<Real>& gradient, Real g) {
    if (d < f.c.kernels.h && g > Real(0))
    {
      const Vec3<Real> n = gradient * (Real(1) / g);
      visit(n, solidSample(f.obstacles[o], q, n, sampleBoundary(f.boundary, d)), f.obstacles[o]);
    }
  });
}

// The solid nearest to a particle within h, as surface tension sees it: a mirror at the solid's
// tangent plane there, as the boundary's sums take it (Boundary.h). Its images continue the
// colour and the surface into the solid as the walls' images do (SurfaceTension.h), so a solid is
// no surface, and its contact angle acts at the contact line. solid < 0: none within h.
template <class Real>
struct SolidMirror
{
  int solid;     // its index among the obstacles
  Vec3<Real> n;  // its outward unit normal
  Real offset;   // the plane: dot(n, x) = offset
  Real distance; // of the particle from it, in [0, h)

  // q reflected in the plane; an image is never closer to a particle on the fluid's side than q.
  PBF_HD PBF_INLINE Vec3<Real> image(const Vec3<Real>& q) const
  {
    return q - n * (Real(2) * (dot(n, q) - offset));
  }
  // A direction seen in the mirror.
  PBF_HD PBF_INLINE Vec3<Real> reflect(const Vec3<Real>& v) const
  {
    return v - n * (Real(2) * dot(n, v));
  }
};

template <class Real>
PBF_HD PBF_INLINE SolidMirror<Real> noSolid()
{
  return SolidMirror<Real>{ -1, Vec3<Real>{ Real(0), Real(0), Real(0) }, Real(0), Real(0) };
}

template <class Real, class Neighbors>
PBF_HD PBF_INLINE SolidMirror<Real> nearestSolid(
  const Vec3<Real>& q, const FluidView<Real, Neighbors>& f)
{
  SolidMirror<Real> m{ -1, Vec3<Real>{ Real(0), Real(0), Real(0) }, Real(0), f.c.kernels.h };
  forEachSolidField(q, f, [&](int o, Real d, const Vec3<Real>& gradient, Real g) {
    d = d < Real(0) ? Real(0) : d; // inside: on its surface, where the collision puts it
    if (d < m.distance && g > Real(0))
    {
      m.solid = o;
      m.n = gradient * (Real(1) / g);
      m.distance = d;
      m.offset = dot(m.n, q) - d;
    }
  });
  return m;
}

// A solid's share of delta p_i (eq. 14, before m / rho_0), from what it adds to the sums there
// (SolidSample): it carries lambda_i, as a mirror image does, and s_corr's push.
// positionCorrection adds it; the particle pushes the solid back with it (solidLoads).
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> solidShare(const SolidSample<Real>& s, Real lambdaI, Real tensile)
{
  if (!s.shaped)
  {
    return s.spikyDirection * (s.spiky * (lambdaI + lambdaI) + tensile * s.tensile);
  }
  return s.spikyDirection * (s.spiky * (lambdaI + lambdaI)) +
    s.tensileDirection * (tensile * s.tensile);
}

// Collision looks at a solid with a shape map: near its edges the trilinear field bends, and a
// particle its gradient moved once can still be inside; the map's factors, which push the fluid
// closer to an edge than the tangent plane does, bring particles there.
constexpr int kCollisionLooks = 3;
// Where a mapped solid's collision puts a particle: this share of a cell outside its surface
// (a micrometre at 2 cm), so that single precision's rounding of the move (1e-7 m on a 1 m
// tank) leaves it outside, not on the surface a few nanometres in.
constexpr double kCollisionMargin = 1e-4;

// A particle inside an obstacle goes to its surface, along the field's gradient or the node
// tangent plane that finds it inside (DistanceGridView::contact). Solid by solid:
// each is asked where the particle is after the ones before it moved it; a solid with a map is
// asked again where its move left the particle, up to kCollisionLooks times, and put
// kCollisionMargin of a cell outside. One loop for both, so that the passes inline one lookup (a
// second copy for the later looks took the correction pass from 56 to 61 registers and the 1M
// step 2.5 % longer, solids or not).
template <class Real, class Neighbors>
PBF_HD PBF_INLINE Vec3<Real> collideWithObstacles(Vec3<Real> q, const FluidView<Real, Neighbors>& f)
{
  for (int o = 0; o < f.obstacleCount; ++o)
  {
    const DistanceGridView<Real>& solid = f.obstacles[o];
    const int looks = solid.shape ? kCollisionLooks : 1;
    const Real margin = solid.shape ? Real(kCollisionMargin) / solid.inverseCell : Real(0);
#if defined(__CUDACC__)
#pragma unroll 1
#endif
    for (int look = 0; look < looks; ++look)
    {
      Real d;
      Vec3<Real> gradient;
      if (!solid.contact(q, &d, &gradient))
      {
        break;
      }
      const Real g = length(gradient);
      if (!(d < Real(0) && g > Real(0)))
      {
        break;
      }
      q -= gradient * ((d - margin) / g);
    }
  }
  return q;
}

// What particle i pushes each solid with in this projection: the solid's share of its delta p_i
// (positionCorrection's) as a force, m delta p / dt^2, reversed, and that force's torque about
// the world's origin; add(solid index, force, torque). The same model that keeps the fluid out:
// a solid feels exactly what it does to the fluid.
template <class Real, class Neighbors, class Add>
PBF_HD PBF_INLINE void solidLoads(std::uint32_t i, const FluidView<Real, Neighbors>& f, Add&& add)
{
  const Vec3<Real> pi = f.p[i];
  const Real lambdaI = f.lambda[i];
  const Real tensile = solidTensile(i, f);
  const Real scale = -f.c.massOverRho0 * f.c.mass * f.time->inverseDt * f.time->inverseDt;
  forEachNearSolid(pi, f,
    [&](const Vec3<Real>&, const SolidSample<Real>& s, const DistanceGridView<Real>& solid) {
    const Vec3<Real> force = solidShare(s, lambdaI, tensile) * scale;
    add(static_cast<int>(&solid - f.obstacles), force, cross(pi, force));
  });
}

} // namespace pbf
