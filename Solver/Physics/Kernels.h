// SPH smoothing kernels of Mueller et al. 2003 as used by Macklin & Mueller 2013:
// poly6 for density (eq. 2) and the spiky gradient for constraint gradients (eq. 8).
#pragma once

#include <cmath>

#include "HostDevice.h"
#include "Math.h"
#include "Vec3.h"

namespace pbf
{

template <class Real>
struct Kernels
{
  Real h;
  Real h2;
  Real poly6Scale;      // 315 / (64 pi h^9)
  Real spikyGradScale;  // -45 / (pi h^6)

  static Kernels make(double hIn)
  {
    const double pi = 3.14159265358979323846;
    Kernels k;
    k.h = static_cast<Real>(hIn);
    k.h2 = static_cast<Real>(hIn * hIn);
    k.poly6Scale = static_cast<Real>(315.0 / (64.0 * pi * std::pow(hIn, 9)));
    k.spikyGradScale = static_cast<Real>(-45.0 / (pi * std::pow(hIn, 6)));
    return k;
  }

  // W_poly6(r, h) from the squared distance: no square root on the density path.
  PBF_HD PBF_INLINE Real poly6(Real r2) const
  {
    if (r2 >= h2)
    {
      return Real(0);
    }
    return poly6Within(r2);
  }

  // poly6 for r2 < h2, which the neighbour loops test before they call it: the same value without
  // a second test (on a GPU, a test and a select in every pair of every pass).
  PBF_HD PBF_INLINE Real poly6Within(Real r2) const
  {
    const Real d = h2 - r2;
    return poly6Scale * d * d * d;
  }

  // W_spiky(r, h) = 15 / (pi h^6) (h - r)^3: the kernel whose gradient is used below. Not on the
  // solver's path; it lets the gradient be checked against its own function.
  PBF_HD PBF_INLINE Real spiky(Real r) const
  {
    if (r >= h)
    {
      return Real(0);
    }
    const Real d = h - r;
    return -spikyGradScale / Real(3) * d * d * d;
  }

  // grad_i W_spiky(p_i - p_j, h); r = p_i - p_j. Zero at r = 0, where the direction is undefined.
  PBF_HD PBF_INLINE Vec3<Real> spikyGradient(const Vec3<Real>& r, Real r2) const
  {
    if (r2 >= h2)
    {
      return { Real(0), Real(0), Real(0) };
    }
    return spikyGradientWithin(r, r2);
  }

  // spikyGradient for r2 < h2, which the neighbour loops test before they call it.
  PBF_HD PBF_INLINE Vec3<Real> spikyGradientWithin(const Vec3<Real>& r, Real r2) const
  {
#if defined(__CUDA_ARCH__) && !defined(PBF_CUDA_IEEE_GRADIENT)
    // On the GPU: 1/r from one reciprocal square root (CUDA's rsqrtf: 2 ulp, rsqrt: 1 ulp)
    // instead of a correctly rounded square root and division, which the neighbour passes pay for
    // every pair. The CPU backends do not compile this; the GPU already rounds differently from
    // them (FMA), and this adds a few ulps to the gradient (Documentation/Performance.md).
    // No branch: r2 is raised to the smallest normal number first, so r = 0 (a particle and
    // itself) gives r times a finite number, zero, and the hardware's reciprocal square root needs
    // no subnormal handling (for any larger r2 it returns the same bits as rsqrtf).
    const Real inverse = reciprocalSquareRootOfNormal(r2);
    const Real d = h - r2 * inverse;
    return r * (spikyGradScale * d * d * inverse);
#else
    if (r2 <= Real(0))
    {
      return { Real(0), Real(0), Real(0) };
    }
    const Real rl = squareRoot(r2);
    const Real d = h - rl;
    return r * (spikyGradScale * d * d / rl);
#endif
  }
};

} // namespace pbf
