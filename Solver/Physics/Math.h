// Precision-exact math for host and device. Unqualified sqrt/pow on a float can resolve to the
// double C functions on the host but to the float ones in CUDA; these overloads pin the precision
// so every backend evaluates the same function.
#pragma once

#include "HostDevice.h"

#include <math.h>

namespace pbf
{

PBF_HD PBF_INLINE float squareRoot(float a)
{
  return sqrtf(a);
}
PBF_HD PBF_INLINE double squareRoot(double a)
{
  return sqrt(a);
}
#if defined(__CUDA_ARCH__)
// Device only (the spiky gradient's fast path in Kernels.h): the hardware's reciprocal square root
// of max(a, smallest normal) (CUDA's rsqrtf: 2 ulp, rsqrt: 1 ulp). For a normal a the bits of
// rsqrtf(a) / rsqrt(a); for a subnormal a or 0 a finite 2^63 (float) or 2^511 (double), with no
// branch to scale subnormals (rsqrtf's own scaling costs 4 instructions in every pair).
__device__ __forceinline__ float reciprocalSquareRootOfNormal(float a)
{
  float r;
  asm("rsqrt.approx.ftz.f32 %0, %1;" : "=f"(r) : "f"(fmaxf(a, 1.17549435e-38f)));
  return r;
}
__device__ __forceinline__ double reciprocalSquareRootOfNormal(double a)
{
  return rsqrt(fmax(a, 2.2250738585072014e-308));
}
#endif
// s_corr (eq. 13) raises to n = 4 for every neighbour pair in every solver iteration. On a GPU the
// general pow costs ~60 instructions there, most of the pass; a small integer exponent by
// repeated squaring is as accurate (a few ulps, the bound CUDA's own powf has) and deterministic.
// The host takes the same path, so CPU and GPU evaluate the same products (and the CPU saves the
// pow call too); other exponents fall back to the library pow on both.
template <class Real>
PBF_HD PBF_INLINE bool isSmallIntegerExponent(Real b)
{
  return b >= Real(1) && b <= Real(8) && b == static_cast<Real>(static_cast<int>(b));
}
template <class Real>
PBF_HD PBF_INLINE Real integerPower(Real a, int n)
{
  if (n == 4)
  {
    // The default exponent, unrolled: the same two squarings the loop makes (its final product
    // with 1 is exact), without the loop's bookkeeping in every neighbour pair on a GPU.
    const Real a2 = a * a;
    return a2 * a2;
  }
  Real result = Real(1);
  for (; n > 0; n >>= 1)
  {
    if (n & 1)
    {
      result *= a;
    }
    a *= a;
  }
  return result;
}
PBF_HD PBF_INLINE float power(float a, float b)
{
  if (isSmallIntegerExponent(b))
  {
    return integerPower(a, static_cast<int>(b));
  }
  return powf(a, b);
}
PBF_HD PBF_INLINE double power(double a, double b)
{
  if (isSmallIntegerExponent(b))
  {
    return integerPower(a, static_cast<int>(b));
  }
  return pow(a, b);
}

} // namespace pbf
