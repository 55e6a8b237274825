// Initial fluids of shapes the scene's boxes and spheres do not make (a spheroid, a hemisphere
// on the floor): the sites of the scene's lattice inside the shape, at rest, ids in order.
#pragma once

#include "Scene.h"

#include <cstdint>

namespace pbf::validation
{

// The sites of fillScene(scene) for which inside(x) holds.
template <class Inside>
ParticleBatch latticeSitesInside(const Scene& scene, const Parameters& parameters, Inside&& inside)
{
  const ParticleBatch lattice = fillScene(scene, withSceneDomain(parameters, scene));
  ParticleBatch batch;
  for (const Vec3d& x : lattice.position)
  {
    if (inside(x))
    {
      batch.position.push_back(x);
      batch.velocity.push_back({ 0, 0, 0 });
      batch.id.push_back(static_cast<std::int64_t>(batch.id.size()));
    }
  }
  return batch;
}

} // namespace pbf::validation
