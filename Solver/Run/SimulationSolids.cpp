// Simulation's solids: the obstacles' motions, the bodies the fluid moves, the loads on them,
// and where they stand.
#include "Simulation.h"

#include "BodyContact.h"
#include "MassProperties.h"
#include "RigidBody.h"
#include "Solids.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace pbf
{
namespace
{

// A body held until its release stays at rest where it is given; after it, the coordinates and
// momenta of its locked freedoms are the resting state's, so it moves along its free axes and
// turns only if it may (a sphere on a vertical guide heaves).
RigidState withinFreedoms(
  const RigidState& s, const RigidState& rest, const SolidRegion& solid, double end)
{
  if (end <= solid.release)
  {
    return rest;
  }
  RigidState r = s;
  if (!solid.freeAxes[0])
  {
    r.centre.x = rest.centre.x;
    r.velocity.x = 0;
  }
  if (!solid.freeAxes[1])
  {
    r.centre.y = rest.centre.y;
    r.velocity.y = 0;
  }
  if (!solid.freeAxes[2])
  {
    r.centre.z = rest.centre.z;
    r.velocity.z = 0;
  }
  if (!solid.turns)
  {
    r.orientation = rest.orientation;
    r.angularMomentum = rest.angularMomentum;
  }
  return r;
}

} // namespace

// The fastest point of a moving solid now and one largest step on (the next step may begin a
// faster keyframe segment): a function of the time alone, so the steps stay a function of the
// state.
double Simulation::fastestSolidPoint() const
{
  double fastest = 0;
  for (std::size_t k = 0; k < motions_.size(); ++k)
  {
    if (!motions_[k].moves())
    {
      continue;
    }
    for (double t : { time_, time_ + parameters_.timeStep })
    {
      const SolidPose pose = motions_[k].at(t);
      fastest = std::max(
        fastest, length(pose.pivotVelocity) + length(pose.angularVelocity) * solidReach_[k]);
    }
  }
  for (const Body& body : bodies_)
  {
    fastest = std::max(fastest,
      length(body.state.velocity) + length(angularVelocity(body.state, body.mass)) * body.reach);
  }
  return fastest;
}

void Simulation::setSolidMotion(std::size_t solid, SolidMotion motion)
{
  if (solid >= motions_.size())
  {
    throw InvalidInput("solid = " + std::to_string(solid) + ": the scene has " +
      std::to_string(motions_.size()) + " solid(s)");
  }
  const std::string name = solidName(solid);
  motion.validate(name + ".motion");
  if (motion.moves() && std::isnan(motion.pivot.x))
  {
    throw InvalidInput(name + ".motion.pivot: must be given");
  }
  const SolidMotion& old = motions_[solid];
  const bool samePivot = old.pivot.x == motion.pivot.x && old.pivot.y == motion.pivot.y &&
    old.pivot.z == motion.pivot.z;
  const bool startsMoving = old.moves() != motion.moves();
  motions_[solid] = std::move(motion);
  scene_.solids[solid].motion = motions_[solid];
  // The reach (a mesh's bounds, checked whole) only when the pivot moved or the solid began to
  // move: the VTK filter calls this at every request.
  if (!samePivot || startsMoving)
  {
    solidReach_ = solidReaches(scene_.solids, motions_);
  }
}

void Simulation::makeBodies()
{
  for (std::size_t k = 0; k < scene_.solids.size(); ++k)
  {
    const SolidRegion& solid = scene_.solids[k];
    if (solid.density == 0)
    {
      continue; // static or prescribed; any other density is a body's, checked below
    }
    Body body;
    body.solid = k;
    body.mass = solidMassProperties(solid, solid.density, solidName(k));
    body.state = restingState(body.mass);
    body.hull = contactHull(solid);
    const Box b = solidBounds(solid, solidName(k));
    const Vec3d c = body.mass.centre;
    body.reach = length(Vec3d{ std::max(std::abs(b.min.x - c.x), std::abs(b.max.x - c.x)),
      std::max(std::abs(b.min.y - c.y), std::abs(b.max.y - c.y)),
      std::max(std::abs(b.min.z - c.z), std::abs(b.max.z - c.z)) });
    bodies_.push_back(body);
  }
}

std::vector<SolidPose> Simulation::solidPoses(double time) const
{
  std::vector<SolidPose> poses = posesAt(motions_, time);
  if (bodies_.empty())
  {
    return poses;
  }
  poses.resize(scene_.solids.size());
  for (const Body& body : bodies_)
  {
    poses[body.solid] = poseOf(body.state, body.mass);
  }
  return poses;
}

std::string Simulation::solidName(std::size_t k) const
{
  return scene_.solids[k].name.empty() ? "obstacles[" + std::to_string(k) + "]"
                                        : scene_.solids[k].name;
}

std::string Simulation::loadName(std::size_t k) const
{
  static const char* const walls[6] = { "tank -x", "tank +x", "tank -y", "tank +y", "tank -z",
    "tank +z" };
  const std::size_t solids = scene_.solids.size();
  return k < solids ? solidName(k) : walls[(k - solids) % 6];
}

void Simulation::moveBodies(double dt, double end)
{
  for (Body& body : bodies_)
  {
    const double release = scene_.solids[body.solid].release;
    if (end <= release)
    {
      continue; // held where it is given (withinFreedoms puts it back after the contacts)
    }
    // The step in which it is let go moves it from the release on.
    body.state = advanceRigid(body.state, body.mass, body.load.force, body.load.torque,
      parameters_.gravity, std::min(dt, end - release));
  }
  // Each body against every solid after it, in the scene's order (the result does not depend on
  // anything else); the sides are placed anew for each pair, as the one before may have moved them.
  const std::vector<SolidPose> fixed = posesAt(motions_, end);
  for (const Body& body : bodies_)
  {
    for (std::size_t k = 0; k < scene_.solids.size(); ++k)
    {
      const bool bodyK = scene_.solids[k].density != 0;
      if (k == body.solid || (bodyK && k < body.solid))
      {
        continue; // itself, or a pair of bodies met from the first of them
      }
      ContactSide a = contactSide(body.solid, fixed);
      ContactSide b = contactSide(k, fixed);
      separate(a, b);
    }
  }
  for (Body& body : bodies_)
  {
    body.state = keepInside(body.state, body.mass, body.hull, parameters_.domain);
    body.state =
      withinFreedoms(body.state, restingState(body.mass), scene_.solids[body.solid], end);
  }
}

ContactSide Simulation::contactSide(std::size_t k, const std::vector<SolidPose>& poses)
{
  ContactSide side;
  side.hull = &hulls_[k];
  const Box& b = bounds_[k];
  side.reach = 0.5 * length(b.max - b.min);
  side.centre = (b.min + b.max) * 0.5;
  for (Body& body : bodies_)
  {
    if (body.solid == k)
    {
      side.body = &body.state;
      side.mass = &body.mass;
      side.pose = poseOf(body.state, body.mass);
      side.centre = body.state.centre;
      side.reach = body.reach;
    }
  }
  if (!side.body && k < poses.size())
  {
    side.pose = poses[k];
    side.centre = side.pose.toWorld(side.centre);
  }
  // Contacts read the field alone.
  const DistanceGridView<double> view =
    solidFields_[k].view<double>(solidFields_[k].phi.data(), nullptr);
  side.field = side.pose.moving ? placed(view, side.pose) : view;
  return side;
}

void Simulation::checkBodiesStartApart()
{
  if (bodies_.empty())
  {
    return;
  }
  for (std::size_t k = 0; k < scene_.solids.size(); ++k)
  {
    hulls_.push_back(surfaceHull(scene_.solids[k], parameters_.particleSpacing));
    bounds_.push_back(solidBounds(scene_.solids[k], solidName(k)));
  }
  const std::vector<SolidPose> poses = posesAt(motions_, 0.0);
  const Box& d = parameters_.domain;
  // A thousandth of a spacing: a body placed on the floor or against another touches, it is not
  // through.
  const double tolerance = 1e-3 * parameters_.particleSpacing;
  for (const Body& body : bodies_)
  {
    const Box& b = bounds_[body.solid];
    const double through[6] = { d.min.x - b.min.x, b.max.x - d.max.x, d.min.y - b.min.y,
      b.max.y - d.max.y, d.min.z - b.min.z, b.max.z - d.max.z };
    static const char* const walls[6] = { "-x", "+x", "-y", "+y", "-z", "+z" };
    for (int w = 0; w < 6; ++w)
    {
      if (through[w] > tolerance)
      {
        std::ostringstream text;
        text << solidName(body.solid) << ": a body starts " << through[w] << " m through the tank's "
             << walls[w] << " wall; place it inside the domain";
        throw InvalidInput(text.str());
      }
    }
    for (std::size_t k = 0; k < scene_.solids.size(); ++k)
    {
      if (k == body.solid)
      {
        continue;
      }
      ContactSide a = contactSide(body.solid, poses);
      ContactSide other = contactSide(k, poses);
      const double depth = deepestContact(a, other);
      if (depth > tolerance)
      {
        std::ostringstream text;
        text << solidName(body.solid) << ": a body starts " << depth << " m inside "
             << solidName(k) << "; move them apart";
        throw InvalidInput(text.str());
      }
    }
  }
}

void Simulation::addLoads(const std::vector<SolidLoad>& loads,
  const std::vector<SolidPose>& poses, double dt, AdvanceReport& report)
{
  // The stepper's torques are about the world's origin: about the centre c, torque - c x force.
  // A solid's centre is its centre of mass; a wall's, the middle of its face of the domain.
  const Box& domain = parameters_.domain;
  const auto centreOf = [&](std::size_t k) {
    if (k < solidCentres_.size())
    {
      return k < poses.size() ? poses[k].toWorld(solidCentres_[k]) : solidCentres_[k];
    }
    const std::size_t wall = k - solidCentres_.size();
    double middle[3] = { 0.5 * (domain.min.x + domain.max.x), 0.5 * (domain.min.y + domain.max.y),
      0.5 * (domain.min.z + domain.max.z) };
    const double lo[3] = { domain.min.x, domain.min.y, domain.min.z };
    const double hi[3] = { domain.max.x, domain.max.y, domain.max.z };
    middle[wall / 2] = wall % 2 == 0 ? lo[wall / 2] : hi[wall / 2];
    return Vec3d{ middle[0], middle[1], middle[2] };
  };
  report.impulses.resize(loads.size());
  for (std::size_t k = 0; k < loads.size(); ++k)
  {
    const Vec3d centre = centreOf(k);
    report.impulses[k].force += loads[k].force * dt;
    report.impulses[k].torque += (loads[k].torque - cross(centre, loads[k].force)) * dt;
  }
  for (Body& body : bodies_)
  {
    const SolidLoad& load = loads[body.solid];
    body.load = { load.force, load.torque - cross(body.state.centre, load.force) };
  }
}

SurfaceSolids Simulation::surfaceSolids(double time) const
{
  SurfaceSolids solids;
  const std::vector<SolidPose> poses = solidPoses(time);
  for (std::size_t k = 0; k < solidFields_.size(); ++k)
  {
    // posesAt gives none when no solid moves: each then stands where its field was made. The
    // surface and the probes read the field alone.
    const DistanceGridView<double> view =
      solidFields_[k].view<double>(solidFields_[k].phi.data(), nullptr);
    solids.views.push_back(k < poses.size() ? placed(view, poses[k]) : view);
  }
  return solids;
}

} // namespace pbf
