// The passes after the solve that set the velocity: eq. 15's vorticity and the sum of XSPH's
// eq. 17 in one neighbour walk (vorticityAndXsph), then the confinement pass, which applies XSPH,
// its bi-Laplacian, the vorticity confinement of eq. 16 and surface tension (TensionPasses.h).
#pragma once

#include "FluidView.h"
#include "HostDevice.h"
#include "SolidTerms.h"
#include "SurfaceTension.h"
#include "TensionPasses.h"
#include "Vec3.h"
#include "WallMirrors.h"

#include <cstdint>

namespace pbf
{

// Eq. 15 (vorticity omega_i) and eq. 17's sum S_i = sum_j V_j (v_j - v_i) W_ij (XSPH) from the
// same neighbour pass, into f.omega and f.smoothing; the confinement pass applies XSPH, because
// its bi-Laplacian needs every neighbour's S_j first. Both sums carry the SPH volume
// V_j = m / rho_j, so omega is a true curl in 1/s and c is a dimensionless blend.
// With wall friction the walls' images join the smoothing (wallFrictionImage), in the same pass:
// one neighbour walk, so the GPU stages its neighbour rows once. Friction = false compiles them
// out: the GPU launches that pass when the friction is 0, as the images' code made the kernel
// slower even where they were not visited (3 % a step in double at 1M particles on the H200).
// Solids = false compiles the solids' images of the colour out (the GPU launches that pass when
// the scene has no solid: their registers cost the colour's pass 3 % a step).
template <class Real, class Neighbors, bool Friction = true, bool Colour = true, bool Solids = true>
PBF_HD PBF_INLINE void vorticityAndXsph(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Vec3<Real> pi = f.p[i];
  const Vec3<Real> vi = f.v[i];
  Vec3<Real> omega{ Real(0), Real(0), Real(0) };
  Vec3<Real> smoothing{ Real(0), Real(0), Real(0) };
  Vec3<Real> gradC{ Real(0), Real(0), Real(0) };
  const Real friction = Friction ? Real(-2) * f.c.wallFriction : Real(0);
  WallMirrors<Real> mirrors{ { 1, 1, 1 }, { { Real(0), Real(0) }, { Real(0), Real(0) }, { Real(0), Real(0) } } };
  const bool colour = Colour && f.colour;
  if ((Friction && friction != Real(0)) || colour)
  {
    mirrors = nearWalls(pi, f.c);
  }
  const bool images = hasReflections(mirrors);
  // The nearest solid's images continue the colour as the walls' do (SolidMirror).
  SolidMirror<Real> solid = noSolid<Real>();
  if (Solids && colour && f.obstacleCount > 0)
  {
    solid = nearestSolid(pi, f);
  }
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> pj = f.p[j];
    const Vec3<Real> r = pi - pj;
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2) // the particle itself adds zeros: no test
    {
      const Real volume = volumeOf(j, f);
      const Vec3<Real> vij = f.v[j] - vi;
      omega += cross(f.c.kernels.spikyGradientWithin(r, r2), vij) * volume;
      smoothing += vij * (volume * f.c.kernels.poly6Within(r2));
      if (colour)
      {
        gradC += colourGradientTerm(r, f.c.kernels.h2 - r2, f.c.colourScale * volume);
      }
    }
    if (colour && images && r2 < f.c.kernels.h2)
    {
      // The walls' images continue the colour as they continue the density: a wall is no
      // surface, and the surface meets it at a right angle (no adhesion).
      const Real scale = f.c.colourScale * volumeOf(j, f);
      forEachReflectionWithin(mirrors, pi, pj, f.c.kernels.h2, [&](const Vec3<Real>& ri, Real ri2) {
        gradC += colourGradientTerm(ri, f.c.kernels.h2 - ri2, scale);
      });
    }
    if (Solids && colour && solid.solid >= 0 && r2 < f.c.kernels.h2)
    {
      const Vec3<Real> ri = pi - solid.image(pj);
      const Real ri2 = dot(ri, ri);
      if (ri2 < f.c.kernels.h2)
      {
        gradC += colourGradientTerm(ri, f.c.kernels.h2 - ri2, f.c.colourScale * volumeOf(j, f));
      }
    }
    if (Friction && friction != Real(0) && images && r2 < f.c.kernels.h2)
    {
      // An image is never closer than its neighbour (both on the fluid's side of the wall).
      const Vec3<Real> vj = f.v[j];
      const Real volume = volumeOf(j, f);
      forEachReflection(mirrors, pj, [&](const Vec3<Real>& image, int, int, int) {
        const Vec3<Real> ri = pi - image;
        const Real ri2 = dot(ri, ri);
        if (ri2 < f.c.kernels.h2)
        {
          smoothing += wallFrictionImage(
            pj, image, vj, friction * volume * f.c.kernels.poly6Within(ri2));
        }
      });
    }
  });
  if (Friction && friction != Real(0))
  {
    forEachNearSolid(pi, f,
      [&](const Vec3<Real>& n, const SolidSample<Real>& s, const DistanceGridView<Real>& solid) {
      // The velocity relative to the solid's surface (a moving obstacle drags the fluid along).
      const Vec3<Real> slip = vi - solid.velocityAt(pi);
      smoothing += (slip - n * dot(slip, n)) * (friction * f.c.massOverRho0 * s.poly6);
    });
  }
  f.omega[i] = omega;
  if (f.omegaLength)
  {
    f.omegaLength[i] = length(omega);
  }
  f.smoothing[i] = smoothing;
  if (colour)
  {
    f.colour[i] = gradC;
  }
}

