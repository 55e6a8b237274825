// Several liquids in one scene (Parameters::liquids, Scene's "liquids"): the scene names them, a
// particle keeps its liquid through sorts, ranks and checkpoints, one liquid named as the reference
// changes nothing, a lighter liquid alone moves as water does and reads its own density, and bad
// liquids are named.
#include "Backends.h"
#include "CpuStepper.h"
#include "Distributed/SubdomainStepper.h"
#include "Distributed/ThreadCluster.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <string>

using namespace pbf;

namespace
{

// Water under oil in a small tank, 4 cm spacing: 10 x 4 x 4 sites of each.
const char* kLayers = R"({
  "name": "layers",
  "domain": { "min": [0, 0, 0], "max": [0.4, 0.5, 0.16] },
  "liquids": [
    { "name": "water", "restDensity": 1000 },
    { "name": "oil", "restDensity": 800, "xsphViscosity": 0.05 }
  ],
  "fluid": [
    { "type": "box", "min": [0, 0, 0], "max": [0.4, 0.16, 0.16], "liquid": "water" },
    { "type": "box", "min": [0, 0.16, 0], "max": [0.4, 0.32, 0.16], "liquid": "oil" }
  ]
})";

Parameters coarse()
{
  Parameters p;
  p.particleSpacing = 0.04;
  return p;
}

// The scene's error message, or "" when it parses.
std::string errorOf(const std::string& json)
{
  try
  {
    parseScene(json);
  }
  catch (const InvalidInput& e)
  {
    return e.what();
  }
  return "";
}

std::string withLayers(const std::string& from, const std::string& to)
{
  std::string json = kLayers;
  const std::size_t at = json.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? json : json.replace(at, from.size(), to);
}

} // namespace

TEST(Liquids, TheSceneNamesItsLiquidsAndEachRegionItsLiquid)
{
  const Scene scene = parseScene(kLayers);
  ASSERT_EQ(scene.liquids.size(), 2u);
  EXPECT_EQ(scene.liquids[1].name, "oil");
  EXPECT_EQ(scene.liquids[1].restDensity, 800);
  EXPECT_EQ(scene.liquids[1].xsphViscosity, 0.05);
  EXPECT_TRUE(std::isnan(scene.liquids[0].xsphViscosity)) << "unset: the parameters' alpha";
  const Parameters p = withSceneDomain(coarse(), scene);
  ASSERT_EQ(p.liquids.size(), 2u);
  const ParticleBatch batch = fillScene(scene, p);
  ASSERT_EQ(batch.liquid.size(), batch.position.size());
  for (std::size_t i = 0; i < batch.position.size(); ++i)
  {
    EXPECT_EQ(batch.liquid[i], batch.position[i].y < 0.16 ? 0 : 1) << i;
  }
  // Without "liquids", nothing is carried.
  EXPECT_TRUE(fillScene(presetScene("dam_break"), withSceneDomain(coarse(), presetScene("dam_break")))
                .liquid.empty());
}

