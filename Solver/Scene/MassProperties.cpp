#include "MassProperties.h"

#include "Parameters.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <utility>

namespace pbf
{

namespace
{

void checkDensity(double density, const std::string& what)
{
  if (!(std::isfinite(density) && density > 0))
  {
    std::ostringstream text;
    text << what << ": density = " << density
         << ": must be a finite number > 0 [kg/m^3] for a body the fluid moves";
    throw InvalidInput(text.str());
  }
}

// Every directed edge (a, b) of the triangles once, and its reverse once: the surface is closed
// and its triangles agree on which side is outside, which the signed volumes of the tetrahedra
// need (the distance field's ray parity does not).
void checkOriented(const TriangleMesh& mesh, const std::string& what)
{
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
  {
    const auto& v = mesh.triangles[t];
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
    {
      throw InvalidInput(what + ": triangle " + std::to_string(t) +
        " names a point twice: a body the fluid moves needs a surface of proper triangles");
    }
    for (int e = 0; e < 3; ++e)
    {
      ++directed[{ v[e], v[(e + 1) % 3] }];
    }
  }
  for (const auto& [edge, count] : directed)
  {
    const auto reverse = directed.find({ edge.second, edge.first });
    if (count != 1 || reverse == directed.end() || reverse->second != 1)
    {
      throw InvalidInput(what + ": the edge from point " + std::to_string(edge.first) +
        " to point " + std::to_string(edge.second) +
        (count != 1 ? " runs the same way in " + std::to_string(count) + " triangles"
                    : " has no triangle running back along it") +
        ": a body the fluid moves needs a closed surface whose triangles agree on their "
        "orientation");
    }
  }
}

// The inertia tensor about the centre of mass from the covariance C = integral of rho r r^T dV
// about `origin`: C moved to the centre, then I = trace(C) 1 - C.
std::array<double, 9> inertiaFromCovariance(
  std::array<double, 9> covariance, double mass, const Vec3d& fromOrigin)
{
  const double d[3] = { fromOrigin.x, fromOrigin.y, fromOrigin.z };
  for (int a = 0; a < 3; ++a)
  {
    for (int b = 0; b < 3; ++b)
    {
      covariance[3 * a + b] -= mass * d[a] * d[b];
    }
  }
  const double trace = covariance[0] + covariance[4] + covariance[8];
  std::array<double, 9> inertia{};
  for (int k = 0; k < 9; ++k)
  {
    inertia[k] = (k % 4 == 0 ? trace : 0.0) - covariance[k];
  }
  return inertia;
}

Vec3d centreOfBounds(const TriangleMesh& mesh)
{
  Box bounds{ mesh.points[0], mesh.points[0] };
  for (const Vec3d& p : mesh.points)
  {
    bounds.min = { std::min(bounds.min.x, p.x), std::min(bounds.min.y, p.y), std::min(bounds.min.z, p.z) };
    bounds.max = { std::max(bounds.max.x, p.x), std::max(bounds.max.y, p.y), std::max(bounds.max.z, p.z) };
  }
  return (bounds.min + bounds.max) * 0.5;
}

} // namespace

MassProperties meshMassProperties(const TriangleMesh& mesh, double density, const std::string& what)
{
  checkDensity(density, what);
  const Box bounds = meshBounds(mesh, 0.0, what);
  checkOriented(mesh, what);
  // About the bounds' centre rather than the world's origin: the tetrahedra's signed volumes then
  // cancel far less, for a solid far from the origin.
  const Vec3d origin = (bounds.min + bounds.max) * 0.5;
  double sixVolumes = 0;
  Vec3d moment{ 0, 0, 0 };       // 24 times the first moment
  std::array<double, 9> c{};     // 120 times the covariance
  for (const auto& t : mesh.triangles)
  {
    const Vec3d a = mesh.points[t[0]] - origin;
    const Vec3d b = mesh.points[t[1]] - origin;
    const Vec3d e = mesh.points[t[2]] - origin;
    const double det = dot(a, cross(b, e));
    const Vec3d s = a + b + e;
    sixVolumes += det;
    moment += s * det;
    // The canonical tetrahedron's covariance (1 + 1 1^T) / 120 mapped by [a b e]: the outer
    // products of the three corners plus that of their sum.
    const double p[4][3] = { { a.x, a.y, a.z }, { b.x, b.y, b.z }, { e.x, e.y, e.z },
      { s.x, s.y, s.z } };
    for (const auto& q : p)
    {
      for (int i = 0; i < 3; ++i)
      {
        for (int j = 0; j < 3; ++j)
        {
          c[3 * i + j] += det * q[i] * q[j];
        }
      }
    }
  }
  // An inside-out surface has every signed volume negated: the same solid.
  const double sign = sixVolumes < 0 ? -1.0 : 1.0;
  const Vec3d size = bounds.max - bounds.min;
  MassProperties m;
  m.volume = sign * sixVolumes / 6.0;
  if (!(m.volume > 1e-12 * size.x * size.y * size.z))
  {
    std::ostringstream text;
    text << what << ": the surface encloses a volume of " << m.volume
         << " m^3: a body the fluid moves needs a solid";
    throw InvalidInput(text.str());
  }
  m.mass = density * m.volume;
  const Vec3d offset = moment * (sign / 24.0 / m.volume);
  m.centre = origin + offset;
  for (double& v : c)
  {
    v *= sign * density / 120.0;
  }
  m.inertia = inertiaFromCovariance(c, m.mass, offset);
  return m;
}

MassProperties boxMassProperties(const Box& box, double density, const std::string& what)
{
  checkDensity(density, what);
  const Vec3d l = box.max - box.min;
  MassProperties m;
  m.volume = l.x * l.y * l.z;
  if (!(m.volume > 0))
  {
    throw InvalidInput(what + ": the box encloses no volume: a body the fluid moves needs a solid");
  }
  m.mass = density * m.volume;
  m.centre = (box.min + box.max) * 0.5;
  m.inertia = { m.mass / 12 * (l.y * l.y + l.z * l.z), 0, 0, 0,
    m.mass / 12 * (l.x * l.x + l.z * l.z), 0, 0, 0, m.mass / 12 * (l.x * l.x + l.y * l.y) };
  return m;
}

MassProperties sphereMassProperties(
  const Vec3d& centre, double radius, double density, const std::string& what)
{
  checkDensity(density, what);
  if (!(radius > 0))
  {
    throw InvalidInput(what + ": the sphere has no volume: a body the fluid moves needs a solid");
  }
  MassProperties m;
  m.volume = 4.0 / 3.0 * M_PI * radius * radius * radius;
  m.mass = density * m.volume;
  m.centre = centre;
  const double i = 0.4 * m.mass * radius * radius;
  m.inertia = { i, 0, 0, 0, i, 0, 0, 0, i };
  return m;
}

MassProperties solidMassProperties(const SolidRegion& solid, double density, const std::string& what)
{
  switch (solid.kind)
  {
    case SolidRegion::Kind::Box:
      return boxMassProperties(solid.box, density, what);
    case SolidRegion::Kind::Sphere:
      return sphereMassProperties(solid.center, solid.radius, density, what);
    case SolidRegion::Kind::Mesh:
      break;
  }
  if (solid.thickness > 0)
  {
    throw InvalidInput(what + ": a shell (thickness > 0) encloses no solid: a body the fluid "
                              "moves needs a closed surface and thickness 0");
  }
  if (solid.mesh.triangles.empty() && !solid.file.empty())
  {
    throw InvalidInput(what + ": the mesh of " + solid.file + " has not been read");
  }
  return meshMassProperties(solid.mesh, density, what);
}

Vec3d solidCentre(const SolidRegion& solid)
{
  if (solid.kind != SolidRegion::Kind::Mesh || solid.thickness > 0 || solid.mesh.triangles.empty())
  {
    return solid.kind == SolidRegion::Kind::Sphere ? solid.center
      : solid.kind == SolidRegion::Kind::Box      ? (solid.box.min + solid.box.max) * 0.5
      : solid.mesh.points.empty()                  ? Vec3d{ 0, 0, 0 }
                                                   : centreOfBounds(solid.mesh);
  }
  try
  {
    return meshMassProperties(solid.mesh, 1.0, "solid").centre;
  }
  catch (const InvalidInput&)
  {
    // Closed (the distance field checked it) but not consistently oriented: no signed volume.
    return centreOfBounds(solid.mesh);
  }
}

} // namespace pbf