// Neighbour j's term of eta = grad |omega|_i (eq. 16; an SPH difference gradient, zero in uniform
// rotation), at r = p_i - p_j with volume V_j; magI is |omega_i|.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE Vec3<Real> vorticityGradientTerm(std::uint32_t j, const Vec3<Real>& r, Real r2,
  Real volume, Real magI, const FluidView<Real, Neighbors>& f)
{
  return f.c.kernels.spikyGradientWithin(r, r2) * (volume * (omegaLengthOf(j, f) - magI));
}

// XSPH (eq. 17) and its bi-Laplacian: v + c S_i - c_4 S(S)_i, with hyper = S(S)_i (read only when
// smoothTwice).
template <class Real, class Neighbors>
PBF_HD PBF_INLINE Vec3<Real> xsphVelocity(std::uint32_t i, const FluidView<Real, Neighbors>& f,
  const Vec3<Real>& si, const Vec3<Real>& hyper, bool smoothTwice)
{
  Vec3<Real> v = f.v[i] + si * (f.liquid ? f.time->liquidXsph[f.liquid[i]] : f.time->xsph);
  if (smoothTwice)
  {
    v -= hyper * f.time->xsphHyper;
  }
  return v;
}

// Eq. 16's force added to v as a velocity change: N = eta / |eta|, f_vorticity =
// epsilon (N x omega_i), times dt; none where N is noise (|eta| h negligible against |omega_i|).
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void addVorticityForce(Vec3<Real>& v, const Vec3<Real>& eta,
  const Vec3<Real>& omegaI, Real magI, const FluidView<Real, Neighbors>& f)
{
  const Real etaLength = length(eta);
  if (etaLength * f.c.kernels.h > Real(1e-4) * magI && etaLength > Real(0))
  {
    const Vec3<Real> N = eta * (Real(1) / etaLength);
    v += cross(N, omegaI) * (f.c.vorticityEpsilon * f.time->dt);
  }
}

// The step's new velocity into velocityOut[i]: XSPH, v_i + c S_i (eq. 17), minus c_4 times S
// smoothed once more, S(S)_i = sum_j V_j (S_j - S_i) W_ij (Parameters::xsphHyperViscosity; a
// pattern of gain g under S is damped by c g + c_4 g^2, so long waves, g ~ (k h)^2, hardly feel
// c_4), plus eq. 16: f_i = epsilon (N x omega_i), N = eta / |eta|, eta = grad |omega|_i (SPH
// difference gradient, zero in uniform rotation), as an acceleration. Where |eta| h is negligible
// against |omega| the direction N is noise, and the force is dropped. velocityOut may be f.v or
// f.omega: each particle reads only its own of those. SmoothTwice = false compiles the
// bi-Laplacian out: the GPU launches that pass when alpha_4 is 0 (its registers made the double
// precision pass spill). Then surface tension (SurfaceTension.h): dt times its acceleration,
// -sigma (div n) grad c_i / rho, with div n from the surface neighbours' smoothed normals in the
// same walk; Tension = false compiles it out, as SmoothTwice does, and Solids = false the solids'
// images and adhesion (vorticityAndXsph says why).
template <class Real, class Neighbors, bool SmoothTwice = true, bool Tension = true,
  bool Solids = true>
PBF_HD PBF_INLINE void vorticityConfinement(
  std::uint32_t i, const FluidView<Real, Neighbors>& f, Vec3<Real>* velocityOut)
{
  const Vec3<Real> pi = f.p[i];
  const Vec3<Real> omegaI = f.omega[i];
  const Real magI = omegaLengthOf(i, f);
  const Vec3<Real> si = f.smoothing[i];
  const bool smoothTwice = SmoothTwice && f.time->xsphHyper != Real(0);
  // Surface tension where particle i is on the surface (SurfaceTension.h).
  Vec3<Real> gradC{ Real(0), Real(0), Real(0) };
  const Real weight = surfaceTensionWeight<Tension>(i, f, gradC);
  const bool tension = weight > Real(0);
  const Vec3<Real> smooth = tension ? f.normal[i] : Vec3<Real>{ Real(0), Real(0), Real(1) };
  SurfaceDivergence<Real> divergence(smooth * (Real(1) / squareRoot(dot(smooth, smooth))));
  const Real gate2 = Real(kSurfaceGate * kSurfaceGate) * f.c.inverseH2;
  // The walls' images of the surface neighbours take part with their normals reflected
  // (smoothColour says why).
  WallMirrors<Real> mirrors{ { 1, 1, 1 }, { { Real(0), Real(0) }, { Real(0), Real(0) }, { Real(0), Real(0) } } };
  SolidMirror<Real> solid = noSolid<Real>();
  if (tension)
  {
    mirrors = nearWalls(pi, f.c);
    if (Solids && f.obstacleCount > 0)
    {
      solid = nearestSolid(pi, f);
    }
  }
  const bool images = hasReflections(mirrors);
  Vec3<Real> eta{ Real(0), Real(0), Real(0) };
  Vec3<Real> hyper{ Real(0), Real(0), Real(0) };
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> r = pi - f.p[j];
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2) // the particle itself adds zeros: no test
    {
      const Real volume = volumeOf(j, f);
      eta += vorticityGradientTerm(j, r, r2, volume, magI, f);
      if (smoothTwice)
      {
        hyper += (f.smoothing[j] - si) * (volume * f.c.kernels.poly6Within(r2));
      }
      if (tension)
      {
        addSurfaceNeighbour<Solids>(
          divergence, j, pi, r, r2, volume, gate2, mirrors, images, solid, f);
      }
    }
  });
  Vec3<Real> v = xsphVelocity(i, f, si, hyper, smoothTwice);
  if (tension)
  {
    addSurfaceTension<Solids>(v, i, pi, gradC, weight, divergence, solid, f);
  }
  addVorticityForce(v, eta, omegaI, magI, f);
  velocityOut[i] = v;
}

} // namespace pbf
