#include "Solids.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace pbf
{

namespace
{

// The solid's bounding box (a shell's padded by half its thickness).
Box boundsOf(const SolidRegion& s, const std::string& name)
{
  if (s.kind == SolidRegion::Kind::Box)
  {
    return s.box;
  }
  if (s.kind == SolidRegion::Kind::Sphere)
  {
    const Vec3d r{ s.radius, s.radius, s.radius };
    return Box{ s.center - r, s.center + r };
  }
  if (s.mesh.triangles.empty() && !s.file.empty())
  {
    throw InvalidInput(name + ".file = \"" + s.file +
      "\": mesh files are read by the ParaView plugin (VTK's readers); load the scene in "
      "ParaView or pvpython, or give the solid as a box or a sphere");
  }
  // A mesh is checked whole (closed, or given a thickness) before anything is sized from it.
  const Box b = meshBounds(s.mesh, s.thickness, name);
  const double t = 0.5 * s.thickness;
  return Box{ b.min - Vec3d{ t, t, t }, b.max + Vec3d{ t, t, t } };
}

} // namespace

std::vector<DistanceGrid> solidFields(const std::vector<SolidRegion>& solids, const Parameters& p)
{
  const double h = p.smoothingLength();
  const Box& d = p.domain;
  std::vector<DistanceGrid> fields;
  for (std::size_t k = 0; k < solids.size(); ++k)
  {
    const SolidRegion& s = solids[k];
    const std::string name = s.name.empty() ? "obstacles[" + std::to_string(k) + "]" : s.name;
    const Box bounds = boundsOf(s, name);
    // Only what the fluid can reach: the solid within h of the domain.
    const Box reach{ { std::max(bounds.min.x, d.min.x - h), std::max(bounds.min.y, d.min.y - h),
                       std::max(bounds.min.z, d.min.z - h) },
      { std::min(bounds.max.x, d.max.x + h), std::min(bounds.max.y, d.max.y + h),
        std::min(bounds.max.z, d.max.z + h) } };
    if (!(reach.min.x < reach.max.x && reach.min.y < reach.max.y && reach.min.z < reach.max.z))
    {
      std::ostringstream text;
      text << name << ": lies outside the domain (" << d.min.x << ", " << d.min.y
           << ", " << d.min.z << ") - (" << d.max.x << ", " << d.max.y << ", " << d.max.z << ")";
      throw InvalidInput(text.str());
    }
    // Nodes s/2 apart, or coarser for solids so large that all of them together would pass 2^24
    // nodes (64 MiB of floats).
    const Vec3d size = reach.max - reach.min + Vec3d{ 2 * h, 2 * h, 2 * h };
    const double budget = 16777216.0 / static_cast<double>(solids.size());
    const double cell =
      std::max(0.5 * p.particleSpacing, std::cbrt(size.x * size.y * size.z / budget));
    if (s.kind == SolidRegion::Kind::Mesh)
    {
      // Exact where the boundary's sums and the collision read it (h, plus two nodes for the
      // interpolation), estimated beyond.
      fields.push_back(meshDistance(s.mesh, cell, h, s.thickness, name, h + 2 * cell, &reach));
    }
    else if (s.kind == SolidRegion::Kind::Sphere)
    {
      // The sphere's own grid, as far as the fluid can reach it.
      DistanceGrid g = sphereDistance(s.center, s.radius, cell, h);
      fields.push_back(std::move(g));
    }
    else
    {
      // The box's field is exact everywhere; the grid covers the reachable part of it only.
      fields.push_back(boxDistanceOn(s.box, gridOver(reach, cell, h, "obstacles")));
    }
  }
  return fields;
}

ParticleBatch outsideSolids(
  const ParticleBatch& batch, const std::vector<DistanceGrid>& fields, std::size_t& removed)
{
  ParticleBatch kept;
  removed = 0;
  for (std::size_t i = 0; i < batch.position.size(); ++i)
  {
    bool inside = false;
    for (const DistanceGrid& g : fields)
    {
      inside = inside || g.at(batch.position[i]) < 0.0;
    }
    if (inside)
    {
      ++removed;
      continue;
    }
    kept.position.push_back(batch.position[i]);
    kept.velocity.push_back(batch.velocity[i]);
    kept.id.push_back(static_cast<std::int64_t>(kept.id.size()));
  }
  return kept;
}

} // namespace pbf
