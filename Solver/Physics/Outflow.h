// Where particles leave the simulation (the scene's "outflows", Scene.h): boxes, each a face of
// the domain or a region of it, resolved to world coordinates by Simulation. A particle whose
// position lies in a zone at the end of a step is removed (Stepper::removeOutflow); its id is
// never given again. One test serves every backend, in the stepper's precision, so that the
// serial, OpenMP and CUDA steppers remove the same particles.
#pragma once

#include "HostDevice.h"
#include "Parameters.h"
#include "Vec3.h"

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbf
{

// More than any channel needs, few enough to pass by value to a kernel.
constexpr int kMaxOutflows = 16;

template <class Real>
struct OutflowZones
{
  int count = 0;
  Vec3<Real> min[kMaxOutflows];
  Vec3<Real> max[kMaxOutflows];

  // Closed boxes: a particle clamped onto a face that is an outflow leaves.
  PBF_HD bool contains(const Vec3<Real>& x) const
  {
    for (int k = 0; k < count; ++k)
    {
      if (x.x >= min[k].x && x.x <= max[k].x && x.y >= min[k].y && x.y <= max[k].y &&
        x.z >= min[k].z && x.z <= max[k].z)
      {
        return true;
      }
    }
    return false;
  }

  // The boxes rounded to this precision once, so that every backend compares the same numbers.
  static OutflowZones make(const std::vector<Box>& boxes)
  {
    if (boxes.size() > static_cast<std::size_t>(kMaxOutflows))
    {
      throw InvalidInput("outflows = " + std::to_string(boxes.size()) + " zones: at most " +
        std::to_string(kMaxOutflows) + " are supported");
    }
    OutflowZones z;
    z.count = static_cast<int>(boxes.size());
    for (std::size_t k = 0; k < boxes.size(); ++k)
    {
      z.min[k] = Vec3<Real>::from(boxes[k].min);
      z.max[k] = Vec3<Real>::from(boxes[k].max);
    }
    return z;
  }
};

// Particle i stays: it lies in no zone (the GPU steppers' selection of the kept particles).
template <class Real>
struct OutsideOutflows
{
  const Vec3<Real>* x;
  OutflowZones<Real> zones;
  PBF_HD bool operator()(std::uint32_t i) const { return !zones.contains(x[i]); }
};

} // namespace pbf
