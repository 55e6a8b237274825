#include "Scene.h"

#include "PresetScenes.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace pbf
{
namespace
{

using nlohmann::json;

// Deeper than any scene needs; bounds the recursion of dump() and of the checks.
constexpr int kMaxDepth = 16;

// The value as the message quotes it: long values are cut, a message stays readable.
std::string quote(const json& value)
{
  constexpr std::size_t limit = 120;
  std::string text = value.dump(-1, ' ', false, json::error_handler_t::replace);
  if (text.size() > limit)
  {
    text = text.substr(0, limit) + "... (" + std::to_string(text.size()) + " characters)";
  }
  return text;
}

[[noreturn]] void reject(const std::string& path, const json& value, const std::string& rule)
{
  throw InvalidInput("scene " + path + " = " + quote(value) + ": " + rule);
}

void requireKeys(const json& object, const std::string& path, const std::set<std::string>& allowed,
  const std::set<std::string>& required)
{
  if (!object.is_object())
  {
    reject(path, object, "must be an object");
  }
  for (const auto& item : object.items())
  {
    if (!allowed.count(item.key()))
    {
      std::string list;
      for (const auto& key : allowed)
      {
        list += (list.empty() ? "" : ", ") + key;
      }
      reject(path + "." + item.key(), item.value(), "unknown key (allowed: " + list + ")");
    }
  }
  for (const auto& key : required)
  {
    if (!object.contains(key))
    {
      throw InvalidInput("scene " + path + "." + key + " is missing");
    }
  }
}

double number(const json& object, const std::string& path, const std::string& key)
{
  const json& value = object.at(key);
  if (!value.is_number())
  {
    reject(path + "." + key, value, "must be a number");
  }
  const double d = value.get<double>();
  if (!std::isfinite(d))
  {
    reject(path + "." + key, value, "must be finite");
  }
  return d;
}

double positive(const json& object, const std::string& path, const std::string& key)
{
  const double d = number(object, path, key);
  if (d <= 0)
  {
    reject(path + "." + key, object.at(key), "must be > 0");
  }
  return d;
}

Vec3d vector3(const json& object, const std::string& path, const std::string& key,
  Vec3d fallback = { 0, 0, 0 })
{
  if (!object.contains(key))
  {
    return fallback;
  }
  const json& value = object.at(key);
  if (!value.is_array() || value.size() != 3)
  {
    reject(path + "." + key, value, "must be an array of 3 numbers");
  }
  double c[3];
  for (int a = 0; a < 3; ++a)
  {
    if (!value[a].is_number() || !std::isfinite(value[a].get<double>()))
    {
      reject(path + "." + key, value, "must be an array of 3 finite numbers");
    }
    c[a] = value[a].get<double>();
  }
  return { c[0], c[1], c[2] };
}

void requireOrdered(const Vec3d& lo, const Vec3d& hi, const std::string& path, const json& value)
{
  if (!(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z))
  {
    reject(path + ".max", value, "must exceed min along every axis");
  }
}

bool inside(const Vec3d& p, const Box& box)
{
  return p.x >= box.min.x && p.y >= box.min.y && p.z >= box.min.z && p.x <= box.max.x &&
    p.y <= box.max.y && p.z <= box.max.z;
}

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
    if (!item.is_object() || !item.contains("type") || !item["type"].is_string())
    {
      reject(path + ".type", item.is_object() && item.contains("type") ? item["type"] : json(),
        "each obstacle needs a type, \"box\", \"sphere\" or \"mesh\"");
    }
    const std::string type = item["type"].get<std::string>();
    SolidRegion solid;
    if (type == "box")
    {
      requireKeys(item, path, { "type", "name", "min", "max", "motion", "density", "contactAngle" }, { "min", "max" });
      solid.kind = SolidRegion::Kind::Box;
      solid.box = { vector3(item, path, "min"), vector3(item, path, "max") };
      requireOrdered(solid.box.min, solid.box.max, path, item["max"]);
    }
    else if (type == "sphere")
    {
      requireKeys(item, path, { "type", "name", "center", "radius", "motion", "density", "contactAngle" }, { "center", "radius" });
      solid.kind = SolidRegion::Kind::Sphere;
      solid.center = vector3(item, path, "center");
      solid.radius = positive(item, path, "radius");
    }
    else if (type == "mesh")
    {
      requireKeys(item, path, { "type", "name", "file", "thickness", "motion", "density", "contactAngle" }, { "file" });
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
    solids.push_back(solid);
  }
  return solids;
}

// A liquid's "contactAngles": {"walls": 60}: its contact angle [degrees] with the domain's walls;
// a key naming a solid is checked by parse() (requireContactSolids).
void parseContactAngles(const json& angles, const std::string& path, Liquid& liquid)
{
  if (!angles.is_object() || angles.empty())
  {
    reject(path, angles, "must be an object of contact angles [degrees] by solid name (\"walls\": "
      "the domain's walls)");
  }
  for (auto it = angles.begin(); it != angles.end(); ++it)
  {
    const double theta = number(angles, path, it.key());
    if (!(theta >= 0.0 && theta <= 180.0))
    {
      reject(path + "." + it.key(), it.value(), "must lie in [0, 180] [degrees]");
    }
    if (it.key() == "walls")
    {
      liquid.wallContactAngle = theta;
    }
  }
}

// "liquids": [{"name": "water", "restDensity": 1000, "xsphViscosity": 0.0125,
// "surfaceTension": 0.072, "contactAngles": {"walls": 60}}, ...]: the
// scene's liquids, which its regions and emitters name.
std::vector<Liquid> parseLiquids(const json& liquids)
{
  if (!liquids.is_array() || liquids.empty() || liquids.size() > std::size_t(kMaxLiquids))
  {
    reject(".liquids", liquids,
      "must be an array of 1 to " + std::to_string(kMaxLiquids) + " liquids");
  }
  std::vector<Liquid> out;
  for (std::size_t k = 0; k < liquids.size(); ++k)
  {
    const std::string path = ".liquids[" + std::to_string(k) + "]";
    const json& item = liquids[k];
    requireKeys(item, path,
      { "name", "restDensity", "xsphViscosity", "surfaceTension", "contactAngles" },
      { "name", "restDensity" });
    if (!item["name"].is_string() || item["name"].get<std::string>().empty())
    {
      reject(path + ".name", item["name"], "must be a non-empty string");
    }
    Liquid liquid;
    liquid.name = item["name"].get<std::string>();
    for (const Liquid& earlier : out)
    {
      if (earlier.name == liquid.name)
      {
        reject(path + ".name", item["name"], "another liquid has this name");
      }
    }
    liquid.restDensity = positive(item, path, "restDensity");
    if (item.contains("xsphViscosity"))
    {
      liquid.xsphViscosity = number(item, path, "xsphViscosity");
      if (liquid.xsphViscosity < 0)
      {
        reject(path + ".xsphViscosity", item["xsphViscosity"], "must be >= 0");
      }
    }
    if (item.contains("surfaceTension"))
    {
      liquid.surfaceTension = number(item, path, "surfaceTension");
      if (liquid.surfaceTension < 0)
      {
        reject(path + ".surfaceTension", item["surfaceTension"], "must be >= 0");
      }
    }
    if (item.contains("contactAngles"))
    {
      parseContactAngles(item["contactAngles"], path + ".contactAngles", liquid);
    }
    out.push_back(liquid);
  }
  return out;
}

// The index in scene.liquids of the liquid that item's "liquid" names; 0 without the key.
int liquidOf(const json& item, const std::string& path, const Scene& scene)
{
  if (!item.contains("liquid"))
  {
    return 0;
  }
  const json& name = item["liquid"];
  std::string known;
  for (std::size_t l = 0; l < scene.liquids.size(); ++l)
  {
    if (name.is_string() && name.get<std::string>() == scene.liquids[l].name)
    {
      return static_cast<int>(l);
    }
    known += (known.empty() ? "" : ", ") + scene.liquids[l].name;
  }
  reject(path + ".liquid", name,
    scene.liquids.empty() ? "the scene has no \"liquids\" to name"
                          : "unknown liquid (the scene's: " + known + ")");
}

// The fluid regions of a scene file's "fluid" array, into scene (whose domain and liquids are
// read).
void parseFluidRegions(const json& fluid, Scene& scene)
{
  for (std::size_t r = 0; r < fluid.size(); ++r)
  {
    const std::string path = ".fluid[" + std::to_string(r) + "]";
    const json& region = fluid[r];
    if (!region.is_object() || !region.contains("type") || !region["type"].is_string())
    {
      reject(path + ".type", region.is_object() && region.contains("type") ? region["type"] : json(),
        "each fluid region needs a type, \"box\" or \"sphere\"");
    }
    const std::string type = region["type"].get<std::string>();
    if (type == "box")
    {
      requireKeys(region, path, { "type", "min", "max", "velocity", "liquid" }, { "min", "max" });
      FluidBox box{ vector3(region, path, "min"), vector3(region, path, "max"),
        vector3(region, path, "velocity"), liquidOf(region, path, scene) };
      requireOrdered(box.min, box.max, path, region["max"]);
      if (!inside(box.min, scene.domain) || !inside(box.max, scene.domain))
      {
        reject(path, region, "the box must lie inside the domain");
      }
      scene.boxes.push_back(box);
    }
    else if (type == "sphere")
    {
      requireKeys(
        region, path, { "type", "center", "radius", "velocity", "liquid" }, { "center", "radius" });
      FluidSphere sphere{ vector3(region, path, "center"), positive(region, path, "radius"),
        vector3(region, path, "velocity"), liquidOf(region, path, scene) };
      const Vec3d r{ sphere.radius, sphere.radius, sphere.radius };
      if (!inside(sphere.center - r, scene.domain) || !inside(sphere.center + r, scene.domain))
      {
        reject(path, region, "the sphere must lie inside the domain");
      }
      scene.spheres.push_back(sphere);
    }
    else
    {
      reject(path + ".type", region["type"], "must be \"box\" or \"sphere\"");
    }
  }

}

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

const char* const kFaceNames[6] = { "-x", "+x", "-y", "+y", "-z", "+z" };

double& component(Vec3d& v, int axis)
{
  return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}
double component(const Vec3d& v, int axis)
{
  return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
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

// Every solid a liquid's "contactAngles" names is one of the scene's "obstacles", and takes that
// angle for that liquid.
void requireContactSolids(const json& root, Scene& scene)
{
  std::string known;
  for (const SolidRegion& solid : scene.solids)
  {
    known += solid.name.empty() ? "" : (known.empty() ? "" : ", ") + solid.name;
  }
  if (!root.contains("liquids"))
  {
    return;
  }
  for (std::size_t l = 0; l < scene.liquids.size(); ++l)
  {
    const json& item = root["liquids"][l];
    if (!item.contains("contactAngles"))
    {
      continue;
    }
    for (auto it = item["contactAngles"].begin(); it != item["contactAngles"].end(); ++it)
    {
      const std::string& name = it.key();
      if (name == "walls")
      {
        continue;
      }
      bool found = false;
      for (SolidRegion& solid : scene.solids)
      {
        if (solid.name == name)
        {
          // parseContactAngles checked the range.
          solid.contactAngle[l] = it.value().get<double>();
          found = true;
        }
      }
      if (!found)
      {
        const std::string path = ".liquids[" + std::to_string(l) + "].contactAngles." + name;
        reject(path, it.value(),
          "no solid of the scene's \"obstacles\" has this name (named solids: " +
            (known.empty() ? std::string("none") : known) + "; \"walls\" names the domain's walls)");
      }
    }
  }
}

Scene parse(const json& root)
{
  requireKeys(root, "",
    { "name", "description", "domain", "liquids", "fluid", "emitters", "outflows", "obstacles" },
    { "domain", "fluid" });
  Scene scene;
  if (root.contains("name"))
  {
    if (!root["name"].is_string())
    {
      reject(".name", root["name"], "must be a string");
    }
    scene.name = root["name"].get<std::string>();
  }
  if (root.contains("description"))
  {
    if (!root["description"].is_string())
    {
      reject(".description", root["description"], "must be a string");
    }
    scene.description = root["description"].get<std::string>();
  }

  const json& domain = root["domain"];
  requireKeys(domain, ".domain", { "min", "max" }, { "min", "max" });
  scene.domain.min = vector3(domain, ".domain", "min");
  scene.domain.max = vector3(domain, ".domain", "max");
  requireOrdered(scene.domain.min, scene.domain.max, ".domain", domain["max"]);

  if (root.contains("liquids"))
  {
    scene.liquids = parseLiquids(root["liquids"]);
  }
  const json& fluid = root["fluid"];
  if (!fluid.is_array())
  {
    reject(".fluid", fluid, "must be an array of regions");
  }
  parseFluidRegions(fluid, scene);

  if (root.contains("emitters"))
  {
    const json& emitters = root["emitters"];
    if (!emitters.is_array())
    {
      reject(".emitters", emitters, "must be an array");
    }
    parseEmitters(emitters, scene);
  }
  if (scene.boxes.empty() && scene.spheres.empty() && scene.emitters.empty())
  {
    reject(".fluid", fluid, "the scene has no fluid region and no emitter");
  }
  if (root.contains("outflows"))
  {
    parseOutflows(root["outflows"], scene);
  }
  if (root.contains("obstacles"))
  {
    scene.solids = parseObstacles(root["obstacles"]);
  }
  requireContactSolids(root, scene);
  return scene;
}

// Lattice sites min + s (i + 1/2) inside [min, max]: the fluid stays s/2 from the region's faces.
// The region's liquid goes with each site where the scene names liquids (`liquids`).
} // namespace

Scene parseScene(const std::string& text)
{
  json root;
  try
  {
    // The parser is iterative; deep nesting is refused while parsing, before anything recurses.
    root = json::parse(text, [](int depth, json::parse_event_t, json&) {
      if (depth > kMaxDepth)
      {
        throw InvalidInput("scene is nested deeper than " + std::to_string(kMaxDepth) +
          " levels: not a scene");
      }
      return true;
    });
  }
  catch (const json::exception& error)
  {
    // parse_error for bad syntax, out_of_range for a number beyond double (1e400).
    throw InvalidInput(std::string("scene is not valid JSON: ") + error.what());
  }
  return parse(root);
}

Scene loadSceneFile(const std::string& path)
{
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
  {
    throw InvalidInput("scene file = \"" + path + "\": is a folder, not a file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in)
  {
    throw InvalidInput("scene file = \"" + path + "\": cannot be opened");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad())
  {
    throw InvalidInput("scene file = \"" + path + "\": cannot be read");
  }
  if (text.str().empty())
  {
    throw InvalidInput("scene file = \"" + path + "\": is empty");
  }
  Scene scene;
  try
  {
    scene = parseScene(text.str());
  }
  catch (const InvalidInput& error)
  {
    throw InvalidInput("scene file \"" + path + "\": " + error.what());
  }
  // A mesh's file is named relative to the scene file, so that a scene and its parts move
  // together.
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  for (SolidRegion& solid : scene.solids)
  {
    if (!solid.file.empty() && std::filesystem::path(solid.file).is_relative())
    {
      solid.file = (folder / solid.file).lexically_normal().string();
    }
  }
  return scene;
}

std::vector<std::string> presetNames()
{
  std::vector<std::string> names;
  for (std::size_t i = 0; i < kPresetSceneCount; ++i)
  {
    names.emplace_back(kPresetScenes[i].name);
  }
  return names;
}

Scene presetScene(const std::string& name)
{
  std::string known;
  for (std::size_t i = 0; i < kPresetSceneCount; ++i)
  {
    if (name == kPresetScenes[i].name)
    {
      return parseScene(kPresetScenes[i].json);
    }
    known += (known.empty() ? "" : ", ") + std::string(kPresetScenes[i].name);
  }
  throw InvalidInput("preset = \"" + name + "\": unknown (known: " + known + ")");
}

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
