#include "SolidMotion.h"

#include "Parameters.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace pbf
{

namespace
{

constexpr double kPi = 3.14159265358979323846;

Rotation multiply(const Rotation& a, const Rotation& b)
{
  return { a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
    a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
    a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w };
}

Rotation conjugate(const Rotation& q)
{
  return { q.w, -q.x, -q.y, -q.z };
}

Rotation normalized(const Rotation& q)
{
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return { q.w / n, q.x / n, q.y / n, q.z / n };
}

Rotation about(const Vec3d& axis, double radians)
{
  const double s = std::sin(0.5 * radians);
  return { std::cos(0.5 * radians), axis.x * s, axis.y * s, axis.z * s };
}

// The rotation from a to b as a unit axis and an angle in [0, pi], along the shorter arc.
void relative(const Rotation& a, Rotation b, Vec3d& axis, double& angle)
{
  if (a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z < 0)
  {
    b = { -b.w, -b.x, -b.y, -b.z }; // the same rotation, the shorter way
  }
  const Rotation r = multiply(conjugate(a), b);
  const double sine = std::sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
  angle = 2.0 * std::atan2(sine, r.w);
  axis = sine > 0 ? Vec3d{ r.x / sine, r.y / sine, r.z / sine } : Vec3d{ 1, 0, 0 };
}

std::string number(double v)
{
  std::ostringstream out;
  out << v;
  return out.str();
}

} // namespace

Rotation Rotation::fromDegrees(const Vec3d& d)
{
  const double k = kPi / 180.0;
  return normalized(multiply(multiply(about({ 0, 0, 1 }, d.z * k), about({ 1, 0, 0 }, d.x * k)),
    about({ 0, 1, 0 }, d.y * k)));
}

// Shepperd's method: from the largest of w, x, y, z, so no square root of a small number.
Rotation Rotation::fromMatrix(const std::array<double, 9>& m)
{
  const double trace = m[0] + m[4] + m[8];
  Rotation q;
  if (trace >= m[0] && trace >= m[4] && trace >= m[8])
  {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + trace));
    q = { 0.25 * s, (m[7] - m[5]) / s, (m[2] - m[6]) / s, (m[3] - m[1]) / s };
  }
  else if (m[0] >= m[4] && m[0] >= m[8])
  {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + m[0] - m[4] - m[8]));
    q = { (m[7] - m[5]) / s, 0.25 * s, (m[1] + m[3]) / s, (m[2] + m[6]) / s };
  }
  else if (m[4] >= m[8])
  {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + m[4] - m[0] - m[8]));
    q = { (m[2] - m[6]) / s, (m[1] + m[3]) / s, 0.25 * s, (m[5] + m[7]) / s };
  }
  else
  {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + m[8] - m[0] - m[4]));
    q = { (m[3] - m[1]) / s, (m[2] + m[6]) / s, (m[5] + m[7]) / s, 0.25 * s };
  }
  return normalized(q);
}

std::array<double, 9> Rotation::matrix() const
{
  return { 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
    2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
    2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y) };
}

Vec3d Rotation::apply(const Vec3d& v) const
{
  const std::array<double, 9> m = matrix();
  return { m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
    m[6] * v.x + m[7] * v.y + m[8] * v.z };
}

Vec3d SolidPose::toWorld(const Vec3d& l) const
{
  const auto& m = rotation;
  return Vec3d{ m[0] * l.x + m[1] * l.y + m[2] * l.z, m[3] * l.x + m[4] * l.y + m[5] * l.z,
           m[6] * l.x + m[7] * l.y + m[8] * l.z } +
    translation;
}

Vec3d SolidPose::toLocal(const Vec3d& world) const
{
  const auto& m = rotation;
  const Vec3d d = world - translation;
  return { m[0] * d.x + m[3] * d.y + m[6] * d.z, m[1] * d.x + m[4] * d.y + m[7] * d.z,
    m[2] * d.x + m[5] * d.y + m[8] * d.z };
}

Vec3d SolidPose::velocityAt(const Vec3d& world) const
{
  return pivotVelocity + cross(angularVelocity, world - pivot);
}

SolidPose SolidMotion::at(double time) const
{
  SolidPose pose;
  if (keyframes.empty())
  {
    return pose;
  }
  pose.moving = true;
  // The segment [k, k + 1] holding `time`; before the first and after the last keyframe the solid
  // holds that keyframe's pose, at rest.
  const auto after = std::upper_bound(keyframes.begin(), keyframes.end(), time,
    [](double t, const Keyframe& k) { return t < k.time; });
  Rotation rotation;
  Vec3d offset;
  if (after == keyframes.begin() || after == keyframes.end())
  {
    const Keyframe& held = after == keyframes.begin() ? keyframes.front() : keyframes.back();
    rotation = held.rotation;
    offset = held.translation;
  }
  else
  {
    const Keyframe& a = *(after - 1);
    const Keyframe& b = *after;
    const double span = b.time - a.time;
    const double s = (time - a.time) / span;
    Vec3d axis;
    double angle = 0;
    relative(a.rotation, b.rotation, axis, angle);
    rotation = normalized(multiply(a.rotation, about(axis, s * angle)));
    offset = a.translation + (b.translation - a.translation) * s;
    pose.pivotVelocity = (b.translation - a.translation) * (1.0 / span);
    pose.angularVelocity = a.rotation.apply(axis) * (angle / span);
  }
  pose.rotation = rotation.matrix();
  pose.pivot = pivot + offset;
  // x -> R (x - pivot) + pivot + offset.
  pose.translation = pose.pivot - rotation.apply(pivot);
  return pose;
}

void SolidMotion::validate(const std::string& what) const
{
  auto finite = [](const Vec3d& v) { return std::isfinite(v.x + v.y + v.z); };
  if (!finite(pivot))
  {
    throw InvalidInput(what + ".pivot: must be finite");
  }
  for (std::size_t k = 0; k < keyframes.size(); ++k)
  {
    const Keyframe& f = keyframes[k];
    const std::string at = what + ".keyframes[" + std::to_string(k) + "]";
    const Rotation& q = f.rotation;
    if (!std::isfinite(f.time))
    {
      throw InvalidInput(at + ".time = " + number(f.time) + ": must be finite");
    }
    if (k > 0 && !(f.time > keyframes[k - 1].time))
    {
      throw InvalidInput(at + ".time = " + number(f.time) +
        ": keyframe times must increase (the one before is " + number(keyframes[k - 1].time) +
        ")");
    }
    if (!finite(f.translation))
    {
      throw InvalidInput(at + ".translation: must be finite");
    }
    if (!std::isfinite(q.w + q.x + q.y + q.z) ||
      std::abs(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z - 1.0) > 1e-6)
    {
      throw InvalidInput(at + ".rotation: must be a finite rotation");
    }
  }
}

void checkPoseCount(std::size_t poses, std::size_t solids)
{
  if (poses != 0 && poses != solids)
  {
    throw InvalidInput("obstacle poses = " + std::to_string(poses) + ": there are " +
      std::to_string(solids) + " solid(s), one pose each");
  }
}

} // namespace pbf
