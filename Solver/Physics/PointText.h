// A point as the solver's messages write it, "(x, y, z)", and whether all of it is finite: the
// two things every check of input geometry (particles, solids, meshes) says and asks.
#pragma once

#include "Vec3.h"

#include <cmath>
#include <sstream>
#include <string>

namespace pbf
{

inline std::string pointText(const Vec3d& v)
{
  std::ostringstream out;
  out << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return out.str();
}

inline bool isFinite(const Vec3d& v)
{
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

} // namespace pbf
