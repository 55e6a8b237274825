// The kernel integrals over a solid's true shape (Scene/ShapeIntegrals.h): exact on a half-space
// against closed forms, the same on a flat face of any orientation as on the half-space, and at a
// box's edge and corner against a brute-force sum over small cubes.
#include "Kernels.h"
#include "ShapeIntegrals.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace pbf;

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr double kH = 2.0; // h = 2 s with s = 1
const double kWDeltaQ = Kernels<double>::make(kH).poly6(0.2 * kH * 0.2 * kH);
const ShapeKernels kKernels{ kH, 4.0, kWDeltaQ };

// int_{z > d, |y| < h} W_poly6: slabs of c6 pi / 4 (h^2 - z^2)^4, expanded and integrated.
double halfSpacePoly6(double d)
{
  const double h2 = kH * kH;
  const auto antiderivative = [h2](double z) {
    return h2 * h2 * h2 * h2 * z - 4 * h2 * h2 * h2 * std::pow(z, 3) / 3 +
      6 * h2 * h2 * std::pow(z, 5) / 5 - 4 * h2 * std::pow(z, 7) / 7 + std::pow(z, 9) / 9;
  };
  const double c6 = 315.0 / (64.0 * kPi * std::pow(kH, 9));
  return c6 * kPi / 4 * (antiderivative(kH) - antiderivative(std::max(d, -kH)));
}

// The normal component of int grad W_spiky over the same half-space: the derivative of the
// spiky kernel's half-space integral with the distance, the slab at z = d,
// 2 pi int_d^h W_spiky(r) r dr = 30 / h^6 (h (h - d)^4 / 4 - (h - d)^5 / 5), for d >= 0.
double halfSpaceSpikyNormal(double d)
{
  const double u = kH - d;
  return 30.0 / std::pow(kH, 6) * (kH * std::pow(u, 4) / 4 - std::pow(u, 5) / 5);
}

double boxDistance(const Vec3d& p, const Vec3d& lo, const Vec3d& hi)
{
  const Vec3d c = (lo + hi) * 0.5, e = (hi - lo) * 0.5;
  const Vec3d q{ std::abs(p.x - c.x) - e.x, std::abs(p.y - c.y) - e.y, std::abs(p.z - c.z) - e.z };
  const Vec3d out{ std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0) };
  return length(out) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
}

} // namespace

// A half-space at distance d: the poly6 integral against its closed form (1/2 at d = 0, half the
// kernel's mass) and the spiky gradient's normal component against its own. Tolerance 5e-4 of
// the value at d = 0: the polar rule (8 nodes on each side of the split) integrates functions of
// d / mu, not polynomials, steepest close to the face (measured 3.6e-4 at d = s/8, 2.1e-4 at
// s/4, below 1e-5 from s/2). The shape factor divides by the same rule's half-space, so a flat face
// stays exact whatever this error.
TEST(ShapeIntegrals, AHalfSpaceMatchesItsClosedForms)
{
  EXPECT_NEAR(halfSpacePoly6(0.0), 0.5, 1e-15);
  for (double d : { 0.0, 0.125, 0.25, 0.5, 0.75, 1.0, 1.5 })
  {
    const ShapeIntegrals flat = integrateOverHalfSpace(d, kKernels);
    std::printf("d = %.3f: poly6 %.12f (closed %.12f), spiky.z %.12f (closed %.12f)\n", d,
      flat.poly6, halfSpacePoly6(d), flat.spiky.z, halfSpaceSpikyNormal(d));
    EXPECT_NEAR(flat.poly6, halfSpacePoly6(d), 5e-4 * halfSpacePoly6(0.0)) << "d = " << d;
    EXPECT_NEAR(flat.spiky.z, halfSpaceSpikyNormal(d), 5e-4 * halfSpaceSpikyNormal(0.0))
      << "d = " << d;
    EXPECT_NEAR(flat.spiky.x, 0.0, 1e-12);
    EXPECT_NEAR(flat.spiky.y, 0.0, 1e-12);
  }
  const ShapeIntegrals beyond = integrateOverHalfSpace(kH, kKernels);
  EXPECT_EQ(beyond.poly6, 0.0);
}

