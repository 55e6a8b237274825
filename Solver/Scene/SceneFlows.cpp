// What enters and what leaves a scene: its "emitters" (nozzles releasing lattice layers) and its
// "outflows" (a face's slab or a box), as the file gives them and as a run's spacing makes them.
#include "SceneJson.h"

#include <algorithm>
#include <cmath>

namespace pbf
{
namespace
{

const char* const kFaceNames[6] = { "-x", "+x", "-y", "+y", "-z", "+z" };

double& component(Vec3d& v, int axis)
{
  return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}
double component(const Vec3d& v, int axis)
{
  return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}

} // namespace

namespace scenejson
{

// The emitters of a scene file's "emitters" array, into scene (whose domain is read).
void parseEmitters(const json& emitters, Scene& scene)
{
  for (std::size_t e = 0; e < emitters.size(); ++e)
  {
    const std::string path = ".emitters[" + std::to_string(e) + "]";
    const json& item = emitters[e];
    requireKeys(item, path,
      { "center", "direction", "radius", "speed", "rate", "start", "stop", "liquid" },
      { "center", "direction", "radius", "stop" });
    if (item.contains("speed") == item.contains("rate"))
    {
      if (item.contains("speed"))
      {
        reject(path + ".rate", item["rate"], "give speed or rate, not both");
      }
      throw InvalidInput("scene " + path + ".speed is missing (or give rate, in m^3/s)");
    }
    Emitter emitter;
    emitter.liquid = liquidOf(item, path, scene);
    emitter.center = vector3(item, path, "center");
    emitter.direction = vector3(item, path, "direction");
    // Scaled by the largest component first: |d| of [1e200, 0, 0] overflows and that of
    // [1e-200, 0, 0] underflows, yet both are the x axis.
    const Vec3d& d = emitter.direction;
    const double largest = std::max({ std::abs(d.x), std::abs(d.y), std::abs(d.z) });
    if (largest <= 0)
    {
      reject(path + ".direction", item["direction"], "must not be zero");
    }
    emitter.direction = { d.x / largest, d.y / largest, d.z / largest }; // not * (1 / x): 1 / 5e-324 overflows
    emitter.direction *= 1.0 / length(emitter.direction);
    emitter.radius = positive(item, path, "radius");
    if (item.contains("speed"))
    {
      emitter.speed = positive(item, path, "speed");
    }
    else
    {
      emitter.rate = positive(item, path, "rate");
    }
    emitter.start = item.contains("start") ? number(item, path, "start") : 0.0;
    emitter.stop = number(item, path, "stop");
    if (emitter.start < 0)
    {
      reject(path + ".start", item["start"], "must be >= 0");
    }
    if (emitter.stop <= emitter.start)
    {
      reject(path + ".stop", item["stop"], "must be later than start");
    }
    const Vec3d r{ emitter.radius, emitter.radius, emitter.radius };
    if (!inside(emitter.center - r, scene.domain) || !inside(emitter.center + r, scene.domain))
    {
      reject(path, item, "the nozzle must lie inside the domain");
    }
    scene.emitters.push_back(emitter);
  }
}

// "outflows": [{"face": "+x", "depth": 0.05}, {"min": [...], "max": [...]}].
void parseOutflows(const json& outflows, Scene& scene)
{
  if (!outflows.is_array())
  {
    reject(".outflows", outflows, "must be an array");
  }
  for (std::size_t k = 0; k < outflows.size(); ++k)
  {
    const std::string path = ".outflows[" + std::to_string(k) + "]";
    const json& item = outflows[k];
    requireKeys(item, path, { "face", "depth", "min", "max" }, {});
    Outflow outflow;
    if (item.contains("face"))
    {
      if (item.contains("min") || item.contains("max"))
      {
        reject(path, item, "give a face or a box (min and max), not both");
      }
      const json& face = item["face"];
      for (int f = 0; f < 6 && face.is_string(); ++f)
      {
        outflow.face = face.get<std::string>() == kFaceNames[f] ? f : outflow.face;
      }
      if (outflow.face < 0)
      {
        reject(path + ".face", face, "must be one of \"-x\", \"+x\", \"-y\", \"+y\", \"-z\", \"+z\"");
      }
      if (item.contains("depth"))
      {
        outflow.depth = positive(item, path, "depth");
        const int axis = outflow.face / 2;
        const double extent =
          component(scene.domain.max, axis) - component(scene.domain.min, axis);
        if (outflow.depth >= extent)
        {
          reject(path + ".depth", item["depth"],
            "the slab would cover the whole domain (its extent across the face is " +
              quote(json(extent)) + " m)");
        }
      }
    }
    else
    {
      if (item.contains("depth"))
      {
        reject(path + ".depth", item["depth"], "a depth belongs to a face");
      }
      if (!item.contains("min") || !item.contains("max"))
      {
        throw InvalidInput("scene " + path + " needs a face, or a box's min and max");
      }
      outflow.box.min = vector3(item, path, "min");
      outflow.box.max = vector3(item, path, "max");
      requireOrdered(outflow.box.min, outflow.box.max, path, item["max"]);
      const Box& d = scene.domain;
      const Box& b = outflow.box;
      if (b.max.x <= d.min.x || b.max.y <= d.min.y || b.max.z <= d.min.z || b.min.x >= d.max.x ||
        b.min.y >= d.max.y || b.min.z >= d.max.z)
      {
        reject(path, item, "the box lies outside the domain");
      }
      if (b.min.x <= d.min.x && b.min.y <= d.min.y && b.min.z <= d.min.z && b.max.x >= d.max.x &&
        b.max.y >= d.max.y && b.max.z >= d.max.z)
      {
        reject(path, item, "the box covers the whole domain: every particle would leave at once");
      }
    }
    scene.outflows.push_back(outflow);
  }
}

} // namespace scenejson

long emitterSites(const Emitter& emitter, double s)
{
  const long n = static_cast<long>(std::floor(emitter.radius / s));
  long sites = 0;
  for (long a = -n; a <= n; ++a)
  {
    for (long b = -n; b <= n; ++b)
    {
      sites += (a * a + b * b) * s * s <= emitter.radius * emitter.radius ? 1 : 0;
    }
  }
  return sites;
}

double emitterSpeed(const Emitter& emitter, const Parameters& parameters)
{
  if (emitter.speed > 0)
  {
    return emitter.speed;
  }
  const double s = parameters.particleSpacing;
  return emitter.rate / (static_cast<double>(emitterSites(emitter, s)) * s * s);
}

std::vector<Box> outflowZones(const Scene& scene, const Parameters& parameters)
{
  const double slack = parameters.particleSpacing;
  std::vector<Box> zones;
  for (const Outflow& outflow : scene.outflows)
  {
    if (outflow.face < 0)
    {
      zones.push_back(outflow.box);
      continue;
    }
    Box slab = scene.domain;
    slab.min -= Vec3d{ slack, slack, slack };
    slab.max += Vec3d{ slack, slack, slack };
    const int axis = outflow.face / 2;
    const double depth = outflow.depth > 0 ? outflow.depth : parameters.smoothingLength();
    if (outflow.face % 2 == 0)
    {
      component(slab.max, axis) = component(scene.domain.min, axis) + depth;
    }
    else
    {
      component(slab.min, axis) = component(scene.domain.max, axis) - depth;
    }
    zones.push_back(slab);
  }
  return zones;
}

std::string outflowName(const Scene& scene, std::size_t k)
{
  const Outflow& outflow = scene.outflows[k];
  return "outflows[" + std::to_string(k) + "] (" +
    (outflow.face < 0 ? std::string("box") : "face " + std::string(kFaceNames[outflow.face])) + ")";
}

} // namespace pbf
