#include "RigidBody.h"

#include <cmath>

namespace pbf
{

namespace
{

using Matrix = std::array<double, 9>; // rows

Vec3d times(const Matrix& a, const Vec3d& v)
{
  return { a[0] * v.x + a[1] * v.y + a[2] * v.z, a[3] * v.x + a[4] * v.y + a[5] * v.z,
    a[6] * v.x + a[7] * v.y + a[8] * v.z };
}

Vec3d transposeTimes(const Matrix& a, const Vec3d& v)
{
  return { a[0] * v.x + a[3] * v.y + a[6] * v.z, a[1] * v.x + a[4] * v.y + a[7] * v.z,
    a[2] * v.x + a[5] * v.y + a[8] * v.z };
}

// The inverse of a symmetric positive definite 3 x 3 matrix (the inertia), by its adjugate.
Matrix inverse(const Matrix& a)
{
  const Matrix adjugate = { a[4] * a[8] - a[5] * a[7], a[2] * a[7] - a[1] * a[8],
    a[1] * a[5] - a[2] * a[4], a[5] * a[6] - a[3] * a[8], a[0] * a[8] - a[2] * a[6],
    a[2] * a[3] - a[0] * a[5], a[3] * a[7] - a[4] * a[6], a[1] * a[6] - a[0] * a[7],
    a[0] * a[4] - a[1] * a[3] };
  const double det = a[0] * adjugate[0] + a[1] * adjugate[3] + a[2] * adjugate[6];
  Matrix result{};
  for (int k = 0; k < 9; ++k)
  {
    result[k] = adjugate[k] / det;
  }
  return result;
}

// q1 q2: the rotation q2, then q1.
Rotation compose(const Rotation& a, const Rotation& b)
{
  Rotation r;
  r.w = a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z;
  r.x = a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y;
  r.y = a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x;
  r.z = a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w;
  return r;
}

Rotation normalised(Rotation r)
{
  const double n = std::sqrt(r.w * r.w + r.x * r.x + r.y * r.y + r.z * r.z);
  r.w /= n;
  r.x /= n;
  r.y /= n;
  r.z /= n;
  return r;
}

// r turned by the rotation of angular velocity w over dt, renormalised.
Rotation turned(const Rotation& r, const Vec3d& w, double dt)
{
  const double speed = std::sqrt(dot(w, w));
  if (!(speed > 0))
  {
    return r;
  }
  const Vec3d axis = w * (1.0 / speed);
  const double half = 0.5 * speed * dt;
  Rotation turn;
  turn.w = std::cos(half);
  turn.x = axis.x * std::sin(half);
  turn.y = axis.y * std::sin(half);
  turn.z = axis.z * std::sin(half);
  return normalised(compose(turn, r));
}

} // namespace

RigidState restingState(const MassProperties& m)
{
  RigidState s;
  s.centre = m.centre;
  return s;
}

Vec3d angularVelocity(const RigidState& s, const MassProperties& m)
{
  // I_world^-1 L = R I^-1 R^T L.
  const Matrix r = s.orientation.matrix();
  return times(r, times(inverse(m.inertia), transposeTimes(r, s.angularMomentum)));
}

RigidState advanceRigid(const RigidState& s, const MassProperties& m, const Vec3d& force,
  const Vec3d& torque, const Vec3d& gravity, double dt)
{
  RigidState next = s;
  next.velocity = s.velocity + (force * (1.0 / m.mass) + gravity) * dt;
  next.angularMomentum = s.angularMomentum + torque * dt;
  next.centre = s.centre + next.velocity * dt;
  // The rotation over dt at the angular velocity of the half step (explicit midpoint): second
  // order, so a body tumbling for minutes keeps its energy.
  const Vec3d start = angularVelocity(next, m);
  RigidState half = next;
  half.orientation = turned(s.orientation, start, 0.5 * dt);
  next.orientation = turned(s.orientation, angularVelocity(half, m), dt);
  return next;
}

SolidPose poseOf(const RigidState& s, const MassProperties& m)
{
  SolidPose pose;
  pose.rotation = s.orientation.matrix();
  pose.translation = s.centre - times(pose.rotation, m.centre);
  pose.pivot = s.centre;
  pose.pivotVelocity = s.velocity;
  pose.angularVelocity = angularVelocity(s, m);
  pose.moving = true;
  return pose;
}

} // namespace pbf
