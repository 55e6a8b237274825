#include "Solids.h"

#include "ShapeMapCache.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace pbf
{

Box solidBounds(const SolidRegion& s, const std::string& name)
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

namespace
{

// The world box around `box` placed at `pose`.
Box placedBounds(const Box& box, const SolidPose& pose)
{
  Box out{ { HUGE_VAL, HUGE_VAL, HUGE_VAL }, { -HUGE_VAL, -HUGE_VAL, -HUGE_VAL } };
  for (int corner = 0; corner < 8; ++corner)
  {
    const Vec3d c = pose.toWorld({ corner & 1 ? box.max.x : box.min.x,
      corner & 2 ? box.max.y : box.min.y, corner & 4 ? box.max.z : box.min.z });
    out.min = { std::min(out.min.x, c.x), std::min(out.min.y, c.y), std::min(out.min.z, c.z) };
    out.max = { std::max(out.max.x, c.x), std::max(out.max.y, c.y), std::max(out.max.z, c.z) };
  }
  return out;
}

bool overlaps(const Box& a, const Box& b)
{
  return a.min.x < b.max.x && b.min.x < a.max.x && a.min.y < b.max.y && b.min.y < a.max.y &&
    a.min.z < b.max.z && b.min.z < a.max.z;
}

std::string nameOf(const SolidRegion& s, std::size_t k)
{
  return s.name.empty() ? "obstacles[" + std::to_string(k) + "]" : s.name;
}

// A solid no node of its grid lies inside is thinner than the grid resolves: the stages would
// not see it. InvalidInput naming it, its grid's cell and the field's least value.
void requireResolved(const DistanceGrid& g, const std::string& name)
{
  float least = std::numeric_limits<float>::infinity();
  for (float v : g.phi)
  {
    least = std::min(least, v);
  }
  if (!(least < 0.0f))
  {
    std::ostringstream text;
    text << name << ": thinner than its grid resolves: no node of cell " << g.cell
         << " m lies inside it (the nearest is " << least << " m from its surface)";
    throw InvalidInput(text.str());
  }
}

// A map with a value that is not a number (a field the integration cannot follow) would poison
// every particle near the solid: InvalidInput naming the solid and the node.
void requireFiniteMap(const DistanceGrid& g, const std::string& name)
{
  for (std::size_t v = 0; v < g.shape.size(); ++v)
  {
    if (!std::isfinite(g.shape[v]))
    {
      const std::size_t node = v / kShapeValues;
      const Vec3d x = g.nodePosition(static_cast<int>(node % g.nx),
        static_cast<int>(node / g.nx % g.ny), static_cast<int>(node / g.nx / g.ny));
      std::ostringstream text;
      text << name << ": its shape map cannot be built: the node at (" << x.x << ", " << x.y
           << ", " << x.z << ") reads " << g.shape[v];
      throw InvalidInput(text.str());
    }
  }
}

} // namespace

std::vector<SolidMotion> solidMotions(const std::vector<SolidRegion>& solids)
{
  std::vector<SolidMotion> motions;
  for (std::size_t k = 0; k < solids.size(); ++k)
  {
    SolidMotion m = solids[k].motion;
    if (m.moves() && std::isnan(m.pivot.x))
    {
      const Box b = solidBounds(solids[k], nameOf(solids[k], k));
      m.pivot = (b.min + b.max) * 0.5;
    }
    m.validate(nameOf(solids[k], k) + ".motion");
    motions.push_back(m);
  }
  return motions;
}

std::vector<SolidPose> posesAt(const std::vector<SolidMotion>& motions, double time)
{
  const bool any =
    std::any_of(motions.begin(), motions.end(), [](const SolidMotion& m) { return m.moves(); });
  std::vector<SolidPose> poses;
  for (const SolidMotion& m : motions)
  {
    if (any)
    {
      poses.push_back(m.at(time));
    }
  }
  return poses;
}

std::vector<double> solidReaches(
  const std::vector<SolidRegion>& solids, const std::vector<SolidMotion>& motions)
{
  std::vector<double> reaches(solids.size(), 0.0);
  for (std::size_t k = 0; k < solids.size() && k < motions.size(); ++k)
  {
    if (!motions[k].moves())
    {
      continue;
    }
    const Box b = solidBounds(solids[k], nameOf(solids[k], k));
    const Vec3d p = motions[k].pivot;
    const Vec3d far{ std::max(std::abs(b.min.x - p.x), std::abs(b.max.x - p.x)),
      std::max(std::abs(b.min.y - p.y), std::abs(b.max.y - p.y)),
      std::max(std::abs(b.min.z - p.z), std::abs(b.max.z - p.z)) };
    reaches[k] = length(far);
  }
  return reaches;
}

std::vector<DistanceGrid> solidFields(const std::vector<SolidRegion>& solids, const Parameters& p)
{
  const double h = p.smoothingLength();
  const Box& d = p.domain;
  std::vector<DistanceGrid> fields;
  for (std::size_t k = 0; k < solids.size(); ++k)
  {
    const SolidRegion& s = solids[k];
    const std::string name = nameOf(s, k);
    const Box bounds = solidBounds(s, name);
    // Only what the fluid can reach: the solid within h of the domain; a moving solid whole,
    // when some keyframe brings it within h of the domain.
    const Box padded{ d.min - Vec3d{ h, h, h }, d.max + Vec3d{ h, h, h } };
    Box reach{ { std::max(bounds.min.x, padded.min.x), std::max(bounds.min.y, padded.min.y),
                 std::max(bounds.min.z, padded.min.z) },
      { std::min(bounds.max.x, padded.max.x), std::min(bounds.max.y, padded.max.y),
        std::min(bounds.max.z, padded.max.z) } };
    if (s.motion.moves())
    {
      reach = Box{ { 1, 1, 1 }, { 0, 0, 0 } }; // empty unless a keyframe overlaps
      SolidMotion m = s.motion;
      m.pivot = std::isnan(m.pivot.x) ? (bounds.min + bounds.max) * 0.5 : m.pivot;
      for (const Keyframe& key : m.keyframes)
      {
        if (overlaps(placedBounds(bounds, m.at(key.time)), padded))
        {
          reach = bounds;
        }
      }
    }
    if (!(reach.min.x < reach.max.x && reach.min.y < reach.max.y && reach.min.z < reach.max.z))
    {
      std::ostringstream text;
      text << name << ": lies outside the domain (" << d.min.x << ", " << d.min.y
           << ", " << d.min.z << ") - (" << d.max.x << ", " << d.max.y << ", " << d.max.z << ")";
      throw InvalidInput(text.str());
    }
    // Nodes s/2 apart, or coarser for solids so large that all of them together would pass 2^24
    // nodes (64 MiB of distances and 192 MiB of normals).
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
    fields.back().contactAngle = s.contactAngle;
    if (s.density == 0)
    {
      // A body's own checks name a shell that encloses nothing (RigidBody.h).
      requireResolved(fields.back(), name);
    }
    if (p.exactBoundaries)
    {
      attachShapeMap(
        fields.back(), shapeKernels(p), shapeWalls(p, !s.motion.moves() && s.density == 0));
      requireFiniteMap(fields.back(), name);
    }
  }
  return fields;
}

bool insideSolids(
  const Vec3d& x, const std::vector<DistanceGrid>& fields, const std::vector<SolidPose>& poses)
{
  for (std::size_t k = 0; k < fields.size(); ++k)
  {
    if (fields[k].at(poses.empty() ? x : poses[k].toLocal(x)) < 0.0)
    {
      return true;
    }
  }
  return false;
}

ParticleBatch outsideSolids(const ParticleBatch& batch, const std::vector<DistanceGrid>& fields,
  const std::vector<SolidPose>& poses, std::size_t& removed)
{
  checkPoseCount(poses.size(), fields.size());
  ParticleBatch kept;
  removed = 0;
  for (std::size_t i = 0; i < batch.position.size(); ++i)
  {
    if (insideSolids(batch.position[i], fields, poses))
    {
      ++removed;
      continue;
    }
    kept.position.push_back(batch.position[i]);
    kept.velocity.push_back(batch.velocity[i]);
    kept.id.push_back(static_cast<std::int64_t>(kept.id.size()));
    if (!batch.liquid.empty())
    {
      kept.liquid.push_back(batch.liquid[i]);
    }
  }
  return kept;
}

} // namespace pbf
