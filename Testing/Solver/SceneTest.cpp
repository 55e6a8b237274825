// Scene files: every preset loads; broken files get errors naming the key and the value.
#include "Scene.h"
#include "Simulation.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <set>

using namespace pbf;

namespace
{

std::string errorOf(const std::string& json)
{
  try
  {
    parseScene(json);
  }
  catch (const InvalidInput& error)
  {
    return error.what();
  }
  return "";
}

const char* kValid = R"({"domain": {"min": [0,0,0], "max": [1,1,1]},
  "fluid": [{"type": "box", "min": [0,0,0], "max": [0.5,0.5,0.5]}]})";

} // namespace

TEST(Scene, EveryPresetParsesAndFills)
{
  const auto names = presetNames();
  const std::set<std::string> expected = { "blob", "channel", "dam_break", "double_dam_break",
    "marin_dam_break", "stream" };
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()), expected);
  for (const auto& name : names)
  {
    const Scene scene = presetScene(name);
    EXPECT_EQ(scene.name, name);
    const ParticleBatch batch = fillScene(scene, withSceneDomain(Parameters(), scene));
    if (scene.emitters.empty())
    {
      EXPECT_GT(batch.position.size(), 1000u) << name;
    }
  }
}

TEST(Scene, DamBreakColumnHasTheLatticeCount)
{
  const Scene scene = presetScene("dam_break");
  Parameters p;
  const ParticleBatch batch = fillScene(scene, withSceneDomain(p, scene));
  // 0.4 x 0.6 x 0.6 m at s = 0.02 m: 20 x 30 x 30 sites.
  EXPECT_EQ(batch.position.size(), 18000u);
  EXPECT_LE(static_cast<double>(batch.position.size()), estimateParticleCount(scene, p));
}

TEST(Scene, ErrorsNameTheKeyAndTheValue)
{
  EXPECT_EQ(errorOf(kValid), "");
  std::string e = errorOf(R"({"domain": {"min": [0,0,0], "max": [1,1,1]}, "fluid": [], "colour": 3})");
  EXPECT_NE(e.find(".colour"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key"), std::string::npos) << e;

  e = errorOf(R"({"domain": {"min": [0,0,0], "max": [1,1,1]},
    "fluid": [{"type": "sphere", "center": [0.5,0.5,0.5], "radius": -2}]})");
  EXPECT_NE(e.find(".fluid[0].radius = -2"), std::string::npos) << e;

  e = errorOf(R"({"domain": {"min": [0,0,0], "max": [1,1,1]},
    "fluid": [{"type": "box", "min": [0,0,0], "max": [0.5,"x",0.5]}]})");
  EXPECT_NE(e.find(".fluid[0].max"), std::string::npos) << e;

  e = errorOf(R"({"domain": {"min": [0,0,0], "max": [1,1,1]},
    "fluid": [{"type": "box", "min": [0,0,0], "max": [2,0.5,0.5]}]})");
  EXPECT_NE(e.find("inside the domain"), std::string::npos) << e;

  e = errorOf(R"({"domain": {"min": [0,0,0], "max": [1,1,1]}, "fluid": [{"type": "cone"}]})");
  EXPECT_NE(e.find("\"cone\""), std::string::npos) << e;

  e = errorOf(R"({"fluid": []})");
  EXPECT_NE(e.find(".domain is missing"), std::string::npos) << e;

  e = errorOf(R"({"domain": {"min": [0,0,0], "max": [1,1,1]}, "fluid": [)");
  EXPECT_NE(e.find("not valid JSON"), std::string::npos) << e;

  e = errorOf(R"({"domain": {"min": [0,0,0], "max": [1,1,1]}, "fluid": []})");
  EXPECT_NE(e.find("no fluid region"), std::string::npos) << e;
}

TEST(Scene, MissingAndEmptyFilesAreErrorsNamingThePath)
{
  const std::string missing = "/nonexistent/pbf/scene.json";
  try
  {
    loadSceneFile(missing);
    FAIL();
  }
  catch (const InvalidInput& error)
  {
    EXPECT_NE(std::string(error.what()).find(missing), std::string::npos);
  }
  const std::string empty = testing::TempDir() + "pbf_empty_scene.json";
  std::ofstream(empty).close();
  try
  {
    loadSceneFile(empty);
    FAIL();
  }
  catch (const InvalidInput& error)
  {
    EXPECT_NE(std::string(error.what()).find("is empty"), std::string::npos) << error.what();
  }
  std::remove(empty.c_str());
}

TEST(Scene, UnknownPresetListsTheKnownOnes)
{
  try
  {
    presetScene("tsunami");
    FAIL();
  }
  catch (const InvalidInput& error)
  {
    const std::string message = error.what();
    EXPECT_NE(message.find("tsunami"), std::string::npos);
    EXPECT_NE(message.find("dam_break"), std::string::npos);
  }
}

TEST(Scene, SpacingThatWouldMakeTooManyParticlesFailsBeforeAllocating)
{
  const Scene scene = presetScene("dam_break");
  Parameters p;
  p.particleSpacing = 1e-5; // 1.4e16 particles
  try
  {
    fillScene(scene, withSceneDomain(p, scene));
    FAIL();
  }
  catch (const InvalidInput& error)
  {
    EXPECT_NE(std::string(error.what()).find("particleSpacing"), std::string::npos);
  }
}

TEST(Scene, StreamEmitterAddsLayersWithUniqueIds)
{
  const Scene scene = presetScene("stream");
  Parameters p;
  p.particleSpacing = 0.04;
  Simulation simulation(scene, p, Backend::Serial, Precision::Single);
  const std::size_t first = simulation.stepper().size();
  EXPECT_GT(first, 0u);
  simulation.advance(48); // 0.2 s: 1.5 m/s / 0.04 m = 37.5 layers per second
  Snapshot<float> snapshot;
  simulation.stepper().read(snapshot);
  const std::size_t layers = snapshot.id.size() / first;
  EXPECT_EQ(snapshot.id.size() % first, 0u);
  EXPECT_GE(layers, 7u);
  EXPECT_LE(layers, 9u);
  std::set<std::int64_t> ids(snapshot.id.begin(), snapshot.id.end());
  EXPECT_EQ(ids.size(), snapshot.id.size());
  EXPECT_EQ(*ids.rbegin(), static_cast<std::int64_t>(snapshot.id.size()) - 1);
}
