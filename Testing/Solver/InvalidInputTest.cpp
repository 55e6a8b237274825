// Bad input of every kind is refused up front with InvalidInput naming the field and the value:
// parameters (NaN, infinities, negative counts, sizes against the domain, constants beyond the
// precision), scene files (missing, empty, a folder, not JSON, unknown keys, numbers beyond
// double, deep nesting) and scenes whose emitters would later fail.
#include "Scene.h"
#include "Simulation.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

// The message of the InvalidInput that `act` throws, or "" when it throws none.
std::string messageOf(const std::function<void()>& act)
{
  try
  {
    act();
  }
  catch (const InvalidInput& error)
  {
    return error.what();
  }
  return "";
}

#define EXPECT_MENTIONS(message, text)                                                            \
  EXPECT_NE((message).find(text), std::string::npos) << "\"" << (message) << "\" lacks " << (text)

// Every floating-point parameter, by the name its messages use.
std::vector<std::pair<std::string, double Parameters::*>> scalarFields()
{
  return {
    { "restDensity", &Parameters::restDensity },
    { "particleSpacing", &Parameters::particleSpacing },
    { "smoothingRatio", &Parameters::smoothingRatio },
    { "densityErrorTolerance", &Parameters::densityErrorTolerance },
    { "relaxation", &Parameters::relaxation },
    { "sCorrK", &Parameters::sCorrK },
    { "sCorrN", &Parameters::sCorrN },
    { "sCorrDeltaQ", &Parameters::sCorrDeltaQ },
    { "xsphViscosity", &Parameters::xsphViscosity },
    { "xsphHyperViscosity", &Parameters::xsphHyperViscosity },
    { "chebyshevRho", &Parameters::chebyshevRho },
    { "cflNumber", &Parameters::cflNumber },
    { "vorticityEpsilon", &Parameters::vorticityEpsilon },
    { "timeStep", &Parameters::timeStep },
  };
}

std::vector<std::pair<std::string, double*>> vectorFields(Parameters& p)
{
  return {
    { "gravity.x", &p.gravity.x },
    { "gravity.y", &p.gravity.y },
    { "gravity.z", &p.gravity.z },
    { "domain.min.x", &p.domain.min.x },
    { "domain.min.y", &p.domain.min.y },
    { "domain.min.z", &p.domain.min.z },
    { "domain.max.x", &p.domain.max.x },
    { "domain.max.y", &p.domain.max.y },
    { "domain.max.z", &p.domain.max.z },
  };
}

std::string writeFile(const std::string& name, const std::string& text)
{
  const std::string path = testing::TempDir() + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// A 1 m box with a small block of fluid, for scenes built in code.
Scene smallScene()
{
  Scene scene;
  scene.name = "small";
  scene.domain = { { 0, 0, 0 }, { 1, 1, 1 } };
  scene.boxes.push_back({ { 0, 0, 0 }, { 0.2, 0.2, 0.2 }, { 0, 0, 0 } });
  return scene;
}

Parameters coarse()
{
  Parameters p;
  p.particleSpacing = 0.05;
  return p;
}

// Starts a simulation on the serial backend and throws it away: construction is what is checked.
void start(const Scene& scene, const Parameters& p, Precision precision = Precision::Single,
  const ParticleBatch* given = nullptr)
{
  if (given)
  {
    Simulation simulation(scene, p, Backend::Serial, precision, *given);
  }
  else
  {
    Simulation simulation(scene, p, Backend::Serial, precision);
  }
}

} // namespace

TEST(InvalidInput, EveryParameterRefusesNaNAndInfinitiesByName)
{
  for (const auto& [name, field] : scalarFields())
  {
    for (double bad : { kNaN, kInf, -kInf })
    {
      Parameters p;
      p.*field = bad;
      const std::string message = messageOf([&] { p.validate(); });
      EXPECT_MENTIONS(message, name + " = ");
      EXPECT_MENTIONS(message, std::isnan(bad) ? "nan" : "inf");
    }
  }
  for (double bad : { kNaN, kInf, -kInf })
  {
    for (std::size_t k = 0; k < 9; ++k)
    {
      Parameters p;
      const auto fields = vectorFields(p);
      *fields[k].second = bad;
      const std::string message = messageOf([&] { p.validate(); });
      EXPECT_MENTIONS(message, fields[k].first + " = ");
    }
  }
}

