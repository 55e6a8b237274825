#include "RigidBody.h"

#include <algorithm>
#include <cmath>
#include <vector>

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
  return inverseInertiaTimes(s, m, s.angularMomentum);
}

Vec3d inverseInertiaTimes(const RigidState& s, const MassProperties& m, const Vec3d& v)
{
  // I_world^-1 v = R I^-1 R^T v.
  const Matrix r = s.orientation.matrix();
  return times(r, times(inverse(m.inertia), transposeTimes(r, v)));
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

ContactHull contactHull(const SolidRegion& solid)
{
  ContactHull hull;
  switch (solid.kind)
  {
    case SolidRegion::Kind::Box:
      for (int k = 0; k < 8; ++k)
      {
        hull.points.push_back({ k & 1 ? solid.box.max.x : solid.box.min.x,
          k & 2 ? solid.box.max.y : solid.box.min.y, k & 4 ? solid.box.max.z : solid.box.min.z });
      }
      break;
    case SolidRegion::Kind::Sphere:
      hull.points.push_back(solid.center);
      hull.radius = solid.radius;
      break;
    case SolidRegion::Kind::Mesh:
      hull.points = solid.mesh.points;
      break;
  }
  return hull;
}

RigidState keepInside(
  const RigidState& s, const MassProperties& m, const ContactHull& hull, const Box& domain)
{
  RigidState next = s;
  const double low[3] = { domain.min.x, domain.min.y, domain.min.z };
  const double high[3] = { domain.max.x, domain.max.y, domain.max.z };
  // Points within a thousandth of the body's size of the wall touch it, so that a face lying on
  // it, tilted by a rounding or a rocking, touches at every corner and the body comes to rest.
  Box extent{ hull.points.empty() ? Vec3d{ 0, 0, 0 } : hull.points[0],
    hull.points.empty() ? Vec3d{ 0, 0, 0 } : hull.points[0] };
  for (const Vec3d& p : hull.points)
  {
    extent.min = { std::min(extent.min.x, p.x), std::min(extent.min.y, p.y), std::min(extent.min.z, p.z) };
    extent.max = { std::max(extent.max.x, p.x), std::max(extent.max.y, p.y), std::max(extent.max.z, p.z) };
  }
  const double touching = 1e-3 * (length(extent.max - extent.min) + 2 * hull.radius);
  auto axis = [](const Vec3d& v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); };
  std::vector<Vec3d> world(hull.points.size());
  std::vector<Vec3d> contacts;
  for (int a = 0; a < 3; ++a)
  {
    for (int side = 0; side < 2; ++side)
    {
      // n points into the domain; a point's depth is how far it is through the wall.
      const double sign = side == 0 ? 1.0 : -1.0;
      const Vec3d n{ a == 0 ? sign : 0.0, a == 1 ? sign : 0.0, a == 2 ? sign : 0.0 };
      const Matrix r = next.orientation.matrix();
      double deepest = 0;
      for (std::size_t k = 0; k < hull.points.size(); ++k)
      {
        world[k] = next.centre + times(r, hull.points[k] - m.centre) - n * hull.radius;
        const double depth = side == 0 ? low[a] - axis(world[k], a) : axis(world[k], a) - high[a];
        deepest = std::max(deepest, depth);
      }
      if (!(deepest > 0))
      {
        continue;
      }
      next.centre += n * deepest;
      contacts.clear();
      for (const Vec3d& p : world)
      {
        const double depth = side == 0 ? low[a] - axis(p, a) : axis(p, a) - high[a];
        if (depth > deepest - touching)
        {
          contacts.push_back(p + n * deepest);
        }
      }
      // Impulses along n that bring every touching point's approach to zero, in turn and a few
      // times over (projected Gauss-Seidel: a box lying flat rests on all four corners), each
      // point's accumulated and kept >= 0 so that the excess a later point's push leaves at an
      // earlier one is taken back: the body stops at the wall instead of bouncing off it.
      std::vector<double> accumulated(contacts.size(), 0.0);
      for (int sweep = 0; sweep < 8; ++sweep)
      {
        for (std::size_t i = 0; i < contacts.size(); ++i)
        {
          const Vec3d arm = contacts[i] - next.centre;
          const double approach = dot(next.velocity + cross(angularVelocity(next, m), arm), n);
          if (approach >= 0 && accumulated[i] == 0)
          {
            continue;
          }
          const Matrix rot = next.orientation.matrix();
          const Vec3d armCrossN = cross(arm, n);
          const Vec3d turn = times(rot, times(inverse(m.inertia), transposeTimes(rot, armCrossN)));
          const double j =
            std::max(accumulated[i] - approach / (1.0 / m.mass + dot(cross(turn, arm), n)), 0.0) -
            accumulated[i];
          accumulated[i] += j;
          next.velocity += n * (j / m.mass);
          next.angularMomentum += armCrossN * j;
        }
      }
    }
  }
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
