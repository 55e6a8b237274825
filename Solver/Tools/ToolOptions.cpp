#include "ToolOptions.h"

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

std::map<std::string, std::pair<std::string, Setter>> parameterSetters()
{
  auto real = [](double Parameters::*field) {
    return [field](ToolOptions& o, const std::string& v) { o.parameters.*field = toNumber(v); };
  };
  return {
    { "rest-density", { "rho_0 [kg/m^3]", real(&Parameters::restDensity) } },
    { "spacing", { "particle spacing s [m]", real(&Parameters::particleSpacing) } },
    { "smoothing-ratio", { "h / s", real(&Parameters::smoothingRatio) } },
    { "iterations",
      { "solver iterations",
        [](ToolOptions& o, const std::string& v) {
          const double n = toNumber(v);
          if (n != std::floor(n) || std::abs(n) > 1e9) // converting beyond int is undefined
          {
            throw InvalidInput("not a whole number in [1, 1000]");
          }
          o.parameters.solverIterations = static_cast<int>(n);
        } } },
    { "epsilon", { "relaxation epsilon (bulk denominator units)", real(&Parameters::relaxation) } },
    { "chebyshev",
      { "Chebyshev acceleration of the projections: spectral radius estimate rho in [0, 1) "
        "(0: plain Jacobi)",
        real(&Parameters::chebyshevRho) } },
    { "tolerance",
      { "adaptive iterations: mean compression target [%] (0: fixed count)",
        real(&Parameters::densityErrorTolerance) } },
    { "max-tolerance",
      { "adaptive iterations: largest compression allowed [%] (0: the mean alone decides)",
        real(&Parameters::maxDensityErrorTolerance) } },
    { "scorr-k", { "s_corr k in units of g0", real(&Parameters::sCorrK) } },
    { "scorr-n", { "s_corr n", real(&Parameters::sCorrN) } },
    { "scorr-dq", { "s_corr delta_q / h", real(&Parameters::sCorrDeltaQ) } },
    { "xsph",
      { "XSPH artificial viscosity alpha (nu = alpha h v_scene)",
        real(&Parameters::xsphViscosity) } },
    { "xsph-hyper",
      { "XSPH's bi-Laplacian alpha_4 (nu_4 = alpha_4 h v_scene; 0: off)",
        real(&Parameters::xsphHyperViscosity) } },
    { "vorticity", { "vorticity epsilon [m/s]", real(&Parameters::vorticityEpsilon) } },
    { "dt", { "time step [s]: every step's when fixed, the largest when automatic",
              real(&Parameters::timeStep) } },
    { "cfl", { "CFL number of the automatic time step", real(&Parameters::cflNumber) } },
    { "time-stepping",
      { "auto | fixed",
        [](ToolOptions& o, const std::string& v) {
          if (v != "auto" && v != "fixed")
          {
            throw InvalidInput("must be auto or fixed");
          }
          o.parameters.timeStepping = v == "auto" ? TimeStepping::Automatic : TimeStepping::Fixed;
        } } },
    { "unilateral",
      { "0 or 1: clamp C_i at 0",
        [](ToolOptions& o, const std::string& v) {
          o.parameters.unilateral = toNumber(v) != 0.0;
        } } },
    { "walls",
      { "0 or 1: walls mirror the fluid",
        [](ToolOptions& o, const std::string& v) {
          o.parameters.mirrorWalls = toNumber(v) != 0.0;
        } } },
    { "friction",
      { "wall friction in [0, 1]: 0 free-slip, 1 no-slip",
        [](ToolOptions& o, const std::string& v) { o.parameters.wallFriction = toNumber(v); } } },
    { "scene",
      { "preset name or .json path",
        [](ToolOptions& o, const std::string& v) { o.scene = v; } } },
    { "backend",
      { "serial | openmp | cuda",
        [](ToolOptions& o, const std::string& v) { o.backend = parseBackend(v); } } },
    { "precision",
      { "single | double",
        [](ToolOptions& o, const std::string& v) {
          if (v != "single" && v != "double")
          {
            throw InvalidInput("--precision = \"" + v + "\": must be single or double");
          }
          o.precision = v == "single" ? Precision::Single : Precision::Double;
        } } },
  };
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
