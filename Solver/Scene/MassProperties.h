// The mass, centre of mass and inertia tensor of a solid of uniform density, from its shape: what
// a dynamic body (one the fluid moves) needs before its first step. A mesh's come from its closed
// surface by the divergence theorem: the solid is the signed sum of the tetrahedra that join the
// origin to each triangle, each with the covariance of the canonical tetrahedron mapped onto it
// (Blow and Binstock 2004, after Mirtich 1996). Exact for any closed, consistently oriented
// surface; boxes and spheres have their closed forms.
#pragma once

#include "Solids.h"
#include "Vec3.h"

#include <array>
#include <string>

namespace pbf
{

struct MassProperties
{
  double volume = 0;                 // [m^3]
  double mass = 0;                   // [kg]
  Vec3d centre{ 0, 0, 0 };           // the centre of mass, in the solid's own frame [m]
  std::array<double, 9> inertia{};   // about the centre, the solid's own axes, rows [kg m^2]
};

// The properties of a closed, consistently oriented mesh (either orientation: an inside-out
// surface gives the same solid) of `density` [kg/m^3]. Throws InvalidInput naming `what` for a
// density that is not a finite number > 0, a surface that is open or not consistently oriented
// (naming an edge), or one that encloses no volume.
MassProperties meshMassProperties(
  const TriangleMesh& mesh, double density, const std::string& what);

MassProperties boxMassProperties(const Box& box, double density, const std::string& what);
MassProperties sphereMassProperties(
  const Vec3d& centre, double radius, double density, const std::string& what);

// A scene's solid by its kind (a shell of some thickness is not a closed solid: InvalidInput).
MassProperties solidMassProperties(const SolidRegion& solid, double density, const std::string& what);

// Where a solid's loads turn it about (its centre of mass at uniform density), in its own frame:
// a shell's, or a surface whose triangles disagree on their orientation, is its bounds' centre.
Vec3d solidCentre(const SolidRegion& solid);

} // namespace pbf