TEST(Liquids, BadLiquidsAreNamedWithTheirValues)
{
  const std::pair<std::string, std::string> cases[] = {
    { errorOf(withLayers("\"restDensity\": 800", "\"restDensity\": 0")),
      ".liquids[1].restDensity = 0: must be > 0" },
    { errorOf(withLayers("\"restDensity\": 800", "\"restDensity\": -5")),
      ".liquids[1].restDensity = -5: must be > 0" },
    { errorOf(withLayers("\"liquid\": \"oil\"", "\"liquid\": \"mercury\"")),
      ".fluid[1].liquid = \"mercury\": unknown liquid (the scene's: water, oil)" },
    { errorOf(withLayers("\"name\": \"oil\"", "\"name\": \"water\"")),
      ".liquids[1].name = \"water\": another liquid has this name" },
    { errorOf(withLayers("\"xsphViscosity\": 0.05", "\"xsphViscosity\": -1")),
      ".liquids[1].xsphViscosity = -1: must be >= 0" },
  };
  for (const auto& [message, expected] : cases)
  {
    EXPECT_NE(message.find(expected), std::string::npos) << message;
  }
  // A region that names a liquid in a scene without any.
  const std::string noLiquids = errorOf(R"({"domain": {"min": [0,0,0], "max": [1,1,1]},
    "fluid": [{"type": "box", "min": [0,0,0], "max": [0.5,0.5,0.5], "liquid": "oil"}]})");
  EXPECT_NE(noLiquids.find(".fluid[0].liquid = \"oil\": the scene has no \"liquids\""),
    std::string::npos) << noLiquids;
  // Parameters set through the API: a density beyond a hundred times the reference, and a batch
  // whose liquid index the scene does not have.
  Parameters p = withSceneDomain(coarse(), parseScene(kLayers));
  p.liquids[1].restDensity = 1e6;
  try
  {
    p.validate();
    ADD_FAILURE() << "a density ratio of 1000 was accepted";
  }
  catch (const InvalidInput& e)
  {
    EXPECT_NE(std::string(e.what()).find("liquids[1].restDensity = 1e+06: must be within 100 times"),
      std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(liquid \"oil\")"), std::string::npos) << e.what();
  }
  p.liquids[1].restDensity = 800;
  ParticleBatch batch = fillScene(parseScene(kLayers), p);
  batch.liquid[3] = 2;
  try
  {
    CpuStepper<double> stepper(false, p, batch);
    ADD_FAILURE() << "liquid 2 of 2 was accepted";
  }
  catch (const InvalidInput& e)
  {
    EXPECT_NE(std::string(e.what()).find("liquid of particle 3 = 2: the scene names 2 liquids"),
      std::string::npos) << e.what();
  }
}

// Liquid 0 at the reference density has weight 1 and density ratio 1, each exact: the liquid
// path multiplies by 1 where the one-liquid path does not multiply, so not one bit may differ.
TEST(Liquids, OneLiquidAtTheReferenceDensityIsBitIdenticalToNone)
{
  const Scene plain = presetScene("dam_break");
  Scene named = plain;
  Liquid water;
  water.name = "water";
  named.liquids = { water };
  Simulation a(plain, coarse(), Backend::Serial, Precision::Double);
  Simulation b(named, coarse(), Backend::Serial, Precision::Double);
  a.advance(30);
  b.advance(30);
  Snapshot<double> x, y;
  a.stepper().read(x);
  b.stepper().read(y);
  test::expectBitIdentical(x, y);
  EXPECT_TRUE(x.liquid.empty());
  EXPECT_EQ(y.liquid, std::vector<std::uint8_t>(y.id.size(), 0));
}

// A tank of one liquid of 800 kg/m^3 against the same tank of water: the constraint is on the
// number density, lambda scales with the liquid's density and the correction with its inverse, so
// the particles move alike up to rounding (double: 1e-9 of a coordinate after 30 steps, where a
// correction weighted wrongly would move the column by a fraction of a spacing) and read 0.8
// times water's density and pressure.
TEST(Liquids, ALighterLiquidAloneMovesAsWaterAndReadsItsOwnDensity)
{
  const Scene plain = presetScene("dam_break");
  Scene oily = plain;
  Liquid oil;
  oil.name = "oil";
  oil.restDensity = 800;
  oily.liquids = { oil };
  Simulation a(plain, coarse(), Backend::Serial, Precision::Double);
  Simulation b(oily, coarse(), Backend::Serial, Precision::Double);
  a.advance(30);
  b.advance(30);
  Snapshot<double> x, y;
  a.stepper().read(x);
  b.stepper().read(y);
  EXPECT_LT(test::maxRelativePositionError(y, x), 1e-9);
  ASSERT_EQ(x.id, y.id);
  double densityMiss = 0, pressureMiss = 0, largestPressure = 0;
  for (std::size_t i = 0; i < x.id.size(); ++i)
  {
    densityMiss = std::max(densityMiss, std::abs(y.density[i] - 0.8 * x.density[i]) / x.density[i]);
    pressureMiss = std::max(pressureMiss, std::abs(y.pressure[i] - 0.8 * x.pressure[i]));
    largestPressure = std::max(largestPressure, std::abs(x.pressure[i]));
  }
  EXPECT_LT(densityMiss, 1e-9);
  EXPECT_GT(largestPressure, 100.0);
  EXPECT_LT(pressureMiss, 1e-9 * largestPressure);
  const Statistics water = a.stepper().statistics(), light = b.stepper().statistics();
  EXPECT_NEAR(light.kineticEnergy, 0.8 * water.kineticEnergy, 1e-9 * water.kineticEnergy);
  EXPECT_NEAR(light.averageDensityError, water.averageDensityError, 1e-9);
}

