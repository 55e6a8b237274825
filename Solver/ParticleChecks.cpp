#include "ParticleChecks.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

namespace pbf
{
namespace
{

std::string format(const Vec3d& v)
{
  std::ostringstream out;
  out << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return out.str();
}

bool finite(const Vec3d& v)
{
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

} // namespace

void checkBatch(const Parameters& parameters, const ParticleBatch& batch)
{
  const std::size_t n = batch.position.size();
  if (batch.velocity.size() != n || batch.id.size() != n)
  {
    throw InvalidInput("particle arrays differ in length: " + std::to_string(n) + " positions, " +
      std::to_string(batch.velocity.size()) + " velocities, " + std::to_string(batch.id.size()) +
      " ids");
  }
  if (n >= std::numeric_limits<std::uint32_t>::max())
  {
    throw InvalidInput("particle count = " + std::to_string(n) + ": more than 32-bit indices hold");
  }
  // A particle within one spacing outside the box is a rounding matter and is projected inside by
  // the first collision step; farther out the scene and the domain disagree.
  const double slack = parameters.particleSpacing;
  const Box& d = parameters.domain;
  for (std::size_t i = 0; i < n; ++i)
  {
    const Vec3d& x = batch.position[i];
    if (!finite(x))
    {
      throw InvalidInput("position of particle " + std::to_string(i) + " = " + format(x) +
        ": must be finite");
    }
    if (!finite(batch.velocity[i]))
    {
      throw InvalidInput("velocity of particle " + std::to_string(i) + " = " +
        format(batch.velocity[i]) + ": must be finite");
    }
    if (x.x < d.min.x - slack || x.y < d.min.y - slack || x.z < d.min.z - slack ||
      x.x > d.max.x + slack || x.y > d.max.y + slack || x.z > d.max.z + slack)
    {
      throw InvalidInput("position of particle " + std::to_string(i) + " = " + format(x) +
        ": outside the domain " + format(d.min) + " - " + format(d.max));
    }
  }
}

} // namespace pbf
