// Surface tension's parts of the passes after the solve (SurfaceTension.h): the colour gradients
// averaged into the normals (smoothColour), and the confinement pass's terms: which particles feel
// the force, the divergence of their surface neighbours' normals, and the force and adhesion.
#pragma once

#include "FluidView.h"
#include "HostDevice.h"
#include "SolidTerms.h"
#include "SurfaceTension.h"
#include "Vec3.h"
#include "WallMirrors.h"

#include <cstdint>

namespace pbf
{

// grad c averaged over particle i's neighbours (Shepard's weights V_j W_ij) into f.normal[i]:
// the directions the curvature is taken from, smoothed over twice the kernel's support, so that
// a surface rough on the particles' scale does not read as curved (SurfaceTension.h).
// Solids as in vorticityAndXsph.
template <class Real, class Neighbors, bool Solids = true>
PBF_HD PBF_INLINE void smoothColour(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Vec3<Real> pi = f.p[i];
  Vec3<Real> sum{ Real(0), Real(0), Real(0) };
  Real weight = Real(0);
  // The walls' images take part with their gradients reflected, as in the colour itself: near a
  // wall the average is over the whole support, so a surface meeting the wall at a right angle
  // keeps its normal along the wall.
  const WallMirrors<Real> mirrors = nearWalls(pi, f.c);
  const bool images = hasReflections(mirrors);
  const SolidMirror<Real> solid =
    Solids && f.obstacleCount > 0 ? nearestSolid(pi, f) : noSolid<Real>();
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> pj = f.p[j];
    const Vec3<Real> r = pi - pj;
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2)
    {
      const Real volume = volumeOf(j, f);
      const Real w = volume * f.c.kernels.poly6Within(r2);
      const Vec3<Real> gj = f.colour[j];
      sum += gj * w;
      weight += w;
      if (Solids && solid.solid >= 0)
      {
        const Vec3<Real> ri = pi - solid.image(pj);
        const Real ri2 = dot(ri, ri);
        if (ri2 < f.c.kernels.h2)
        {
          const Real wi = volume * f.c.kernels.poly6Within(ri2);
          sum += solid.reflect(gj) * wi;
          weight += wi;
        }
      }
      if (images)
      {
        forEachReflection(mirrors, pj, [&](const Vec3<Real>& image, int ix, int iy, int iz) {
          const Vec3<Real> ri = pi - image;
          const Real ri2 = dot(ri, ri);
          if (ri2 < f.c.kernels.h2)
          {
            const Real wi = volume * f.c.kernels.poly6Within(ri2);
            sum += reflected(gj, ix, iy, iz) * wi;
            weight += wi;
          }
        });
      }
    }
  });
  f.normal[i] = sum * (Real(1) / weight);
}

// How much of the surface tension particle i feels in the confinement pass (surfaceWeight), and
// its colour gradient grad c_i into gradC; zero without surface tension (Tension false, or no
// colour gradients in the view).
template <bool Tension, class Real, class Neighbors>
PBF_HD PBF_INLINE Real surfaceTensionWeight(
  std::uint32_t i, const FluidView<Real, Neighbors>& f, Vec3<Real>& gradC)
{
  Real weight = Real(0);
  if (Tension && f.colour)
  {
    gradC = f.colour[i];
    weight = surfaceWeight(squareRoot(dot(gradC, gradC)) * f.c.kernels.h);
  }
  // A smoothed normal of zero length (a sheet one particle thin, whose sides' gradients cancel)
  // has no direction: no force, rather than a NaN.
  if (Tension && f.colour && !(dot(f.normal[i], f.normal[i]) > Real(0)))
  {
    weight = Real(0);
  }
  return weight;
}

// Neighbour j's share of div n_i (SurfaceDivergence) in the confinement pass, at r = p_i - p_j
// (r2 = |r|^2 < h^2) with volume V_j: when j is on the surface too (|grad c_j|^2 > gate2), its
// smoothed normal, and that normal reflected for the walls' images of j (images: any within h of
// particle i) and for the nearest solid's image (solid.solid >= 0).
template <bool Solids, class Real, class Neighbors>
PBF_HD PBF_INLINE void addSurfaceNeighbour(SurfaceDivergence<Real>& divergence, std::uint32_t j,
  const Vec3<Real>& pi, const Vec3<Real>& r, Real r2, Real volume, Real gate2,
  const WallMirrors<Real>& mirrors, bool images, const SolidMirror<Real>& solid,
  const FluidView<Real, Neighbors>& f)
{
  const Vec3<Real> gj = f.colour[j];
  if (dot(gj, gj) > gate2) // j on the surface too (the particle itself adds zeros)
  {
    const Vec3<Real> nj = f.normal[j];
    const Real nj2 = dot(nj, nj);
    if (nj2 > Real(0)) // as particle i's own (surfaceTensionWeight)
    {
      const Vec3<Real> unit = nj * (Real(1) / squareRoot(nj2));
      divergence.add(unit, r, f.c.kernels.spikyGradientWithin(r, r2), volume);
      if (images)
      {
        const Vec3<Real> pj = f.p[j];
        forEachReflection(mirrors, pj, [&](const Vec3<Real>& image, int ix, int iy, int iz) {
          const Vec3<Real> ri = pi - image;
          const Real ri2 = dot(ri, ri);
          if (ri2 < f.c.kernels.h2)
          {
            divergence.add(reflected(unit, ix, iy, iz), ri,
              f.c.kernels.spikyGradientWithin(ri, ri2), volume);
          }
        });
      }
      if (Solids && solid.solid >= 0)
      {
        const Vec3<Real> ri = pi - solid.image(f.p[j]);
        const Real ri2 = dot(ri, ri);
        if (ri2 < f.c.kernels.h2)
        {
          divergence.add(solid.reflect(unit), ri, f.c.kernels.spikyGradientWithin(ri, ri2),
            volume);
        }
      }
    }
  }
}

// Surface tension's velocity change for particle i, of weight `weight` and colour gradient gradC,
// added to v: the force from the divergence its neighbours gave, then adhesion at the nearest
// boundary within h (Solids false: at the walls only).
template <bool Solids, class Real, class Neighbors>
PBF_HD PBF_INLINE void addSurfaceTension(Vec3<Real>& v, std::uint32_t i, const Vec3<Real>& pi,
  const Vec3<Real>& gradC, Real weight, const SurfaceDivergence<Real>& divergence,
  const SolidMirror<Real>& solid, const FluidView<Real, Neighbors>& f)
{
  // f = -sigma (div n) grad c, as a velocity change dt f / rho_l.
  const int l = f.liquid ? f.liquid[i] : 0;
  v -= gradC * (divergence.divergence(f.c.kernels.h) * weight * f.time->tension[l]);
  // Adhesion at the nearest boundary within h: a solid nearer than every wall takes the line
  // with its own angle for this liquid, else a wall with the liquid's.
  if (Solids && solid.solid >= 0 && solid.distance < nearestWallDistance(pi, f.c))
  {
    const Real cosTheta = f.obstacles[solid.solid].contactCos[l];
    if (cosTheta != Real(0))
    {
      v += youngForce(f.normal[i], solid.n, gradC, cosTheta, solid.distance, f.c.kernels.h) *
        (weight * f.time->tension[l]);
    }
  }
  else if (f.c.wallAdhesion)
  {
    v += wallYoungForce(pi, f.normal[i], gradC, f.c, f.time->wallCos[l]) *
      (weight * f.time->tension[l]);
  }
}

} // namespace pbf
