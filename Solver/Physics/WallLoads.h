// What one particle's position correction pushes the mirror walls with: its mirror images' terms
// (positionCorrection's onWall) shared out per wall (wallShares), then as a force on each wall at
// the particle's foot there. The CPU adds these per block of particles (HostStepLoop.h), the GPU
// per warp inside the correction pass (StepPasses.h): one definition of what a wall takes.
#pragma once

#include "FluidView.h"
#include "HostDevice.h"
#include "Vec3.h"
#include "WallMirrors.h"

namespace pbf
{

// The box's six walls: 2 a + 0 the low wall of axis a, 2 a + 1 the high one.
constexpr int kMirrorWalls = 6;
// A force and its torque about the world's origin.
constexpr int kWallLoadValues = 6;
// The walls' loads, wall after wall.
constexpr int kWallLoadDoubles = kMirrorWalls * kWallLoadValues;

// pressed is indexed at run time, so on a GPU it lives in local memory rather than in the
// correction's registers (18 more would cost the pass a quarter of its blocks); a wall's entry is
// written only once the particle takes a term of it (touched), so the particles far from the
// walls never touch it and nothing is zeroed (a value-initialised copy would store 18 zeros a
// particle: the default constructor leaves it unwritten).
template <class Real>
struct WallPush
{
  Vec3<Real> pressed[kMirrorWalls]; // pressed[w] is valid where touched has bit w
  unsigned touched;

  PBF_HD PBF_INLINE WallPush()
    : touched(0u)
  {
  }

  PBF_HD PBF_INLINE bool any() const { return touched != 0u; }

  PBF_HD PBF_INLINE void add(int w, const Vec3<Real>& part)
  {
    const unsigned bit = 1u << w;
    if (touched & bit)
    {
      pressed[w] += part;
    }
    else
    {
      pressed[w] = part;
      touched |= bit;
    }
  }

  // Wall w's force, -m (m / rho_0) / dt^2 times what it took from particle p (as solidLoads has a
  // solid's), and that force's torque about the origin at p's foot on the wall; w is touched.
  PBF_HD PBF_INLINE void load(int w, const Vec3<Real>& p, Real scale, const Vec3<Real>& boxMin,
    const Vec3<Real>& boxMax, Vec3<Real>& force, Vec3<Real>& torque) const
  {
    Vec3<Real> foot = p;
    const Vec3<Real>& side = w % 2 == 0 ? boxMin : boxMax;
    const int axis = w / 2;
    (axis == 0 ? foot.x : axis == 1 ? foot.y : foot.z) =
      axis == 0 ? side.x : axis == 1 ? side.y : side.z;
    force = pressed[w] * scale;
    torque = cross(foot, force);
  }
};

// positionCorrection's onWall: each mirror image's term shared out to its walls (wallShares).
// The box's low corner is kept by value: on a GPU a reference into the pass's captured view
// could copy it out of the kernel's parameters.
template <class Real>
struct WallTerms
{
  WallPush<Real>& push;
  Vec3<Real> boxMin;

  PBF_HD PBF_INLINE void operator()(const Vec3<Real>& term, const WallMirrors<Real>& mirrors,
    const Vec3<Real>&, const Vec3<Real>&, int ix, int iy, int iz)
  {
    wallShares(term, mirrors, ix, iy, iz, boxMin,
      [&](int w, const Vec3<Real>& part) { push.add(w, part); });
  }
};

// The scale of WallPush::load for a view: the reaction's -m (m / rho_0) / dt^2.
template <class Real, class View>
PBF_HD PBF_INLINE Real wallLoadScale(const View& f)
{
  return -f.c.massOverRho0 * f.c.mass * f.time->inverseDt * f.time->inverseDt;
}

// A particle's share of the walls' loads as the GPU's sums read it (StepSchedule.h's
// forEachMaxSum): kGroups groups (the walls) of kGroupValues doubles (force, torque); groups()
// says which it has. The rest is set only where push.any().
template <class Real>
struct WallLoadPart
{
  static constexpr int kGroups = kMirrorWalls;
  static constexpr int kGroupValues = kWallLoadValues;
  WallPush<Real> push;
  Vec3<Real> p, boxMin, boxMax;
  Real scale;

  PBF_HD PBF_INLINE unsigned groups() const { return push.touched; }

  // Wall w's force and torque into out[0..5]; zeros where the particle did not touch it.
  PBF_HD PBF_INLINE void group(int w, double* out) const
  {
    if (!(push.touched & (1u << w)))
    {
      for (int k = 0; k < kGroupValues; ++k)
      {
        out[k] = 0.0;
      }
      return;
    }
    Vec3<Real> force, torque;
    push.load(w, p, scale, boxMin, boxMax, force, torque);
    out[0] = static_cast<double>(force.x);
    out[1] = static_cast<double>(force.y);
    out[2] = static_cast<double>(force.z);
    out[3] = static_cast<double>(torque.x);
    out[4] = static_cast<double>(torque.y);
    out[5] = static_cast<double>(torque.z);
  }
};

} // namespace pbf
