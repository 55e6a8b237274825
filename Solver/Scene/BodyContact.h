// Bodies the fluid moves kept apart from each other and from the fixed solids: the contact of two
// solids from one's points against the other's distance field, resolved as RigidBody.h's
// keepInside resolves a wall (moved apart by the deepest point's depth, then impulses along the
// normal that stop the touching points approaching: no bounce, no friction).
#pragma once

#include "RigidBody.h"
#include "SignedDistance.h"

namespace pbf
{

// One solid of a contact, where it is now.
struct ContactSide
{
  RigidState* body = nullptr;          // null: a solid contacts do not move (static, prescribed)
  const MassProperties* mass = nullptr; // a body's
  const ContactHull* hull = nullptr;   // its points in its own frame as sampled
  DistanceGridView<double> field{};    // its field, placed where it is (SignedDistance.h placed)
  SolidPose pose;                      // where it is: its hull's points are pose.toWorld(point)
  Vec3d centre{ 0, 0, 0 };             // where it is (a body's centre of mass) [m]
  double reach = 0;                    // its farthest point from centre [m]
};

// What of a solid touches another: a box's faces sampled at most half a spacing apart (up to
// kMostSamplesPerEdge a side), so that a face meets a face or an edge, not only the corners; a
// sphere's centre with its radius; a mesh's vertices.
constexpr int kMostSamplesPerEdge = 17;
ContactHull surfaceHull(const SolidRegion& solid, double spacing);

// a (a body) and b kept apart: each one's hull points (balls of its hull's radius) are looked up
// in the other's field; a point inside the other moves a away from b along the field's normal by
// the deepest depth, shared by the inverse masses when b is a body too, and the touching points'
// approach is stopped. Returns whether they touched.
bool separate(ContactSide& a, ContactSide& b);

// How deep the deepest point of either is inside the other [m]; 0 where they do not touch.
double deepestContact(const ContactSide& a, const ContactSide& b);

} // namespace pbf
