// The domain box's walls as the stages see them: the collision with the box, the mirror images
// of the neighbours near a wall that the density, correction, colour and friction terms read, and
// what a wall takes from those terms (its share of the loads, friction and adhesion).
#pragma once

#include "FluidView.h"
#include "HostDevice.h"
#include "SurfaceTension.h"
#include "Vec3.h"

namespace pbf
{

// Collision with the domain box: project the particle back inside (the paper's simple response).
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> collideWithBox(Vec3<Real> q, const Coefficients<Real>& c)
{
  q.x = q.x < c.boxMin.x ? c.boxMin.x : (q.x > c.boxMax.x ? c.boxMax.x : q.x);
  q.y = q.y < c.boxMin.y ? c.boxMin.y : (q.y > c.boxMax.y ? c.boxMax.y : q.y);
  q.z = q.z < c.boxMin.z ? c.boxMin.z : (q.z > c.boxMax.z ? c.boxMax.z : q.z);
  return q;
}

// Mirror walls: a particle within h of a domain wall also sees the reflections of its neighbours
// in that wall (and in both walls of an edge or corner), as if resting fluid continued beyond it.
// On the initial lattice, whose outer sites sit s/2 inside the walls, the images are exactly the
// lattice continued, so every particle reads rho_0 at rest; without them the unilateral
// constraint lets the fluid pack against the walls (a resting 12^3 block sank by a fifth). Images
// carry their particle's lambda. Only density and the position correction see them.
template <class Real>
struct WallMirrors
{
  int count[3];     // per axis: 1 (the neighbour itself) + the walls within h
  Real wall[3][2];  // the coordinates of those walls
};

template <class Real>
PBF_HD PBF_INLINE WallMirrors<Real> nearWalls(const Vec3<Real>& p, const Coefficients<Real>& c)
{
  WallMirrors<Real> m;
  const Real pa[3] = { p.x, p.y, p.z };
  const Real lo[3] = { c.boxMin.x, c.boxMin.y, c.boxMin.z };
  const Real hi[3] = { c.boxMax.x, c.boxMax.y, c.boxMax.z };
  // Unrolled, with the wall slot chosen by a branch rather than an index: on a GPU an array
  // indexed at run time lives in local memory.
#if defined(__CUDACC__)
#pragma unroll
#endif
  for (int a = 0; a < 3; ++a)
  {
    m.count[a] = 1;
    m.wall[a][0] = m.wall[a][1] = Real(0);
    if (!c.mirrorWalls)
    {
      continue;
    }
    if (pa[a] - lo[a] < c.kernels.h)
    {
      m.wall[a][0] = lo[a];
      m.count[a] = 2;
    }
    if (hi[a] - pa[a] < c.kernels.h)
    {
      if (m.count[a] == 1)
      {
        m.wall[a][0] = hi[a];
      }
      else
      {
        m.wall[a][1] = hi[a];
      }
      ++m.count[a];
    }
  }
  return m;
}

// Calls visit(image, ix, iy, iz) for each reflection of q in the walls of m (not q itself): ia is 0
// where the image is not reflected along axis a, else 1 + the slot of m.wall[a] it is reflected
// in. In the order of
// three nested loops over x, y, z (z innermost). A reflection is never closer to a particle on the
// fluid's side of a wall than q is, so the passes visit q's reflections only when q itself lies
// within h: most candidates, and every candidate of a particle that sees no wall, pay one test
// instead of the loop (on a GPU its counters and selects had been a sixth of the density pass's
// instructions). The wall is picked by a select, not an index, for the reason given in nearWalls;
// 2 w is exact, so an image is 2 w - q rounded once, whatever the path.
template <class Real, class Visit>
PBF_HD PBF_INLINE void forEachReflection(const WallMirrors<Real>& m, const Vec3<Real> q, Visit&& visit)
{
  const int images = m.count[0] * m.count[1] * m.count[2];
  int ix = 0, iy = 0, iz = 0;
  for (int k = 1; k < images; ++k)
  {
    // The next (ix, iy, iz), z fastest.
    if (++iz == m.count[2])
    {
      iz = 0;
      if (++iy == m.count[1])
      {
        iy = 0;
        ++ix;
      }
    }
    Vec3<Real> image;
    image.x = ix == 0 ? q.x : Real(2) * (ix == 1 ? m.wall[0][0] : m.wall[0][1]) - q.x;
    image.y = iy == 0 ? q.y : Real(2) * (iy == 1 ? m.wall[1][0] : m.wall[1][1]) - q.y;
    image.z = iz == 0 ? q.z : Real(2) * (iz == 1 ? m.wall[2][0] : m.wall[2][1]) - q.z;
    visit(image, ix, iy, iz);
  }
}

// Calls add(r, r2) for each reflection of q closer to p than h (r = p - reflection, r2 = |r|^2).
template <class Real, class Add>
PBF_HD PBF_INLINE void forEachReflectionWithin(
  const WallMirrors<Real>& m, const Vec3<Real>& p, const Vec3<Real>& q, Real h2, Add&& add)
{
  forEachReflection(m, q, [&](const Vec3<Real>& image, int, int, int) {
    const Vec3<Real> r = p - image;
    const Real r2 = dot(r, r);
    if (r2 < h2)
    {
      add(r, r2);
    }
  });
}

template <class Real>
PBF_HD PBF_INLINE bool hasReflections(const WallMirrors<Real>& m)
{
  return m.count[0] * m.count[1] * m.count[2] > 1;
}

// A direction seen in the walls that made an image (forEachReflection's ix, iy, iz): the
// components along the axes it was reflected along change sign.
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> reflected(const Vec3<Real>& v, int ix, int iy, int iz)
{
  return Vec3<Real>{ ix != 0 ? -v.x : v.x, iy != 0 ? -v.y : v.y, iz != 0 ? -v.z : v.z };
}

// Which walls a mirror image's term of delta p_i belongs to (positionCorrection's onWall): add(wall,
// part) with wall = 2 a + 0 for the low wall of axis a, + 1 for the high one. A term reflected in
// one wall is that wall's; one reflected in an edge or a corner gives each of its walls the
// component along the wall's normal and an equal share of the rest. As a force on the wall the
// parts are scaled by -m (m / rho_0) / dt^2 (the reaction, as solidLoads has it for a solid).
template <class Real, class Add>
PBF_HD PBF_INLINE void wallShares(const Vec3<Real>& term, const WallMirrors<Real>& mirrors, int ix,
  int iy, int iz, const Vec3<Real>& boxMin, Add&& add)
{
  const int slot[3] = { ix, iy, iz };
  const Real along[3] = { term.x, term.y, term.z };
  const Real lo[3] = { boxMin.x, boxMin.y, boxMin.z };
  const int walls = (ix > 0) + (iy > 0) + (iz > 0);
  // Unrolled, with the wall chosen by a select (nearWalls says why).
#if defined(__CUDACC__)
#pragma unroll
#endif
  for (int a = 0; a < 3; ++a)
  {
    if (slot[a] == 0)
    {
      continue;
    }
    Real share[3];
    for (int b = 0; b < 3; ++b)
    {
      share[b] = b == a ? along[b] : (slot[b] > 0 ? Real(0) : along[b] / Real(walls));
    }
    const Real wall = slot[a] == 1 ? mirrors.wall[a][0] : mirrors.wall[a][1];
    add(2 * a + (wall == lo[a] ? 0 : 1), Vec3<Real>{ share[0], share[1], share[2] });
  }
}

// Wall friction (Parameters::wallFriction, phi) as the walls' share of XSPH's smoothing: a wall's
// image of a particle moves as the particle reflected in the wall, its normal velocity reversed
// (the free-slip image) and its tangential velocity scaled by 1 - 2 phi (reversed at phi = 1: the
// no-slip image, whose mean with the particle is at rest on the wall). The free-slip image is
// left out of XSPH (the walls were always free-slip), so only the difference enters:
// -2 phi v_t, weighted as a neighbour is. For a mirror wall (the box's) the images are those of
// the neighbours, and an image's tangential components are the ones it was not reflected along;
// for a solid, the image of the particle itself in the solid's tangent plane, weighted by the
// solid's share of the density (Boundary.h), as the density and correction passes treat it.
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> wallFrictionImage(
  const Vec3<Real>& q, const Vec3<Real>& image, const Vec3<Real>& v, Real weight)
{
  return Vec3<Real>{ image.x == q.x ? v.x : Real(0), image.y == q.y ? v.y : Real(0),
           image.z == q.z ? v.z : Real(0) } *
    weight;
}

// How far p is from the nearest mirror wall; h where none is nearer (or the walls mirror nothing).
template <class Real>
PBF_HD PBF_INLINE Real nearestWallDistance(const Vec3<Real>& p, const Coefficients<Real>& c)
{
  if (!c.mirrorWalls)
  {
    return c.kernels.h;
  }
  Real nearest = c.kernels.h;
  nearest = p.x - c.boxMin.x < nearest ? p.x - c.boxMin.x : nearest;
  nearest = p.y - c.boxMin.y < nearest ? p.y - c.boxMin.y : nearest;
  nearest = p.z - c.boxMin.z < nearest ? p.z - c.boxMin.z : nearest;
  nearest = c.boxMax.x - p.x < nearest ? c.boxMax.x - p.x : nearest;
  nearest = c.boxMax.y - p.y < nearest ? c.boxMax.y - p.y : nearest;
  nearest = c.boxMax.z - p.z < nearest ? c.boxMax.z - p.z : nearest;
  return nearest;
}

// Adhesion at the walls (SurfaceTension.h's youngForce) for a surface particle at p with smoothed
// normal n and colour gradient gradC: the nearest wall within h sets it; zero beyond h.
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> wallYoungForce(const Vec3<Real>& p, const Vec3<Real>& n,
  const Vec3<Real>& gradC, const Coefficients<Real>& c, Real cosTheta)
{
  const Real pa[3] = { p.x, p.y, p.z };
  const Real lo[3] = { c.boxMin.x, c.boxMin.y, c.boxMin.z };
  const Real hi[3] = { c.boxMax.x, c.boxMax.y, c.boxMax.z };
  Real nearest = c.kernels.h;
  Vec3<Real> nw{ Real(0), Real(0), Real(0) };
#if defined(__CUDACC__)
#pragma unroll
#endif
  for (int a = 0; a < 3; ++a)
  {
    const Vec3<Real> unit{ a == 0 ? Real(1) : Real(0), a == 1 ? Real(1) : Real(0),
      a == 2 ? Real(1) : Real(0) };
    if (pa[a] - lo[a] < nearest)
    {
      nearest = pa[a] - lo[a];
      nw = unit;
    }
    if (hi[a] - pa[a] < nearest)
    {
      nearest = hi[a] - pa[a];
      nw = unit * Real(-1);
    }
  }
  if (!(nearest < c.kernels.h))
  {
    return Vec3<Real>{ Real(0), Real(0), Real(0) };
  }
  return youngForce(n, nw, gradC, cosTheta, nearest < Real(0) ? Real(0) : nearest, c.kernels.h);
}

} // namespace pbf
