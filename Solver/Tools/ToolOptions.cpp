#include "ToolOptions.h"

#include "ParameterTable.h"

#include <cmath>
#include <functional>
#include <sstream>

namespace pbf
{
namespace
{

// Callers name the option: the message says only what is wrong with the text.
double toNumber(const std::string& text)
{
  std::size_t used = 0;
  double value = 0;
  try
  {
    value = std::stod(text, &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (used != text.size() || text.empty())
  {
    throw InvalidInput("not a number");
  }
  return value;
}

using Setter = std::function<void(ToolOptions&, const std::string&)>;

// "--option value" for a row of the parameter table: a number (a whole one for a count, 0 or 1
// for a switch), or x,y,z for a vector.
Setter tableSetter(const ParameterSpec& spec)
{
  return [&spec](ToolOptions& o, const std::string& v) {
    std::vector<double> values;
    std::stringstream in(v);
    for (std::string item; std::getline(in, item, ',');)
    {
      values.push_back(toNumber(item));
    }
    if (static_cast<int>(values.size()) != spec.components())
    {
      throw InvalidInput(spec.components() == 3 ? "must be three numbers x,y,z" : "not a number");
    }
    if (spec.type == ParameterType::Integer &&
      (values[0] != std::floor(values[0]) || std::abs(values[0]) > 1e9))
    {
      // Converting beyond int is undefined.
      throw InvalidInput("not a whole number (" + spec.valid.rule() + ")");
    }
    for (int c = 0; c < spec.components(); ++c)
    {
      spec.set(o.parameters, c, values[static_cast<std::size_t>(c)]);
    }
  };
}

std::map<std::string, std::pair<std::string, Setter>> parameterSetters()
{
  std::map<std::string, std::pair<std::string, Setter>> setters;
  for (const ParameterSpec& spec : parameterTable())
  {
    std::string help = spec.label;
    if (spec.unit[0] != '\0')
    {
      help += std::string(" [") + spec.unit + "]";
    }
    help += std::string(" (") + spec.field + "; " + spec.valid.rule() + ")";
    setters[spec.option] = { help, tableSetter(spec) };
  }
  setters["time-stepping"] = { "auto | fixed", [](ToolOptions& o, const std::string& v) {
                                if (v != "auto" && v != "fixed")
                                {
                                  throw InvalidInput("must be auto or fixed");
                                }
                                o.parameters.timeStepping =
                                  v == "auto" ? TimeStepping::Automatic : TimeStepping::Fixed;
                              } };
  setters["scene"] = { "preset name or .json path",
    [](ToolOptions& o, const std::string& v) { o.scene = v; } };
  setters["backend"] = { "serial | openmp | cuda",
    [](ToolOptions& o, const std::string& v) { o.backend = parseBackend(v); } };
  setters["precision"] = { "single | double", [](ToolOptions& o, const std::string& v) {
                            if (v != "single" && v != "double")
                            {
                              throw InvalidInput(
                                "--precision = \"" + v + "\": must be single or double");
                            }
                            o.precision = v == "single" ? Precision::Single : Precision::Double;
                          } };
  return setters;
}

} // namespace

Scene toolScene(const ToolOptions& options)
{
  return options.scene.find(".json") != std::string::npos ? loadSceneFile(options.scene)
                                                          : presetScene(options.scene);
}

Backend parseBackend(const std::string& name)
{
  if (name == "serial")
  {
    return Backend::Serial;
  }
  if (name == "openmp")
  {
    return Backend::OpenMP;
  }
  if (name == "cuda")
  {
    return Backend::CUDA;
  }
  throw InvalidInput("--backend = \"" + name + "\": must be serial, openmp or cuda");
}

ToolOptions parseToolOptions(
  int argc, char** argv, const std::map<std::string, std::string>& toolKeys)
{
  ToolOptions options;
  const auto setters = parameterSetters();
  for (int a = 1; a < argc; a += 2)
  {
    const std::string flag = argv[a];
    if (flag.rfind("--", 0) != 0 || a + 1 >= argc)
    {
      throw InvalidInput("argument \"" + flag + "\": expected --key value\n" + toolUsage(toolKeys));
    }
    const std::string key = flag.substr(2);
    const std::string value = argv[a + 1];
    options.given.insert(key);
    if (auto it = setters.find(key); it != setters.end())
    {
      try
      {
        it->second.second(options, value);
      }
      catch (const InvalidInput& error)
      {
        throw InvalidInput("--" + key + " = \"" + value + "\": " + error.what());
      }
    }
    else if (toolKeys.count(key))
    {
      options.extra[key] = value;
    }
    else
    {
      throw InvalidInput("unknown option --" + key + "\n" + toolUsage(toolKeys));
    }
  }
  return options;
}

void usePaperIterationsUnlessGiven(ToolOptions& options)
{
  if (!options.given.count("tolerance"))
  {
    options.parameters.densityErrorTolerance = 0;
  }
  if (!options.given.count("iterations"))
  {
    options.parameters.solverIterations = 4;
  }
}

std::vector<double> toolReals(const ToolOptions& options, const std::string& key, double fallback)
{
  const auto it = options.extra.find(key);
  if (it == options.extra.end())
  {
    return { fallback };
  }
  std::vector<double> out;
  std::stringstream in(it->second);
  std::string item;
  while (std::getline(in, item, ','))
  {
    double value = std::nan("");
    try
    {
      value = toNumber(item);
    }
    catch (const InvalidInput&)
    {
    }
    if (!(value > 0) || !std::isfinite(value))
    {
      throw InvalidInput("--" + key + " = \"" + it->second +
        "\": must be a positive number (or a comma-separated list of them)");
    }
    out.push_back(value);
  }
  if (out.empty())
  {
    throw InvalidInput("--" + key + " = \"\": must be a positive number");
  }
  return out;
}

long toolInteger(const ToolOptions& options, const std::string& key, long fallback, long minimum)
{
  const auto it = options.extra.find(key);
  if (it == options.extra.end())
  {
    return fallback;
  }
  double n = 0;
  try
  {
    n = toNumber(it->second);
  }
  catch (const InvalidInput&)
  {
    n = std::nan("");
  }
  if (!(n == std::floor(n) && n >= static_cast<double>(minimum) && n <= 1e15))
  {
    throw InvalidInput("--" + key + " = \"" + it->second + "\": must be a whole number >= " +
      std::to_string(minimum));
  }
  return static_cast<long>(n);
}

std::string toolUsage(const std::map<std::string, std::string>& toolKeys)
{
  std::ostringstream out;
  out << "options:\n";
  for (const auto& [key, entry] : parameterSetters())
  {
    out << "  --" << key << "  " << entry.first << "\n";
  }
  for (const auto& [key, help] : toolKeys)
  {
    out << "  --" << key << "  " << help << "\n";
  }
  return out.str();
}

} // namespace pbf
