// The rigid motion of a solid obstacle over time: keyframes of a rotation and a translation,
// interpolated between them (the translation linearly, the rotation along the shortest arc at a
// constant angular velocity), held before the first and after the last. The solid's field stays as
// it was sampled, in the solid's own frame; each step reads it through the pose at the step's end
// (Physics/Boundary.h, SolidPose), so a moving solid costs a rotation per lookup, not a new field.
// The pose is a function of time alone: same time, same pose, bit for bit, whatever was asked
// before.
#pragma once

#include "Vec3.h"

#include <array>
#include <string>
#include <vector>

namespace pbf
{

// A rotation as a unit quaternion (w, x, y, z).
struct Rotation
{
  double w = 1, x = 0, y = 0, z = 0;

  // Degrees about x, y and z, composed as ParaView's Transform composes its Rotate property:
  // about y first, then x, then z.
  static Rotation fromDegrees(const Vec3d& degrees);
  // The rotation of a 3 x 3 matrix (rows), which must be orthonormal with determinant 1.
  static Rotation fromMatrix(const std::array<double, 9>& rows);
  std::array<double, 9> matrix() const; // rows
  Vec3d apply(const Vec3d& v) const;
};

struct Keyframe
{
  double time = 0;                 // [s]
  Vec3d translation{ 0, 0, 0 };    // of the pivot [m]
  Rotation rotation;               // about the pivot
};

// Where the solid is at one time: a point x of the solid's own frame is at rotation x + translation,
// and moves at pivotVelocity + angularVelocity x (y - pivot) at its world position y.
struct SolidPose
{
  std::array<double, 9> rotation{ 1, 0, 0, 0, 1, 0, 0, 0, 1 }; // rows
  Vec3d translation{ 0, 0, 0 };
  Vec3d pivot{ 0, 0, 0 };           // the pivot's world position [m]
  Vec3d pivotVelocity{ 0, 0, 0 };   // [m/s]
  Vec3d angularVelocity{ 0, 0, 0 }; // [rad/s], world axes
  bool moving = false;              // false: the identity, at rest (the solid as sampled)

  Vec3d toWorld(const Vec3d& local) const;
  Vec3d toLocal(const Vec3d& world) const;
  Vec3d velocityAt(const Vec3d& world) const;
};

struct SolidMotion
{
  Vec3d pivot{ 0, 0, 0 };          // in the solid's own frame [m]
  std::vector<Keyframe> keyframes; // times strictly increasing; none: the solid never moves

  bool moves() const { return !keyframes.empty(); }
  SolidPose at(double time) const;
  // Throws InvalidInput naming `what` for non-finite values or times not strictly increasing.
  void validate(const std::string& what) const;
};

// Throws InvalidInput unless there is one pose per solid (or none).
void checkPoseCount(std::size_t poses, std::size_t solids);

} // namespace pbf
