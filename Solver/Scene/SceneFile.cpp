// A scene file's text into a Scene: the whole document's checks, its header, domain and fluid
// regions, the sections in their order (SceneJson.h), and the files and presets it comes from.
#include "SceneJson.h"

#include "PresetScenes.h"

#include <filesystem>
#include <fstream>
#include <sstream>

namespace pbf
{
namespace scenejson
{

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

} // namespace scenejson

namespace
{

using namespace scenejson;

// Deeper than any scene needs; bounds the recursion of dump() and of the checks.
constexpr int kMaxDepth = 16;

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

} // namespace pbf
