// A scene's "liquids": their names and properties, their contact angles with the walls and the
// solids, and the liquid that a region or an emitter names.
#include "SceneJson.h"

namespace pbf::scenejson
{
namespace
{

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

} // namespace

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

} // namespace pbf::scenejson
