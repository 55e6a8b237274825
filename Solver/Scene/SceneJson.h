// The reading of a scene file (parseScene), shared by the parsers of its sections: the checks of
// its JSON values, each failing with InvalidInput that names the key path and the value, and the
// sections' parsers in the order parseScene calls them. Private to Solver/Scene/.
#pragma once

#include "Scene.h"

#include <nlohmann/json.hpp>

#include <set>
#include <string>
#include <vector>

namespace pbf::scenejson
{

using nlohmann::json;

std::string quote(const json& value);

[[noreturn]] void reject(const std::string& path, const json& value, const std::string& rule);

void requireKeys(const json& object, const std::string& path, const std::set<std::string>& allowed,
  const std::set<std::string>& required);

double number(const json& object, const std::string& path, const std::string& key);

double positive(const json& object, const std::string& path, const std::string& key);

Vec3d vector3(const json& object, const std::string& path, const std::string& key,
  Vec3d fallback = { 0, 0, 0 });

void requireOrdered(const Vec3d& lo, const Vec3d& hi, const std::string& path, const json& value);

bool inside(const Vec3d& p, const Box& box);

// SceneLiquids.cpp: the liquids, and the index of the one an item names.
std::vector<Liquid> parseLiquids(const json& liquids);
int liquidOf(const json& item, const std::string& path, const Scene& scene);
void requireContactSolids(const json& root, Scene& scene);

// SceneFile.cpp: the fluid regions.
void parseFluidRegions(const json& fluid, Scene& scene);

// SceneFlows.cpp: what enters and what leaves.
void parseEmitters(const json& emitters, Scene& scene);
void parseOutflows(const json& outflows, Scene& scene);

// SceneObstacles.cpp: the solids and their motions.
std::vector<SolidRegion> parseObstacles(const json& obstacles);

} // namespace pbf::scenejson
