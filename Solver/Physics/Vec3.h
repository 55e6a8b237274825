// A small 3-vector usable on host and device. Plain aggregate so arrays of it can be copied with
// memcpy/cudaMemcpy and stay layout-compatible with VTK's interleaved point arrays.
#pragma once

#include "HostDevice.h"
#include "Math.h"

namespace pbf
{

template <class Real>
struct Vec3
{
  Real x, y, z;

  template <class Other>
  PBF_HD static Vec3 from(const Vec3<Other>& o)
  {
    return { static_cast<Real>(o.x), static_cast<Real>(o.y), static_cast<Real>(o.z) };
  }

  PBF_HD Vec3& operator+=(const Vec3& o)
  {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  PBF_HD Vec3& operator-=(const Vec3& o)
  {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  PBF_HD Vec3& operator*=(Real s)
  {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
};

template <class Real>
PBF_HD PBF_INLINE Vec3<Real> operator+(Vec3<Real> a, const Vec3<Real>& b)
{
  return a += b;
}
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> operator-(Vec3<Real> a, const Vec3<Real>& b)
{
  return a -= b;
}
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> operator*(Vec3<Real> a, Real s)
{
  return a *= s;
}
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> operator*(Real s, Vec3<Real> a)
{
  return a *= s;
}
template <class Real>
PBF_HD PBF_INLINE Real dot(const Vec3<Real>& a, const Vec3<Real>& b)
{
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> cross(const Vec3<Real>& a, const Vec3<Real>& b)
{
  return { a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x };
}
template <class Real>
PBF_HD PBF_INLINE Real length(const Vec3<Real>& a)
{
  return squareRoot(dot(a, a));
}

using Vec3d = Vec3<double>;

} // namespace pbf
