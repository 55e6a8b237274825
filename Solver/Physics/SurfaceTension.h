// Surface tension as Brackbill, Kothe and Zemach (1992)'s continuum surface force:
// f = -sigma (div n) grad c [N/m^3], c = sum_j V_j W_ij the fluid's smoothed colour (1 inside,
// as the lattice's mass calibrates it; 0 outside) and n = grad c / |grad c| its normal, pointing
// into the fluid. Across a surface f integrates to sigma kappa, so the pressure inside a drop of
// radius R rises by 2 sigma / R whatever the spacing; a flat surface feels nothing, so a tank at
// rest is as without it, and no pair force holds particles in place.
//
// Three neighbour walks, the first and last those the step already makes after its projections:
// - the vorticity pass sums grad c_i (poly6's gradient; the walls' mirror images count, so a
//   wall is no surface) into the particle's colour gradient;
// - smoothColour averages grad c over the neighbours (Shepard): the normals the curvature is
//   taken from are smoothed over twice the kernel's support;
// - the confinement pass takes div n_i from its surface neighbours' smoothed normals
//   (|grad c| h > kSurfaceGate; inside, n is noise), as the divergence in the tangent plane
//   renormalised on the neighbours found there (Bonet and Lok 1999's corrected gradient): with
//   t_1, t_2 the plane's axes, G_ab = sum_j V_j t_a.(n_j - n_i) t_b.grad W_ij and
//   M_ab = sum_j V_j t_a.(p_j - p_i) t_b.grad W_ij, div n = tr(G M^-1). A linear field's
//   divergence comes out exact on whatever neighbours the surface leaves, so the kernel's
//   truncation there does not bias the curvature.
// The particles carry only part of c's drop from 1 to 0 (the rest lies outside the fluid), so
// the force is divided by that share on the lattice (LatticeCalibration::surfaceColour).
//
// What was measured on the way (Documentation/ValidationInterfaces.md, "Surface tension"): the normals of
// the particles themselves read a surface rough on the particles' scale as curved, an extra
// pressure of order sigma / s that stiffened the drop's skin (its l = 2 period came out 45 % long
// at 20 spacings per radius); c's Hessian at the particle reads the lattice's ripple, about 1 / s;
// and a pairwise cohesion calibrated to sigma froze the drop (its stress grows as sigma / s).
//
// The force then acts on the velocity in the confinement pass, on the step's final positions, so
// the next step's prediction carries it, as gravity's.
//
// Adhesion is Young's force balance at the contact line. The walls' mirror images continue the
// surface beyond a wall, so where it meets the wall at an angle theta' other than 90 degrees the
// surface and its image make a corner whose curvature pulls the line with sigma cos(theta') per
// unit length towards 90 degrees. A wall's adhesion adds sigma cos(theta) along the wall, away
// from the liquid (youngForce): the line rests where the two balance, at theta' = theta. It is a
// force per unit length of the line, spread over the surface particles within h of the wall, so
// theta means the same at any spacing and step. A solid obstacle acts the same way: the nearest
// one within h is a mirror at its tangent plane (SolidTerms.h's SolidMirror), whose images join the
// walls' in the colour, the smoothed normals and the curvature, and whose angle for the
// particle's liquid (DistanceGridView::contactCos) takes the line where it is nearer than every
// wall.
#pragma once

#include "HostDevice.h"
#include "Math.h"
#include "Vec3.h"