// Every CPU backend carries each particle's liquid through its sorts: OpenMP bit-identical to
// serial, one rank too, and two and three ranks within 1e-9 (DistributedTest's bound: the ranks
// sum neighbours in another order) with every particle still of its liquid.
TEST(Liquids, EveryCpuBackendKeepsEachParticlesLiquid)
{
  const Scene scene = parseScene(kLayers);
  Parameters p = withSceneDomain(coarse(), scene);
  p.densityErrorTolerance = 0;
  p.solverIterations = 4;
  const ParticleBatch fluid = fillScene(scene, p);
  auto run = [&](Backend backend) {
    auto stepper = makeStepper(backend, Precision::Double, p, fluid);
    for (int s = 0; s < 20; ++s)
    {
      stepper->step();
    }
    Snapshot<double> out;
    stepper->read(out);
    return out;
  };
  const Snapshot<double> serial = run(Backend::Serial);
  test::expectBitIdentical(serial, run(Backend::OpenMP));
  const std::map<std::int64_t, int> expected = test::liquidsById(serial);
  for (std::size_t i = 0; i < fluid.id.size(); ++i)
  {
    ASSERT_EQ(expected.at(fluid.id[i]), fluid.liquid[i]) << "particle " << fluid.id[i];
  }
  for (int ranks : { 1, 2, 3 })
  {
    std::vector<Snapshot<double>> parts(static_cast<std::size_t>(ranks));
    distributed::runThreadCluster(ranks, [&](distributed::Communicator& communicator) {
      distributed::SubdomainStepper<double> stepper(communicator, false, p, fluid);
      for (int s = 0; s < 20; ++s)
      {
        stepper.step();
      }
      stepper.read(parts[static_cast<std::size_t>(communicator.rank())]);
    });
    const Snapshot<double> all = test::joined(parts);
    EXPECT_EQ(test::liquidsById(all), expected) << ranks << " ranks";
    EXPECT_LE(test::maxRelativePositionError(all, serial), ranks == 1 ? 0.0 : 1e-9)
      << ranks << " ranks";
  }
}

TEST(Liquids, ACheckpointKeepsEachParticlesLiquid)
{
  const Scene scene = parseScene(kLayers);
  Simulation straight(scene, coarse(), Backend::OpenMP, Precision::Single);
  straight.advance(40);
  Simulation resumed(scene, coarse(), Backend::OpenMP, Precision::Single);
  resumed.advance(15);
  const SimulationCheckpoint at15 = resumed.checkpoint();
  resumed.advance(10);
  resumed.restore(at15);
  resumed.advance(25);
  Snapshot<float> x, y;
  straight.stepper().read(x);
  resumed.stepper().read(y);
  test::expectBitIdentical(x, y);
  EXPECT_EQ(x.liquid, y.liquid);
  // A checkpoint of a scene without liquids does not fit one with them, and the reverse.
  Scene plain = scene;
  plain.liquids.clear();
  for (FluidBox& box : plain.boxes)
  {
    box.liquid = 0;
  }
  Simulation other(plain, coarse(), Backend::OpenMP, Precision::Single);
  EXPECT_THROW(other.restore(at15), InvalidInput);
}
