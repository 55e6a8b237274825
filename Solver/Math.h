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
PBF_HD PBF_INLINE float power(float a, float b)
{
  return powf(a, b);
}
PBF_HD PBF_INLINE double power(double a, double b)
{
  return pow(a, b);
}

} // namespace pbf
