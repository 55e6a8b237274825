#include "BodyContact.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pbf
{

namespace
{

// A point of contact: where, the normal from b to a, how deep.
struct Contact
{
  Vec3d point;
  Vec3d normal;
  double depth;
};

// The points of `from` inside `into` (deeper than their ball's radius), with the normal of
// `into`'s field there, pointing out of it; `sign` -1 turns it to point into it.
void contactsOf(const ContactSide& from, const ContactSide& into, double sign,
  std::vector<Contact>& contacts)
{
  const double radius = from.hull->radius;
  const double near2 = (into.reach + radius) * (into.reach + radius);
  for (const Vec3d& local : from.hull->points)
  {
    const Vec3d p = from.pose.toWorld(local);
    const Vec3d off = p - into.centre;
    if (dot(off, off) > near2)
    {
      continue; // farther than the other solid reaches: no lookup
    }
    double d = 0;
    Vec3d gradient;
    if (!into.field.within(p, &d, &gradient))
    {
      continue;
    }
    const double g = length(gradient);
    if (d < radius && g > 0)
    {
      const Vec3d n = gradient * (sign / g);
      contacts.push_back({ p - n * (sign * radius), n, radius - d });
    }
  }
}

Vec3d velocityAt(const ContactSide& side, const Vec3d& p)
{
  if (side.body)
  {
    return side.body->velocity +
      cross(angularVelocity(*side.body, *side.mass), p - side.body->centre);
  }
  return side.pose.moving ? side.pose.velocityAt(p) : Vec3d{ 0, 0, 0 };
}

} // namespace

ContactHull surfaceHull(const SolidRegion& solid, double spacing)
{
  if (solid.kind != SolidRegion::Kind::Box)
  {
    return contactHull(solid); // a sphere's centre and radius, a mesh's vertices
  }
  const Box& b = solid.box;
  const Vec3d size = b.max - b.min;
  int n[3];
  const double sides[3] = { size.x, size.y, size.z };
  for (int a = 0; a < 3; ++a)
  {
    n[a] = std::min(kMostSamplesPerEdge,
      std::max(2, static_cast<int>(std::ceil(sides[a] / (0.5 * spacing))) + 1));
  }
  ContactHull hull;
  for (int i = 0; i < n[0]; ++i)
  {
    for (int j = 0; j < n[1]; ++j)
    {
      for (int k = 0; k < n[2]; ++k)
      {
        const bool onSurface =
          i == 0 || j == 0 || k == 0 || i == n[0] - 1 || j == n[1] - 1 || k == n[2] - 1;
        if (onSurface)
        {
          hull.points.push_back(b.min +
            Vec3d{ size.x * i / (n[0] - 1), size.y * j / (n[1] - 1), size.z * k / (n[2] - 1) });
        }
      }
    }
  }
  return hull;
}

double deepestContact(const ContactSide& a, const ContactSide& b)
{
  std::vector<Contact> contacts;
  contactsOf(a, b, 1.0, contacts);
  contactsOf(b, a, -1.0, contacts);
  double deepest = 0;
  for (const Contact& c : contacts)
  {
    deepest = std::max(deepest, c.depth);
  }
  return deepest;
}

bool separate(ContactSide& a, ContactSide& b)
{
  if (!a.body)
  {
    return false;
  }
  // Far apart: their reaches do not overlap.
  if (length(a.centre - b.centre) > a.reach + b.reach + a.hull->radius + b.hull->radius)
  {
    return false;
  }
  std::vector<Contact> contacts;
  contactsOf(a, b, 1.0, contacts);
  contactsOf(b, a, -1.0, contacts);
  if (contacts.empty())
  {
    return false;
  }
  const double ia = 1.0 / a.mass->mass;
  const double ib = b.body ? 1.0 / b.mass->mass : 0.0;
  // Apart by the deepest depth, along its normal, shared by the inverse masses.
  const Contact* deepest = &contacts[0];
  for (const Contact& c : contacts)
  {
    deepest = c.depth > deepest->depth ? &c : deepest;
  }
  const Vec3d push = deepest->normal * deepest->depth;
  a.body->centre += push * (ia / (ia + ib));
  if (b.body)
  {
    b.body->centre -= push * (ib / (ia + ib));
  }
  // Impulses along each normal that bring its point's approach to zero, in turn and a few times
  // over (projected Gauss-Seidel, as keepInside): a box resting on another rests on all its
  // corners. Each contact's impulse is accumulated and kept >= 0, so that what a later contact's
  // push makes too much at an earlier one is taken back: the contact is inelastic, the bodies do
  // not part faster than they met.
  std::vector<double> accumulated(contacts.size(), 0.0);
  for (int sweep = 0; sweep < 8; ++sweep)
  {
    for (std::size_t i = 0; i < contacts.size(); ++i)
    {
      const Contact& c = contacts[i];
      const Vec3d& n = c.normal;
      const double approach = dot(velocityAt(a, c.point) - velocityAt(b, c.point), n);
      if (approach >= 0 && accumulated[i] == 0)
      {
        continue;
      }
      const Vec3d armA = c.point - a.body->centre;
      double k = ia + ib + dot(cross(inverseInertiaTimes(*a.body, *a.mass, cross(armA, n)), armA), n);
      Vec3d armB{ 0, 0, 0 };
      if (b.body)
      {
        armB = c.point - b.body->centre;
        k += dot(cross(inverseInertiaTimes(*b.body, *b.mass, cross(armB, n)), armB), n);
      }
      const double j = std::max(accumulated[i] - approach / k, 0.0) - accumulated[i];
      accumulated[i] += j;
      a.body->velocity += n * (j * ia);
      a.body->angularMomentum += cross(armA, n) * j;
      if (b.body)
      {
        b.body->velocity -= n * (j * ib);
        b.body->angularMomentum -= cross(armB, n) * j;
      }
    }
  }
  return true;
}

} // namespace pbf
