#include "ParticleChecks.h"

#include "PointText.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
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

void checkPacking(const Parameters& parameters, const ParticleBatch& batch, const std::string& where)
{
  const double s = parameters.particleSpacing;
  const Box& d = parameters.domain;
  std::unordered_map<std::uint64_t, std::uint32_t> perCell;
  perCell.reserve(batch.position.size());
  std::size_t onWalls = 0, firstOnWall = 0;
  for (std::size_t i = 0; i < batch.position.size(); ++i)
  {
    const Vec3d& x = batch.position[i];
    if (!isFinite(x))
    {
      continue; // checkBatch names it
    }
    // Cells of side s from the domain's corner, 21 bits an axis (2 million cells along each).
    auto cell = [&](double value, double low) {
      const double c = std::floor((value - low) / s);
      return static_cast<std::uint64_t>(std::min(std::max(c, 0.0), 2097151.0));
    };
    ++perCell[cell(x.x, d.min.x) | cell(x.y, d.min.y) << 21 | cell(x.z, d.min.z) << 42];
    if (onAMirrorWall(parameters, x))
    {
      firstOnWall = onWalls++ == 0 ? i : firstOnWall;
    }
  }
  const double occupied = static_cast<double>(perCell.size());
  const double perOccupied = occupied > 0 ? static_cast<double>(batch.position.size()) / occupied : 0;
  if (perOccupied > kMaxParticlesPerCell)
  {
    std::ostringstream text;
    text.precision(3);
    text << "initial particles: " << batch.position.size() << " points in " << perCell.size()
         << " occupied cells of side particleSpacing = " << s << " m, " << perOccupied
         << " per cell where the fluid holds 1 (more than " << kMaxParticlesPerCell
         << "): the points are packed about " << std::cbrt(perOccupied)
         << " times closer than the spacing, and the first projection would fling them apart. Set "
            "particleSpacing to about "
         << s / std::cbrt(perOccupied) << " m (the points' own spacing), or resample the points";
    throw InvalidInput(text.str());
  }
  if (onWalls > 0)
  {
    refuseOnWalls(
      parameters, onWalls, batch.id[firstOnWall], batch.position[firstOnWall], where);
  }
}

void checkOffWalls(const Parameters& parameters, const FluidSource& fluid, const std::string& where)
{
  std::size_t onWalls = 0, at = 0, firstOnWall = 0;
  Vec3d first{};
  fluid.forEachPosition([&](const Vec3d& x) {
    if (isFinite(x) && onAMirrorWall(parameters, x) && onWalls++ == 0)
    {
      firstOnWall = at;
      first = x;
    }
    ++at;
  });
  if (onWalls > 0)
  {
    refuseOnWalls(parameters, onWalls, static_cast<std::int64_t>(firstOnWall), first, where);
  }
}

} // namespace pbf
