// The motion of a body the fluid moves: its state, one step of it under a force, a torque and
// gravity, and the pose through which the fluid's stages read its distance field (SolidPose).
// The body's own frame is the scene's at the start (its field is sampled there); its inertia
// (MassProperties) is about its centre of mass along those axes.
#pragma once

#include "MassProperties.h"
#include "SolidMotion.h"

#include <vector>

namespace pbf
{

struct RigidState
{
  Vec3d centre{ 0, 0, 0 };          // of mass, world [m]
  Rotation orientation;             // from the body's own frame to the world's
  Vec3d velocity{ 0, 0, 0 };        // of the centre [m/s]
  Vec3d angularMomentum{ 0, 0, 0 }; // about the centre, world axes [kg m^2/s]
};

// At rest where the scene puts it.
RigidState restingState(const MassProperties& m);

// The angular velocity of a state, I_world^-1 L with I_world = R I R^T [rad/s].
Vec3d angularVelocity(const RigidState& s, const MassProperties& m);
// I_world^-1 v for the state's orientation: what an angular impulse v turns the body by.
Vec3d inverseInertiaTimes(const RigidState& s, const MassProperties& m, const Vec3d& v);

// One step of dt, semi-implicit (symplectic) Euler: the momenta first, from the force (plus the
// body's weight, m gravity) and the torque about the centre; then the centre from the new velocity
// and the orientation by the rotation of the new angular momentum's angular velocity at the half
// step (explicit midpoint), renormalised.
// Carrying the angular momentum rather than the angular velocity keeps it exact without a torque
// and gives the gyroscopic motion of a body that spins about an axis not its principal one.
RigidState advanceRigid(const RigidState& s, const MassProperties& m, const Vec3d& force,
  const Vec3d& torque, const Vec3d& gravity, double dt);

// Where the body is: a point x of its own frame is at R (x - c0) + c, c0 the centre of mass as
// sampled; the pivot is the centre, moving at the state's velocities.
SolidPose poseOf(const RigidState& s, const MassProperties& m);

// What of a body can touch a wall: points of its own frame, each the centre of a ball of
// `radius` (a box's corners or a mesh's vertices with radius 0; a sphere's centre with its radius).
struct ContactHull
{
  std::vector<Vec3d> points;
  double radius = 0;
};
ContactHull contactHull(const SolidRegion& solid);

// The body kept inside `domain`: for each wall in turn (x, y, z; low, high), the body is moved
// back along the wall's normal by its deepest point's depth, and impulses along the normal at the
// points that then touch the wall stop them moving into it (no bounce, no friction; a few
// projected Gauss-Seidel sweeps over them), turning the body as a rigid contact does.
RigidState keepInside(
  const RigidState& s, const MassProperties& m, const ContactHull& hull, const Box& domain);

} // namespace pbf
