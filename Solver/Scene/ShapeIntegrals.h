// The boundary table's four kernel sums taken over a solid's true shape instead of its tangent
// plane: the integrals over the solid, within h of a point x, of
//   poly6 W(x - y),  the spiky gradient grad W(x - y),  |grad W|^2,  and s_corr's
//   grad W(x - y) * -(W(x - y) / W(dq))^n,
// from the solid's signed distance field alone. Their ratio to the same integrals over a
// half-space at x's distance is the solid's shape factor: 1 (and the normal) on a flat face,
// where the tangent-plane table (Physics/Boundary.h) is already exact, and what the table misses
// near edges and corners (Bender et al. 2019 integrate a solid's volume the same way for their
// volume maps).
//
// The integrals are taken along rays from x: Gauss-Legendre in mu = cos(theta) about a pole
// (into the solid, -grad phi), split at mu = phi(x) / h where a half-space at distance phi(x)
// starts to cross the ball, times evenly spaced azimuths; along each ray the solid's intervals
// are found by marching phi (striding its distance) and locating its sign changes by regula
// falsi, and each interval's radial integral
// is Gauss-Legendre of the kernels, polynomials in r of degree at most 28 (exact for them).
#pragma once

#include "Vec3.h"

#include <functional>

namespace pbf
{

struct ShapeIntegrals
{
  double poly6 = 0;           // int W
  Vec3d spiky{ 0, 0, 0 };     // int grad W (grad with respect to x)
  double spiky2 = 0;          // int |grad W|^2
  Vec3d tensile{ 0, 0, 0 };   // int grad W * -(W / W(dq))^n
};

struct ShapeRule
{
  int polar = 8;             // Gauss-Legendre nodes in mu on each side of the split
  int marchSteps = 64;        // the march's shortest stride is h / marchSteps
};

// The kernels' constants: smoothing length h, s_corr's exponent n and W(dq).
struct ShapeKernels
{
  double h;
  double sCorrN;
  double wDeltaQ;
};

// The four integrals over {y : phi(y) < 0, |x - y| < h}. pole: a unit vector into the solid
// (-grad phi at x); phi: the solid's signed distance (negative inside).
ShapeIntegrals integrateOverSolid(const Vec3d& x, const Vec3d& pole,
  const std::function<double(const Vec3d&)>& phi, const ShapeKernels& k,
  const ShapeRule& rule = {});

// The same integrals over a half-space at distance d from x (negative: x inside it), the normal
// component of the vectors along the pole: what a flat face gives, by the same rule.
ShapeIntegrals integrateOverHalfSpace(double d, const ShapeKernels& k, const ShapeRule& rule = {});

} // namespace pbf
