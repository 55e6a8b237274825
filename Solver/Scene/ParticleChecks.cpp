#include "ParticleChecks.h"

#include "PointText.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <sstream>
#include <unordered_map>

namespace pbf
{

void checkBatch(const Parameters& parameters, const ParticleBatch& batch)
{
  const std::size_t n = batch.position.size();
  if (batch.velocity.size() != n || batch.id.size() != n)
  {
    throw InvalidInput("particle arrays differ in length: " + std::to_string(n) + " positions, " +
      std::to_string(batch.velocity.size()) + " velocities, " + std::to_string(batch.id.size()) +
      " ids");
  }
  checkLiquids(parameters, batch.liquid, n, "particle batch");
  if (n >= std::numeric_limits<std::uint32_t>::max())
  {
    throw InvalidInput("particle count = " + std::to_string(n) + ": more than 32-bit indices hold");
  }
  for (std::size_t i = 0; i < n; ++i)
  {
    checkParticle(parameters, static_cast<std::int64_t>(i), batch.position[i], batch.velocity[i]);
  }
}

void checkParticle(
  const Parameters& parameters, std::int64_t which, const Vec3d& x, const Vec3d& v)
{
  // A particle within one spacing outside the box is a rounding matter and is projected inside by
  // the first collision step; farther out the scene and the domain disagree.
  const double slack = parameters.particleSpacing;
  const Box& d = parameters.domain;
  if (!isFinite(x))
  {
    throw InvalidInput("position of particle " + std::to_string(which) + " = " + pointText(x) +
      ": must be finite");
  }
  if (!isFinite(v))
  {
    throw InvalidInput("velocity of particle " + std::to_string(which) + " = " + pointText(v) +
      ": must be finite");
  }
  if (x.x < d.min.x - slack || x.y < d.min.y - slack || x.z < d.min.z - slack ||
    x.x > d.max.x + slack || x.y > d.max.y + slack || x.z > d.max.z + slack)
  {
    throw InvalidInput("position of particle " + std::to_string(which) + " = " + pointText(x) +
      ": outside the domain " + pointText(d.min) + " - " + pointText(d.max));
  }
}

void checkLiquid(const Parameters& parameters, std::int64_t which, std::uint8_t liquid)
{
  if (!parameters.liquids.empty() && liquid >= parameters.liquids.size())
  {
    throw InvalidInput("liquid of particle " + std::to_string(which) + " = " +
      std::to_string(liquid) + ": the scene names " + std::to_string(parameters.liquids.size()) +
      " liquids (0 to " + std::to_string(parameters.liquids.size() - 1) + ")");
  }
}

void checkLiquids(const Parameters& parameters, const std::vector<std::uint8_t>& liquid,
  std::size_t count, const char* what)
{
  if (parameters.liquids.empty())
  {
    if (!liquid.empty())
    {
      throw InvalidInput(std::string(what) + " liquid array: the scene names no liquids, yet " +
        std::to_string(liquid.size()) + " particles carry one");
    }
    return;
  }
  if (!liquid.empty() && liquid.size() != count)
  {
    throw InvalidInput(std::string(what) + " liquid array = " + std::to_string(liquid.size()) +
      " values: must be one per particle (" + std::to_string(count) + ")");
  }
  for (std::size_t i = 0; i < liquid.size(); ++i)
  {
    if (liquid[i] >= parameters.liquids.size())
    {
      throw InvalidInput(std::string(what) + " liquid of particle " + std::to_string(i) + " = " +
        std::to_string(liquid[i]) + ": the scene names " +
        std::to_string(parameters.liquids.size()) + " liquids (0 to " +
        std::to_string(parameters.liquids.size() - 1) + ")");
    }
  }
}

namespace
{

// Within a quarter spacing of a wall that mirrors the fluid.
bool onAMirrorWall(const Parameters& parameters, const Vec3d& x)
{
  const Box& d = parameters.domain;
  const double wall = std::min({ x.x - d.min.x, d.max.x - x.x, x.y - d.min.y, d.max.y - x.y,
    x.z - d.min.z, d.max.z - x.z });
  return parameters.mirrorWalls && std::abs(wall) < 0.25 * parameters.particleSpacing;
}

[[noreturn]] void refuseOnWalls(const Parameters& parameters, std::size_t onWalls,
  std::int64_t firstId, const Vec3d& first, const std::string& where)
{
  const Box& d = parameters.domain;
  std::ostringstream text;
  text.precision(4);
  text << "initial particles: " << onWalls << (onWalls == 1 ? " point lies" : " points lie")
       << " within a quarter of particleSpacing = " << parameters.particleSpacing
       << " m of a wall of the domain " << pointText(d.min) << " - " << pointText(d.max) << " ("
       << where << "), point " << firstId << " = " << pointText(first)
       << " first: a wall mirrors the fluid, so a point on it counts twice. Move the points half "
          "a spacing inside, enlarge the domain (a scene file), or turn mirrorWalls off";
  throw InvalidInput(text.str());
}

} // namespace

namespace
{

// What the parts of a fluid find on the walls, added up over the parts in order: how many points
// lie on a wall, and the first of them (its index in the whole fluid, its position).
struct OnWalls
{
  double points = 0; // of the whole fluid
  std::size_t count = 0;
  std::size_t firstIndex = 0;
  Vec3d first{};
};

// Each part's [points, on walls, first on a wall's index in the part, x, y, z, extra...] gathered
// (FluidSource::allParts); returns the walls' findings and the sums of the extra values.
OnWalls wallsOverParts(const FluidSource& fluid, const std::vector<double>& mine,
  std::vector<double>& extraSums)
{
  OnWalls walls;
  double before = 0;
  extraSums.assign(mine.size() - 6, 0.0);
  for (const std::vector<double>& part : fluid.allParts(mine))
  {
    if (part[1] > 0 && walls.count == 0)
    {
      walls.firstIndex = static_cast<std::size_t>(before + part[2]);
      walls.first = Vec3d{ part[3], part[4], part[5] };
    }
    walls.count += static_cast<std::size_t>(part[1]);
    before += part[0];
    for (std::size_t k = 6; k < part.size(); ++k)
    {
      extraSums[k - 6] += part[k];
    }
  }
  walls.points = before;
  return walls;
}

// This part's [points, on walls, first on a wall, x, y, z], visiting each of its positions.
std::vector<double> wallsOfPart(const Parameters& parameters, const FluidSource& fluid,
  const std::function<void(const Vec3d&)>& alsoVisit)
{
  std::size_t at = 0, onWalls = 0, first = 0;
  Vec3d firstX{};
  fluid.forEachPosition([&](const Vec3d& x) {
    if (isFinite(x) && onAMirrorWall(parameters, x) && onWalls++ == 0)
    {
      first = at;
      firstX = x;
    }
    alsoVisit(x);
    ++at;
  });
  return { double(at), double(onWalls), double(first), firstX.x, firstX.y, firstX.z };
}

} // namespace

void checkPacking(const Parameters& parameters, const FluidSource& fluid, const std::string& where)
{
  const double s = parameters.particleSpacing;
  const Box& d = parameters.domain;
  // The occupied cells of this part: a cell that two pieces share counts in both, which can only
  // lower the ratio (pieces of a parallel input are compact, so few cells are shared).
  std::unordered_map<std::uint64_t, std::uint32_t> perCell;
  std::vector<double> mine = wallsOfPart(parameters, fluid, [&](const Vec3d& x) {
    if (!isFinite(x))
    {
      return; // checkBatch names it
    }
    // Cells of side s from the domain's corner, 21 bits an axis (2 million cells along each).
    auto cell = [&](double value, double low) {
      const double c = std::floor((value - low) / s);
      return static_cast<std::uint64_t>(std::min(std::max(c, 0.0), 2097151.0));
    };
    ++perCell[cell(x.x, d.min.x) | cell(x.y, d.min.y) << 21 | cell(x.z, d.min.z) << 42];
  });
  mine.push_back(static_cast<double>(perCell.size()));
  std::vector<double> sums;
  const OnWalls walls = wallsOverParts(fluid, mine, sums);
  const double occupied = sums[0];
  const double points = walls.points;
  const double perOccupied = occupied > 0 ? points / occupied : 0;
  if (perOccupied > kMaxParticlesPerCell)
  {
    std::ostringstream text;
    text.precision(3);
    text << "initial particles: " << static_cast<std::size_t>(points) << " points in "
         << static_cast<std::size_t>(occupied)
         << " occupied cells of side particleSpacing = " << s << " m, " << perOccupied
         << " per cell where the fluid holds 1 (more than " << kMaxParticlesPerCell
         << "): the points are packed about " << std::cbrt(perOccupied)
         << " times closer than the spacing, and the first projection would fling them apart. Set "
            "particleSpacing to about "
         << s / std::cbrt(perOccupied) << " m (the points' own spacing), or resample the points";
    throw InvalidInput(text.str());
  }
  if (walls.count > 0)
  {
    refuseOnWalls(parameters, walls.count, static_cast<std::int64_t>(walls.firstIndex),
      walls.first, where);
  }
}

void checkPacking(const Parameters& parameters, const ParticleBatch& batch, const std::string& where)
{
  checkPacking(parameters, BatchSource(batch), where);
}

void checkOffWalls(const Parameters& parameters, const FluidSource& fluid, const std::string& where)
{
  std::vector<double> sums;
  const OnWalls walls =
    wallsOverParts(fluid, wallsOfPart(parameters, fluid, [](const Vec3d&) {}), sums);
  if (walls.count > 0)
  {
    refuseOnWalls(parameters, walls.count, static_cast<std::int64_t>(walls.firstIndex),
      walls.first, where);
  }
}

} // namespace pbf