// A tilted plane: the rays' march and bisection give what the half-space's exact crossings give,
// the vectors along the pole. Tolerance 1e-9 relative: the crossings are found to 1e-9 of h;
// the vectors' parts across the normal, which cancel between opposite azimuths, to 1e-9 of the
// half-space's value at the face (at d = 1.7 s the tensile vector itself is ~1e-12 of it).
TEST(ShapeIntegrals, AFlatFaceOfAnyOrientationIsTheHalfSpace)
{
  const Vec3d n = Vec3d{ 0.3, -0.5, 0.8 } * (1 / length(Vec3d{ 0.3, -0.5, 0.8 }));
  const Vec3d onPlane{ 0.2, 0.1, -0.3 };
  const auto plane = [&](const Vec3d& y) { return dot(y - onPlane, n); };
  const ShapeIntegrals face = integrateOverHalfSpace(0.0, kKernels);
  for (double d : { 0.1, 0.5, 1.0, 1.7 })
  {
    const Vec3d x = onPlane + n * d;
    const ShapeIntegrals solid = integrateOverSolid(x, n * -1.0, plane, kKernels);
    const ShapeIntegrals flat = integrateOverHalfSpace(d, kKernels);
    EXPECT_NEAR(solid.poly6, flat.poly6, 1e-9 * flat.poly6) << "d = " << d;
    EXPECT_NEAR(solid.spiky2, flat.spiky2, 1e-9 * flat.spiky2) << "d = " << d;
    EXPECT_NEAR(length(solid.spiky - n * -flat.spiky.z), 0.0, 1e-9 * std::abs(face.spiky.z));
    EXPECT_NEAR(length(solid.tensile - n * -flat.tensile.z), 0.0, 1e-9 * std::abs(face.tensile.z));
  }
}

// At a box's edge and corner the solid is a quarter or an eighth of the half-space the tangent
// plane takes: the rays against a brute-force sum over cubes of h/60 (their centres inside the
// box and the ball). Tolerance 1 % of the half-space's value at d = 0: the cubes' own error and
// the rule's around the edge (8 polar nodes); measured 0.05-0.2 % of it for poly6, up to 0.3 %
// for the gradient. The tangent plane's value printed beside them is what the table reads there today
// (3x the edge's share, 10x the corner's).
TEST(ShapeIntegrals, ABoxEdgeAndCornerAgainstABruteForceSum)
{
  const Vec3d lo{ -10, -10, -10 }, hi{ 0, 0, 0 };
  const auto box = [&](const Vec3d& y) { return boxDistance(y, lo, hi); };
  const Kernels<double> kernels = Kernels<double>::make(kH);
  struct Case
  {
    const char* name;
    Vec3d x;
  };
  for (const Case& c : { Case{ "beside an edge", { 0.5, 0.5, -3 } },
         Case{ "off a corner", { 0.5, 0.5, 0.5 } }, Case{ "over a face by an edge", { 0.5, -0.5, -3 } } })
  {
    const double phi = box(c.x);
    const Vec3d pole = Vec3d{ std::min(c.x.x, 0.0) == 0 ? -1.0 : 0.0,
      std::min(c.x.y, 0.0) == 0 ? -1.0 : 0.0, std::min(c.x.z, 0.0) == 0 ? -1.0 : 0.0 };
    const Vec3d unitPole = pole * (1 / length(pole));
    const ShapeIntegrals rays = integrateOverSolid(c.x, unitPole, box, kKernels);
    const int n = 120;
    const double cell = 2 * kH / n;
    double poly6 = 0;
    Vec3d spiky{ 0, 0, 0 };
    for (int i = 0; i < n; ++i)
    {
      for (int j = 0; j < n; ++j)
      {
        for (int k = 0; k < n; ++k)
        {
          const Vec3d y = c.x + Vec3d{ (i + 0.5) * cell - kH, (j + 0.5) * cell - kH,
            (k + 0.5) * cell - kH };
          const Vec3d r = c.x - y;
          const double r2 = dot(r, r);
          if (r2 >= kernels.h2 || box(y) >= 0)
          {
            continue;
          }
          poly6 += kernels.poly6(r2) * cell * cell * cell;
          spiky = spiky + kernels.spikyGradient(r, r2) * (cell * cell * cell);
        }
      }
    }
    const ShapeIntegrals plane = integrateOverHalfSpace(phi, kKernels);
    std::printf("%s (phi %.3f): poly6 rays %.6f, cubes %.6f, tangent plane %.6f; spiky rays "
                "(%.5f, %.5f, %.5f), cubes (%.5f, %.5f, %.5f)\n",
      c.name, phi, rays.poly6, poly6, plane.poly6, rays.spiky.x, rays.spiky.y, rays.spiky.z,
      spiky.x, spiky.y, spiky.z);
    EXPECT_NEAR(rays.poly6, poly6, 0.01 * integrateOverHalfSpace(0.0, kKernels).poly6) << c.name;
    EXPECT_NEAR(length(rays.spiky - spiky), 0.0,
      0.01 * integrateOverHalfSpace(0.0, kKernels).spiky.z)
      << c.name;
  }
}
