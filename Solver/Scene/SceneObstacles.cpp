// A scene's "obstacles": the solids the fluid flows around, their shapes, names, contact angles,
// and how they move (keyframes) or are moved (a density: a body the fluid moves).
#include "SceneJson.h"

#include <array>
#include <cmath>

namespace pbf::scenejson
{
namespace
{

// An obstacle's "motion": {"pivot": [x, y, z], "keyframes": [{"time": t, "translation": [...],
// "rotation": [degrees about x, y, z]}, ...]}: the pivot (default: the centre of the solid's
// bounds, filled in by solidFields) is carried by the translation and the solid turns about it.
SolidMotion parseMotion(const json& motion, const std::string& path)
{
  requireKeys(motion, path, { "pivot", "keyframes" }, { "keyframes" });
  SolidMotion m;
  m.pivot = vector3(motion, path, "pivot", { std::nan(""), 0, 0 });
  const json& frames = motion["keyframes"];
  constexpr std::size_t kMostKeyframes = 100000;
  if (!frames.is_array() || frames.empty() || frames.size() > kMostKeyframes)
  {
    reject(path + ".keyframes", frames,
      "must be an array of 1 to " + std::to_string(kMostKeyframes) + " keyframes");
  }
  for (std::size_t k = 0; k < frames.size(); ++k)
  {
    const std::string at = path + ".keyframes[" + std::to_string(k) + "]";
    const json& frame = frames[k];
    requireKeys(frame, at, { "time", "translation", "rotation" }, { "time" });
    Keyframe key;
    key.time = number(frame, at, "time");
    if (k > 0 && !(key.time > m.keyframes.back().time))
    {
      reject(at + ".time", frame["time"], "keyframe times must increase");
    }
    key.translation = vector3(frame, at, "translation");
    key.rotation = Rotation::fromDegrees(vector3(frame, at, "rotation"));
    m.keyframes.push_back(key);
  }
  return m;
}

// An obstacle's "type" and the keys of its shape.
SolidRegion parseObstacleShape(const json& item, const std::string& path)
{
  if (!item.is_object() || !item.contains("type") || !item["type"].is_string())
  {
    reject(path + ".type", item.is_object() && item.contains("type") ? item["type"] : json(),
      "each obstacle needs a type, \"box\", \"sphere\" or \"mesh\"");
  }
  const std::string type = item["type"].get<std::string>();
  SolidRegion solid;
  if (type == "box")
  {
    requireKeys(item, path, { "type", "name", "min", "max", "motion", "density", "contactAngle",
      "degreesOfFreedom", "release" }, { "min", "max" });
    solid.kind = SolidRegion::Kind::Box;
    solid.box = { vector3(item, path, "min"), vector3(item, path, "max") };
    requireOrdered(solid.box.min, solid.box.max, path, item["max"]);
  }
  else if (type == "sphere")
  {
    requireKeys(item, path, { "type", "name", "center", "radius", "motion", "density", "contactAngle",
      "degreesOfFreedom", "release" }, { "center", "radius" });
    solid.kind = SolidRegion::Kind::Sphere;
    solid.center = vector3(item, path, "center");
    solid.radius = positive(item, path, "radius");
  }
  else if (type == "mesh")
  {
    requireKeys(item, path, { "type", "name", "file", "thickness", "motion", "density", "contactAngle",
      "degreesOfFreedom", "release" }, { "file" });
    if (!item["file"].is_string() || item["file"].get<std::string>().empty())
    {
      reject(path + ".file", item["file"], "must be the path of an STL, OBJ, PLY or VTP file");
    }
    solid.kind = SolidRegion::Kind::Mesh;
    solid.file = item["file"].get<std::string>();
    solid.thickness = item.contains("thickness") ? number(item, path, "thickness") : 0.0;
    if (!(solid.thickness >= 0))
    {
      reject(path + ".thickness", item["thickness"], "must be >= 0 (0: a closed surface)");
    }
  }
  else
  {
    reject(path + ".type", item["type"], "must be \"box\", \"sphere\" or \"mesh\"");
  }
  return solid;
}

// A body's "degreesOfFreedom" (the axes its centre moves along, and "rotation" if it turns; all
// when absent) and "release" (the time it is held until); both for bodies only.
void parseBodyFreedoms(const json& item, const std::string& path, SolidRegion& solid)
{
  for (const char* key : { "degreesOfFreedom", "release" })
  {
    if (item.contains(key) && !item.contains("density"))
    {
      reject(path + "." + key, item[key], "applies to a body the fluid moves (give its density)");
    }
  }
  if (item.contains("degreesOfFreedom"))
  {
    const json& list = item["degreesOfFreedom"];
    const char* const names[4] = { "x", "y", "z", "rotation" };
    const std::string rule = "must be a list of distinct \"x\", \"y\", \"z\", \"rotation\"";
    if (!list.is_array())
    {
      reject(path + ".degreesOfFreedom", list, rule);
    }
    std::array<bool, 4> free{ false, false, false, false };
    for (const json& name : list)
    {
      int which = -1;
      for (int k = 0; k < 4 && name.is_string(); ++k)
      {
        which = name.get<std::string>() == names[k] ? k : which;
      }
      if (which < 0 || free[static_cast<std::size_t>(which)])
      {
        reject(path + ".degreesOfFreedom", list, rule);
      }
      free[static_cast<std::size_t>(which)] = true;
    }
    solid.freeAxes = { free[0], free[1], free[2] };
    solid.turns = free[3];
  }
  if (item.contains("release"))
  {
    solid.release = number(item, path, "release");
    if (!(solid.release >= 0) || !std::isfinite(solid.release))
    {
      reject(path + ".release", item["release"], "must be a finite time >= 0 [s]");
    }
  }
}

// An obstacle's keys beyond its shape: its name, motion, contact angle and density.
void parseObstacleProperties(const json& item, const std::string& path, SolidRegion& solid)
{
  if (item.contains("name"))
  {
    // What the Diagnostics table's load columns and the errors call it.
    if (!item["name"].is_string() || item["name"].get<std::string>().empty())
    {
      reject(path + ".name", item["name"], "must be a non-empty string");
    }
    solid.name = item["name"].get<std::string>();
  }
  if (item.contains("motion"))
  {
    solid.motion = parseMotion(item["motion"], path + ".motion");
  }
  if (item.contains("contactAngle"))
  {
    // Every liquid's, unless a liquid's "contactAngles" names this solid.
    const double theta = number(item, path, "contactAngle");
    if (!(theta >= 0.0 && theta <= 180.0))
    {
      reject(path + ".contactAngle", item["contactAngle"], "must lie in [0, 180] [degrees]");
    }
    solid.contactAngle.fill(theta);
  }
  if (item.contains("density"))
  {
    // A body the fluid moves: what it weighs, not how it is moved.
    solid.density = number(item, path, "density");
    if (!(solid.density > 0) || !std::isfinite(solid.density))
    {
      reject(path + ".density", item["density"],
        "must be a finite number > 0 [kg/m^3] (a body the fluid moves)");
    }
    if (item.contains("motion"))
    {
      reject(path + ".density", item["density"],
        "an obstacle is moved either by the fluid (density) or by its keyframes (motion), not both");
    }
  }
  parseBodyFreedoms(item, path, solid);
}

} // namespace

// "obstacles": [{"type": "box", "min": [...], "max": [...]}, {"type": "sphere", "center": [...],
// "radius": r}, {"type": "mesh", "file": "part.stl", "thickness": t}]. Where they lie against the
// domain is checked when the run is built (solidFields); a mesh file is read there by the
// ParaView plugin's VTK readers (STL, OBJ, PLY, VTP), its path relative to the scene file.
std::vector<SolidRegion> parseObstacles(const json& obstacles)
{
  if (!obstacles.is_array())
  {
    reject(".obstacles", obstacles, "must be an array of solids");
  }
  // Each solid is one distance lookup per particle per pass: a few describe a scene, hundreds
  // would be a mesh, which is what a mesh obstacle is for.
  constexpr std::size_t kMostObstacles = 64;
  if (obstacles.size() > kMostObstacles)
  {
    reject(".obstacles", json(obstacles.size()),
      "at most " + std::to_string(kMostObstacles) + " obstacles");
  }
  std::vector<SolidRegion> solids;
  for (std::size_t k = 0; k < obstacles.size(); ++k)
  {
    const std::string path = ".obstacles[" + std::to_string(k) + "]";
    const json& item = obstacles[k];
    SolidRegion solid = parseObstacleShape(item, path);
    parseObstacleProperties(item, path, solid);
    solids.push_back(solid);
  }
  return solids;
}

} // namespace pbf::scenejson
