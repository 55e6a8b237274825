#include "SceneJson.h"

#include <cmath>

namespace pbf::scenejson
{

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
  Vec3d fallback)
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

} // namespace pbf::scenejson