TEST(InvalidInput, NegativeAndZeroCountsAndSizesAreRefused)
{
  const std::vector<std::pair<std::function<void(Parameters&)>, std::string>> cases = {
    { [](Parameters& p) { p.solverIterations = -1; }, "solverIterations = -1" },
    { [](Parameters& p) { p.solverIterations = 0; }, "solverIterations = 0" },
    { [](Parameters& p) { p.solverIterations = 1001; }, "solverIterations = 1001" },
    { [](Parameters& p) { p.particleSpacing = -0.02; }, "particleSpacing = -0.02" },
    { [](Parameters& p) { p.restDensity = 0; }, "restDensity = 0" },
    { [](Parameters& p) { p.timeStep = -1; }, "timeStep = -1" },
    { [](Parameters& p) { p.relaxation = -0.01; }, "relaxation = -0.01" },
    { [](Parameters& p) { p.sCorrK = -0.1; }, "sCorrK = -0.1" },
    { [](Parameters& p) { p.sCorrN = 0; }, "sCorrN = 0" },
    { [](Parameters& p) { p.sCorrN = 2e174; }, "sCorrN = 2e+174" }, // found by the fuzzer
    { [](Parameters& p) { p.densityErrorTolerance = -1; }, "densityErrorTolerance = -1" },
    { [](Parameters& p) { p.vorticityEpsilon = -1; }, "vorticityEpsilon = -1" },
    { [](Parameters& p) { p.domain.max.y = -1; }, "domain.max.y = -1" }, // max below min
  };
  for (const auto& [change, expected] : cases)
  {
    Parameters p;
    change(p);
    EXPECT_MENTIONS(messageOf([&] { p.validate(); }), expected);
  }
}

TEST(InvalidInput, SpacingTooLargeForTheDomainNamesBothAndTheRemedy)
{
  Parameters p;
  p.domain = { { 0, 0, 0 }, { 1, 0.15, 1 } };
  p.particleSpacing = 0.1; // h = 0.2 > 0.15
  const std::string message = messageOf([&] { p.validate(); });
  EXPECT_MENTIONS(message, "domain.max.y = 0.15");
  EXPECT_MENTIONS(message, "particleSpacing 0.1");
  EXPECT_MENTIONS(message, "lower particleSpacing or enlarge the domain");
}

TEST(InvalidInput, SpacingLargerThanEveryFluidRegionSaysSo)
{
  Scene scene = smallScene();
  scene.boxes[0].max = { 0.04, 0.3, 0.3 }; // thinner than one spacing of 0.05 along x
  const std::string message =
    messageOf([&] { start(scene, coarse()); });
  EXPECT_MENTIONS(message, "particleSpacing = 0.05");
  EXPECT_MENTIONS(message, "hold no lattice site");
}

TEST(InvalidInput, FluidOutsideTheDomainIsRefused)
{
  // A scene file's regions are checked when it is read ...
  const std::string sphere = messageOf([] {
    parseScene(R"({"domain": {"min": [0,0,0], "max": [1,1,1]},
      "fluid": [{"type": "sphere", "center": [0.9,0.5,0.5], "radius": 0.2}]})");
  });
  EXPECT_MENTIONS(sphere, ".fluid[0]");
  EXPECT_MENTIONS(sphere, "inside the domain");
  const std::string nozzle = messageOf([] {
    parseScene(R"({"domain": {"min": [0,0,0], "max": [1,1,1]}, "fluid": [],
      "emitters": [{"center": [0.5,0.5,0.5], "direction": [1,0,0], "radius": 0.6, "speed": 1,
      "stop": 1}]})");
  });
  EXPECT_MENTIONS(nozzle, ".emitters[0]");
  EXPECT_MENTIONS(nozzle, "inside the domain");
  // ... and given particles (the VTK filter's points) when the simulation starts.
  ParticleBatch points;
  points.position = { { 0.5, 0.5, 0.5 }, { 0.5, 3.0, 0.5 } };
  points.velocity.assign(2, { 0, 0, 0 });
  points.id = { 0, 1 };
  const std::string given =
    messageOf([&] { start(smallScene(), coarse(), Precision::Single, &points); });
  EXPECT_MENTIONS(given, "position of particle 1 = (0.5, 3, 0.5)");
  EXPECT_MENTIONS(given, "outside the domain");
}