namespace pbf
{

// A particle is on the surface where |grad c| h exceeds this (1.06 on a flat surface of the
// lattice at h = 2 s, 0 a layer below); its force is faded in linearly up to twice it.
constexpr double kSurfaceGate = 0.1;

// Young's force at a wall, per unit of the surface's force scale (the caller multiplies by
// dt sigma / (rho surfaceColour) and the surface weight): sigma cos(theta) per unit length of
// the contact line, along the wall away from the liquid, spread over the particles of the
// surface within h of the wall. A particle's share of the line is |grad c| (the surface's delta)
// times 2 (1 - d / h) / h (the wall's, a profile whose layers at d = s / 2, 3 s / 2 sum to 1 / s
// at h = 2 s), times sin(theta') = the outward normal's component along the wall, which is also
// the force's direction: a surface meeting the wall at theta' crosses the band of width h over
// a length h / sin(theta'), so the line gets sigma cos(theta) whatever theta' is, and a film
// lying on the wall (theta' = 0), whose surface runs along the band, gets none.
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> youngForce(const Vec3<Real>& n, const Vec3<Real>& nw,
  const Vec3<Real>& gradC, Real cosTheta, Real d, Real h)
{
  const Vec3<Real> along = nw * dot(n, nw) - n; // -n is outward; its part along the wall
  const Real nLength = squareRoot(dot(n, n));
  if (!(nLength > Real(0)))
  {
    return Vec3<Real>{ Real(0), Real(0), Real(0) };
  }
  const Real line = squareRoot(dot(gradC, gradC)) * (Real(2) * (Real(1) - d / h) / h);
  return along * (cosTheta * line / nLength);
}

// grad c's share of neighbour j at r = p_i - p_j, d = h^2 - r^2: poly6's gradient -6 K d^2 r
// times V_j (scale = 6 K V_j).
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> colourGradientTerm(const Vec3<Real>& r, Real d, Real scale)
{
  return r * (-scale * d * d);
}

// The surface's divergence of n around particle i, summed over the neighbours on the surface.
template <class Real>
struct SurfaceDivergence
{
  Vec3<Real> n;    // n_i
  Vec3<Real> t[2]; // the tangent plane's axes
  Real G[4] = { Real(0), Real(0), Real(0), Real(0) }; // row-major 2 x 2
  Real M[4] = { Real(0), Real(0), Real(0), Real(0) };

  // From n_i (unit): t_1 along the axis least aligned with n, t_2 = n x t_1.
  PBF_HD PBF_INLINE explicit SurfaceDivergence(const Vec3<Real>& normal) : n(normal)
  {
    const Real ax = n.x < Real(0) ? -n.x : n.x;
    const Real ay = n.y < Real(0) ? -n.y : n.y;
    const Real az = n.z < Real(0) ? -n.z : n.z;
    const Vec3<Real> e = ax <= ay && ax <= az ? Vec3<Real>{ Real(1), Real(0), Real(0) }
      : (ay <= az ? Vec3<Real>{ Real(0), Real(1), Real(0) } : Vec3<Real>{ Real(0), Real(0), Real(1) });
    const Vec3<Real> a = e - n * dot(e, n);
    t[0] = a * (Real(1) / squareRoot(dot(a, a)));
    t[1] = cross(n, t[0]);
  }

  // Neighbour j on the surface with normal nj, at r = p_i - p_j, of volume V_j and with
  // gradient grad W_ij.
  PBF_HD PBF_INLINE void add(const Vec3<Real>& nj, const Vec3<Real>& r, const Vec3<Real>& gradW,
    Real volume)
  {
    const Vec3<Real> dn = nj - n;
    const Real b[2] = { dot(t[0], gradW) * volume, dot(t[1], gradW) * volume };
    const Real x[2] = { -dot(t[0], r), -dot(t[1], r) };
    const Real e[2] = { dot(t[0], dn), dot(t[1], dn) };
    for (int a = 0; a < 2; ++a)
    {
      for (int c = 0; c < 2; ++c)
      {
        G[2 * a + c] += e[a] * b[c];
        M[2 * a + c] += x[a] * b[c];
      }
    }
  }

  // tr(G M^-1), bounded by 2 / h (the most a kernel of support h resolves: a drop of a few
  // particles would otherwise fling them); 0 where M is near singular (fewer than two
  // independent neighbours on the surface).
  PBF_HD PBF_INLINE Real divergence(Real h) const
  {
    const Real det = M[0] * M[3] - M[1] * M[2];
    const Real scale = M[0] * M[0] + M[1] * M[1] + M[2] * M[2] + M[3] * M[3];
    if (!(det * det > Real(1e-4) * scale * scale))
    {
      return Real(0);
    }
    // M^-1 = [M3 -M1; -M2 M0] / det; tr(G M^-1) = (G0 M3 - G1 M2 - G2 M1 + G3 M0) / det.
    Real div = (G[0] * M[3] - G[1] * M[2] - G[2] * M[1] + G[3] * M[0]) / det;
    const Real most = Real(2) / h;
    return div > most ? most : (div < -most ? -most : div);
  }
};

// How much of the force particle i feels, from |grad c_i| h: 0 below kSurfaceGate, 1 above twice
// it, linear between.
template <class Real>
PBF_HD PBF_INLINE Real surfaceWeight(Real gradientTimesH)
{
  const Real gate = Real(kSurfaceGate);
  if (!(gradientTimesH > gate))
  {
    return Real(0);
  }
  return gradientTimesH < Real(2) * gate ? (gradientTimesH - gate) / gate : Real(1);
}

} // namespace pbf
