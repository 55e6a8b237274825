// The solid obstacles of a scene ("obstacles" in its JSON): boxes and spheres the fluid flows
// around, turned into signed distance fields at the run's resolution, and the initial fluid that
// lies inside them removed.
#pragma once

#include "Parameters.h"
#include "SignedDistance.h"
#include "SolidMotion.h"
#include "Particles.h"

#include <array>
#include <string>
#include <vector>

namespace pbf
{

struct SolidRegion
{
  enum class Kind
  {
    Box,
    Sphere,
    Mesh
  };
  Kind kind = Kind::Box;
  Box box;         // Kind::Box
  Vec3d center{ 0, 0, 0 }; // Kind::Sphere
  double radius = 0;
  TriangleMesh mesh;     // Kind::Mesh: a closed surface, or a shell of `thickness` ...
  std::string file;      // ... or, until a reader fills `mesh`, the file that holds it
  double thickness = 0;  // [m]
  std::string name;      // what errors call the solid ("obstacles[k]" when empty)
  // How it moves (none: it stays where it is). A NaN pivot.x stands for the centre of its bounds.
  SolidMotion motion;
  // > 0: a body the fluid moves (Scene/RigidBody.h), of this uniform density [kg/m^3], from rest
  // where it is given; 0: it stays or follows `motion`.
  double density = 0;
  // A body's freedoms (a scene's "degreesOfFreedom"): the world axes its centre moves along and
  // whether it turns; a body on a vertical guide heaves only (x and z held, no turning).
  std::array<bool, 3> freeAxes{ true, true, true };
  bool turns = true;
  // A body is held at rest where it is given until this time [s], the fluid pushing on it, and
  // released then: a drop test's hold while the water settles (a scene's "release").
  double release = 0;
  // The angle each liquid's surface makes with it [degrees] (SurfaceTension.h's adhesion); 90, the
  // default, is neutral. The obstacle's "contactAngle" sets every liquid's, a liquid's
  // "contactAngles" by the solid's name its own.
  std::array<double, kMaxLiquids> contactAngle = [] {
    std::array<double, kMaxLiquids> neutral;
    neutral.fill(90.0);
    return neutral;
  }();
};

// The field of each solid: nodes s/2 apart (coarser only beyond 2^24 nodes) over the part of the
// solid within h of the domain (a terrain larger than the tank costs only what is inside),
// padded by h (the reach of the boundary's sums); a mesh's distance is exact within h + 2 nodes
// of its surface. With p.exactBoundaries each grid carries its shape map (ShapeMap.h, from the
// cache of ShapeMapCache.h). Throws InvalidInput naming the solid when it lies wholly outside the
// domain, its mesh is bad, no node lies inside it (a solid that is not a body: a body names a
// shell that encloses nothing itself), or its map holds a value that is not a number.
std::vector<DistanceGrid> solidFields(const std::vector<SolidRegion>& solids, const Parameters& p);

// Whether x is inside a solid (its field < 0) with the solids at `poses` (none: as sampled).
bool insideSolids(
  const Vec3d& x, const std::vector<DistanceGrid>& fields, const std::vector<SolidPose>& poses);

// The particles whose centres are outside every solid (the field >= 0) with the solids at
// `poses` (none: as sampled), in order, their ids renumbered 0..N-1; `removed` receives how many
// were inside.
ParticleBatch outsideSolids(const ParticleBatch& batch, const std::vector<DistanceGrid>& fields,
  const std::vector<SolidPose>& poses, std::size_t& removed);

// The solid's bounding box in its own frame (a shell's padded by half its thickness); InvalidInput
// naming `name` for a mesh that was not read or is bad.
Box solidBounds(const SolidRegion& solid, const std::string& name);

// The solids' motions with every pivot given (a NaN pivot.x becomes the centre of the solid's
// bounds), and checked (InvalidInput naming the solid).
std::vector<SolidMotion> solidMotions(const std::vector<SolidRegion>& solids);
// Where each solid is at `time`; empty when no solid moves.
std::vector<SolidPose> posesAt(const std::vector<SolidMotion>& motions, double time);
// Per solid, the distance from its motion's pivot to the farthest corner of its bounds [m] (0 for
// a solid that does not move): what turns an angular velocity into the fastest surface speed.
std::vector<double> solidReaches(
  const std::vector<SolidRegion>& solids, const std::vector<SolidMotion>& motions);

} // namespace pbf