TEST(InvalidInput, ConstantsBeyondSinglePrecisionNameTheParameter)
{
  // Each is fine in double precision and would silently turn into inf, 0 or NaN in float.
  struct Case
  {
    std::function<void(Parameters&)> change;
    std::string expected;
  };
  const std::vector<Case> cases = {
    { [](Parameters& p) { p.restDensity = 1e39; }, "restDensity = 1e+39" },     // 1 / rho_0
    { [](Parameters& p) { p.relaxation = 1e-300; }, "relaxation = 1e-300" },    // epsilon -> 0
    { [](Parameters& p) { p.timeStep = 1e-40; }, "timeStep = 1e-40" },          // dt -> 0
    { [](Parameters& p) { p.vorticityEpsilon = 1e39; }, "vorticityEpsilon = 1e+39" },
    { [](Parameters& p) { p.gravity.y = -1e39; }, "gravity.y = -1e+39" },
  };
  const Scene scene = smallScene();
  for (const Case& c : cases)
  {
    Parameters p = coarse();
    c.change(p);
    const std::string single = messageOf([&] { start(scene, p); });
    EXPECT_MENTIONS(single, c.expected);
    EXPECT_MENTIONS(single, "single-precision range");
    EXPECT_EQ(messageOf([&] { start(scene, p, Precision::Double); }), "") << c.expected;
  }

  // A 20 um spacing (h = 40 um): the poly6 constant 315 / (64 pi h^9) is 6e39, beyond float.
  Scene tiny;
  tiny.domain = { { 0, 0, 0 }, { 1e-3, 1e-3, 1e-3 } };
  tiny.boxes.push_back({ { 0, 0, 0 }, { 1e-4, 1e-4, 1e-4 }, { 0, 0, 0 } });
  Parameters p;
  p.particleSpacing = 2e-5;
  const std::string kernel = messageOf([&] { start(tiny, p); });
  EXPECT_MENTIONS(kernel, "particleSpacing = 2e-05");
  EXPECT_MENTIONS(kernel, "poly6");
  EXPECT_EQ(messageOf([&] { start(tiny, p, Precision::Double); }), "");

  // s_corr's largest term, k (W(0) / W(delta_q))^n in units of lambda: at delta_q = 0.99 h
  // and n = 16, 1e76, beyond float.
  p = coarse();
  p.sCorrDeltaQ = 0.99;
  p.sCorrN = 16;
  EXPECT_MENTIONS(messageOf([&] { start(scene, p); }), "sCorrN = 16");
  EXPECT_EQ(messageOf([&] { start(scene, p, Precision::Double); }), "");
}

TEST(InvalidInput, DomainFarFromTheOriginNeedsDoublePrecision)
{
  // Float steps by 0.0625 m at 1e6 m: a 0.05 m spacing cannot be simulated there.
  Scene far = smallScene();
  const Vec3d offset{ 1e6, 1e6, 1e6 };
  far.domain = { far.domain.min + offset, far.domain.max + offset };
  far.boxes[0] = { far.boxes[0].min + offset, far.boxes[0].max + offset, { 0, 0, 0 } };
  const std::string message = messageOf([&] { start(far, coarse()); });
  EXPECT_MENTIONS(message, "particleSpacing = 0.05");
  EXPECT_MENTIONS(message, "single precision resolves only");
  EXPECT_EQ(messageOf([&] { start(far, coarse(), Precision::Double); }), "");
}

TEST(InvalidInput, SceneFileProblemsNameTheFileAndTheProblem)
{
  const std::string folder = testing::TempDir();
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
    { folder + "pbf_no_such_scene.json", { "pbf_no_such_scene.json", "cannot be opened" } },
    { writeFile("pbf_empty.json", ""), { "pbf_empty.json", "is empty" } },
    { folder, { folder, "is a folder" } },
    { writeFile("pbf_not_json.json", "domain: [0, 1]\n"), { "pbf_not_json.json", "not valid JSON" } },
    { writeFile("pbf_binary.json", std::string("\x89PNG\r\n\x1a\n\0\0", 10)),
      { "pbf_binary.json", "not valid JSON" } },
    { writeFile("pbf_unknown_key.json",
        R"({"domain": {"min": [0,0,0], "max": [1,1,1]}, "fluid": [], "colour": "blue"})"),
      { "pbf_unknown_key.json", ".colour = \"blue\"", "unknown key (allowed: " } },
    { writeFile("pbf_bad_value.json",
        R"({"domain": {"min": [0,0,0], "max": [1,1,1]}, "fluid": [{"type": "box",
          "min": [0,0,0], "max": [0.5,0.5,0.5], "velocity": [0,null,0]}]})"),
      { "pbf_bad_value.json", ".fluid[0].velocity = [0,null,0]", "3 finite numbers" } },
  };
  for (const auto& [file, needles] : cases)
  {
    const std::string path = file; // a lambda may not capture a structured binding in C++17
    const std::string message = messageOf([&] { loadSceneFile(path); });
    for (const std::string& needle : needles)
    {
      EXPECT_MENTIONS(message, needle);
    }
  }
}

TEST(InvalidInput, JsonNumberBeyondDoubleIsInvalidInputNotAParserException)
{
  // nlohmann::json reports 1e400 with out_of_range, not parse_error; it used to escape as such.
  const std::string message = messageOf([] {
    parseScene(R"({"domain": {"min": [0,0,0], "max": [1e400,1,1]}, "fluid": []})");
  });
  EXPECT_MENTIONS(message, "not valid JSON");
  EXPECT_MENTIONS(message, "1e400");
}

