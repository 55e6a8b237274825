// A scene's fluid on the lattice at a run's spacing: the sites of its regions, their count, and
// the initial particles. Reading scene files: SceneFile.cpp and the files of its sections.
#include "Scene.h"

#include <cmath>

namespace pbf
{

double estimateParticleCount(const Scene& scene, const Parameters& parameters)
{
  const double s = parameters.particleSpacing;
  double count = 0;
  for (const FluidBox& b : scene.boxes)
  {
    count += std::floor((b.max.x - b.min.x) / s + 1e-9) * std::floor((b.max.y - b.min.y) / s + 1e-9) *
      std::floor((b.max.z - b.min.z) / s + 1e-9);
  }
  for (const FluidSphere& sphere : scene.spheres)
  {
    count += std::pow(2 * std::floor(sphere.radius / s) + 1, 3);
  }
  for (const Emitter& e : scene.emitters)
  {
    const double perLayer = std::pow(2 * std::floor(e.radius / s) + 1, 2);
    count += e.speed > 0 ? perLayer * std::ceil((e.stop - e.start) * e.speed / s)
                         : e.rate * (e.stop - e.start) / (s * s * s) + perLayer;
  }
  return count;
}

// Lattice sites min + s (i + 1/2) inside [min, max]: the fluid stays s/2 from the region's faces.
// The region's liquid goes with each site where the scene names liquids (`liquids`).
void forEachSceneSite(const Scene& scene, double s,
  const std::function<void(const Vec3d&, const Vec3d&, std::uint8_t)>& site)
{
  const auto count = [s](double lo, double hi) {
    return static_cast<long>(std::floor((hi - lo) / s + 1e-9));
  };
  for (const FluidBox& box : scene.boxes)
  {
    const long nx = count(box.min.x, box.max.x);
    const long ny = count(box.min.y, box.max.y);
    const long nz = count(box.min.z, box.max.z);
    const auto liquid = static_cast<std::uint8_t>(box.liquid);
    for (long k = 0; k < nz; ++k)
    {
      for (long j = 0; j < ny; ++j)
      {
        for (long i = 0; i < nx; ++i)
        {
          site({ box.min.x + s * (i + 0.5), box.min.y + s * (j + 0.5), box.min.z + s * (k + 0.5) },
            box.velocity, liquid);
        }
      }
    }
  }
  for (const FluidSphere& sphere : scene.spheres)
  {
    const long n = static_cast<long>(std::floor(sphere.radius / s));
    const auto liquid = static_cast<std::uint8_t>(sphere.liquid);
    for (long k = -n; k <= n; ++k)
    {
      for (long j = -n; j <= n; ++j)
      {
        for (long i = -n; i <= n; ++i)
        {
          const Vec3d offset{ s * i, s * j, s * k };
          if (dot(offset, offset) <= sphere.radius * sphere.radius)
          {
            site(sphere.center + offset, sphere.velocity, liquid);
          }
        }
      }
    }
  }
}

void checkSceneSize(const Scene& scene, const Parameters& parameters)
{
  parameters.validate(); // the spacing sizes every loop of a fill
  const double estimate = estimateParticleCount(scene, parameters);
  if (!(estimate <= static_cast<double>(kMaxParticles)))
  {
    throw InvalidInput("particleSpacing = " + std::to_string(parameters.particleSpacing) +
      ": scene \"" + scene.name + "\" would hold about " + std::to_string(estimate) +
      " particles, more than the " + std::to_string(kMaxParticles) + " supported");
  }
}

ParticleBatch fillScene(const Scene& scene, const Parameters& parameters)
{
  checkSceneSize(scene, parameters);
  ParticleBatch batch;
  const bool liquids = !scene.liquids.empty();
  forEachSceneSite(scene, parameters.particleSpacing,
    [&](const Vec3d& x, const Vec3d& v, std::uint8_t liquid) {
      batch.id.push_back(static_cast<std::int64_t>(batch.position.size()));
      batch.position.push_back(x);
      batch.velocity.push_back(v);
      if (liquids)
      {
        batch.liquid.push_back(liquid);
      }
    });
  return batch;
}

Parameters withSceneDomain(Parameters parameters, const Scene& scene)
{
  parameters.domain = scene.domain;
  parameters.liquids = scene.liquids;
  return parameters;
}

} // namespace pbf