TEST(InvalidInput, DeepNestingIsRefusedWhileParsing)
{
  // A million nested arrays: refused at depth 16, before any recursion could overflow the stack.
  const std::string deep = R"({"domain": )" + std::string(1000000, '[') + "0" +
    std::string(1000000, ']') + "}";
  EXPECT_MENTIONS(messageOf([&] { parseScene(deep); }), "nested deeper than 16 levels");
}

TEST(InvalidInput, LongValuesAreQuotedShort)
{
  const std::string message = messageOf([] {
    parseScene(R"({"domain": {"min": [0,0,0], "max": [1,1,1]}, "fluid": [], "notes": ")" +
      std::string(100000, 'x') + R"("})");
  });
  EXPECT_MENTIONS(message, ".notes = \"xxx");
  EXPECT_MENTIONS(message, "(100002 characters)");
  EXPECT_LT(message.size(), 400u);
}

TEST(InvalidInput, EmitterDirectionOfAnyMagnitudeIsNormalised)
{
  // |d| of [1e200, 0, 0] overflows and that of [1e-200, 0, 0] underflows; 1 / 5e-324 overflows.
  for (const char* direction : { "[1e200, 0, 0]", "[1e-200, 0, 0]", "[5e-324, 0, 0]", "[3, 0, 0]" })
  {
    const Scene scene = parseScene(std::string(R"({"domain": {"min": [0,0,0], "max": [1,1,1]},
      "fluid": [], "emitters": [{"center": [0.5,0.5,0.5], "radius": 0.1, "speed": 1, "stop": 1,
      "direction": )") + direction + "}]}");
    const Vec3d d = scene.emitters.at(0).direction;
    EXPECT_EQ(d.x, 1.0) << direction;
    EXPECT_EQ(d.y, 0.0) << direction;
    EXPECT_EQ(d.z, 0.0) << direction;
  }
}

TEST(InvalidInput, EmitterThatWouldThrowLayersOutOfTheDomainIsRefusedAtTheStart)
{
  // At 200 m/s a layer travels 0.83 m in a default step: out of a 1 m box from its middle. It
  // used to be found only when that layer was appended, in the middle of advance().
  Scene scene = smallScene();
  scene.boxes.clear();
  scene.emitters.push_back({ { 0.5, 0.5, 0.5 }, { 1, 0, 0 }, 0.1, 200.0, 0.0, 1.0 });
  const std::string message = messageOf([&] { start(scene, coarse()); });
  EXPECT_MENTIONS(message, ".emitters[0].speed = 200");
  EXPECT_MENTIONS(message, "timeStep = 0.00417");
  // Slow enough, the same nozzle runs.
  scene.emitters[0].speed = 10.0;
  Simulation simulation(scene, coarse(), Backend::Serial, Precision::Single);
  EXPECT_NO_THROW(simulation.advance(5));
}

TEST(InvalidInput, EmittedParticleCountIsBoundedForGivenParticlesToo)
{
  // The scene's own fill counts emitters in its estimate; given particles skip the fill.
  Scene scene = smallScene();
  scene.emitters.push_back({ { 0.5, 0.5, 0.5 }, { 1, 0, 0 }, 0.1, 1.0, 0.0, 1e12 });
  ParticleBatch points;
  points.position = { { 0.5, 0.2, 0.5 } };
  points.velocity = { { 0, 0, 0 } };
  points.id = { 0 };
  const std::string message =
    messageOf([&] { start(scene, coarse(), Precision::Single, &points); });
  EXPECT_MENTIONS(message, "the emitters would add about");
  EXPECT_MENTIONS(message, "particleSpacing = 0.05");
}

TEST(InvalidInput, AnAutomaticStepTooSmallToRepresentNamesWhatForcesIt)
{
  // Found by fuzzing: gravity 1.7e156 m/s^2 is finite, but the automatic step it allows,
  // 0.4 s / sqrt(2 |g| L), underflows to 0, and the first step threw from inside advance().
  Parameters p = coarse();
  p.gravity = { 0, 1.7164750796028833e156, 0 };
  const std::string message = messageOf([&] { start(smallScene(), p, Precision::Double); });
  EXPECT_NE(message.find("gravity.y = 1.72e+156"), std::string::npos) << "[" << message << "]";
  EXPECT_NE(message.find("the automatic time step it allows"), std::string::npos) << message;
  // The same gravity with fixed steps is the caller's choice; it blows up, it is not refused.
  p.timeStepping = TimeStepping::Fixed;
  EXPECT_EQ(messageOf([&] { start(smallScene(), p, Precision::Double); }), "");
}
