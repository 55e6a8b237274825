// Solid obstacles in the step (Physics/Boundary.h) on the host steppers: fluid at rest next to a
// flat solid reads rho_0 as next to a mirror wall, no particle enters a solid in its way, Serial
// and OpenMP stay bit-identical, and a backend without obstacles says so.
#include "Backends.h"
#include "CpuStepper.h"
#include "Distributed/SubdomainStepper.h"
#include "Distributed/ThreadCluster.h"
#include "SignedDistance.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

using namespace pbf;

namespace
{

constexpr double kSpacing = 0.05;

// A 12 x 6 x 12 block of fluid lattice in a tank whose lowest 0.3 m are solid: either a box
// obstacle (`floor` true) or, for the reference, the same block on the domain's own floor 0.3 m
// lower (a mirror wall). Either way the lowest layer sits s/2 above the solid.
struct Tank
{
  Parameters parameters;
  ParticleBatch fluid;
};

Tank tankOn(bool obstacleFloor)
{
  Tank t;
  const double below = obstacleFloor ? 0.3 : 0.0;
  t.parameters.particleSpacing = kSpacing;
  t.parameters.domain = { { 0, 0, 0 }, { 12 * kSpacing, below + 12 * kSpacing, 12 * kSpacing } };
  Scene scene;
  scene.domain = t.parameters.domain;
  scene.boxes.push_back({ { 0, below, 0 }, { 12 * kSpacing, below + 6 * kSpacing, 12 * kSpacing },
    { 0, 0, 0 } });
  t.fluid = fillScene(scene, t.parameters);
  return t;
}

// The solid below y = 0.3, wider than the tank so its sides are not felt, on cells of s / 2.
DistanceGrid solidFloor()
{
  const double h = Parameters().smoothingRatio * kSpacing;
  return boxDistance({ { -1, -1, -1 }, { 2, 0.3, 2 } }, 0.5 * kSpacing, h);
}

} // namespace

TEST(Obstacle, FluidAtRestOnAFlatSolidReadsRestDensityAsOnAMirrorWall)
{
  const Tank onSolid = tankOn(true), onWall = tankOn(false);
  ASSERT_EQ(onSolid.fluid.position.size(), onWall.fluid.position.size());
  CpuStepper<double> solid(false, onSolid.parameters, onSolid.fluid);
  solid.setObstacles({ solidFloor() });
  CpuStepper<double> wall(false, onWall.parameters, onWall.fluid);
  Snapshot<double> a, b;
  solid.read(a);
  wall.read(b);
  const auto byId = test::indexById(b);
  const double h = onSolid.parameters.smoothingLength();
  double worst = 0, worstAgainstWall = 0;
  int near = 0;
  for (std::size_t i = 0; i < a.id.size(); ++i)
  {
    const Vec3d x = a.position[i];
    // Within h of the solid and away from the side walls, where the mirror walls add corner
    // images that a flat solid's table does not.
    if (x.y - 0.3 < h && x.x > h && x.x < 12 * kSpacing - h && x.z > h && x.z < 12 * kSpacing - h)
    {
      ++near;
      const double rho0 = onSolid.parameters.restDensity;
      worst = std::max(worst, std::abs(a.density[i] / rho0 - 1));
      worstAgainstWall =
        std::max(worstAgainstWall, std::abs(a.density[i] - b.density[byId.at(a.id[i])]) / rho0);
    }
  }
  ASSERT_GT(near, 50);
  // The required bound is 1 %; the table is the continued lattice itself, so what remains is
  // summation order and the table's linear interpolation, far below it.
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(worstAgainstWall, 1e-6);
}

TEST(Obstacle, FluidAtRestOnASolidBehavesAsOnTheFloor)
{
  // The same column on the solid and on the domain's floor, 0.5 s (120 steps of 1/240 s) from
  // the lattice: the solid must hold it as the floor does.
  struct Outcome
  {
    double lowest = 1e9, fastest = 0;
    Statistics statistics;
  };
  auto run = [](bool onSolid) {
    const Tank t = tankOn(onSolid);
    CpuStepper<double> stepper(true, t.parameters, t.fluid);
    if (onSolid)
    {
      stepper.setObstacles({ solidFloor() });
    }
    for (int s = 0; s < 120; ++s)
    {
      stepper.step();
    }
    Snapshot<double> state;
    stepper.read(state);
    Outcome o;
    for (std::size_t i = 0; i < state.id.size(); ++i)
    {
      o.lowest = std::min(o.lowest, state.position[i].y - (onSolid ? 0.3 : 0.0));
      o.fastest = std::max(o.fastest, length(state.velocity[i]));
    }
    o.statistics = stepper.statistics();
    return o;
  };
  const Outcome solid = run(true), floor = run(false);
  // Nothing sinks into the solid; the lowest particle as high above it as above the floor, to a
  // tenth of a spacing.
  EXPECT_GE(solid.lowest, -1e-9);
  EXPECT_NEAR(solid.lowest, floor.lowest, 0.1 * kSpacing);
  // At rest: the lattice settles at a few cm/s either way (measured 0.059 m/s on the solid,
  // 0.022 on the floor: the solid's sums follow the ideal reflected lattice, the floor's images
  // the particles themselves). 0.1 m/s is under half the tall column's bound (0.25 m/s,
  // Documentation/Validation.md) and 2.5 g dt: no particle is thrown.
  EXPECT_LT(solid.fastest, 0.1);
  EXPECT_NEAR(solid.statistics.averageDensityError, floor.statistics.averageDensityError, 0.002);
  EXPECT_LT(solid.statistics.maxDensityError, 0.05);
  std::printf("on the solid: lowest %.4f m, fastest %.4f m/s, mean error %.4f %%; on the floor: "
              "%.4f m, %.4f m/s, %.4f %%\n",
    solid.lowest, solid.fastest, 100 * solid.statistics.averageDensityError, floor.lowest,
    floor.fastest, 100 * floor.statistics.averageDensityError);
}

TEST(Obstacle, AParticlePutInsideASolidEndsOnItsSurface)
{
  // One particle 0.03 m deep in the solid floor (its face at y = 0.3), without gravity: the
  // step's predict projects it along the field's gradient to the face (the box's field is
  // linear across a flat face, so its trilinear samples put the face at y = 0.3 to double
  // rounding). The projections then push it a little off the face: at the face the solid's
  // density sum and the particle's own weight exceed rho_0 (measured +0.21 mm). Below the face by
  // the depth (a push-out of the wrong sign) or left where it was would be 0.03 m off; 1 mm
  // (s / 50) tells them apart.
  Parameters p;
  p.particleSpacing = kSpacing;
  p.gravity = { 0, 0, 0 };
  p.domain = { { 0, 0, 0 }, { 0.6, 0.9, 0.6 } };
  const double depth = 0.03;
  ParticleBatch lone;
  lone.position = { { 0.3, 0.3 - depth, 0.3 } };
  lone.velocity = { { 0, 0, 0 } };
  lone.id = { 0 };
  CpuStepper<double> stepper(false, p, lone);
  stepper.setObstacles({ solidFloor() });
  stepper.step();
  Snapshot<double> state;
  stepper.read(state);
  ASSERT_EQ(state.position.size(), 1u);
  EXPECT_NEAR(state.position[0].y, 0.3, 1e-3);
  // Along the normal only: the face's gradient has no x or z part (double rounding).
  EXPECT_NEAR(state.position[0].x, 0.3, 1e-12);
  EXPECT_NEAR(state.position[0].z, 0.3, 1e-12);
}

TEST(Obstacle, NoParticleEntersASphereInTheDamBreaksWay)
{
  const test::PresetFluid setup = test::presetFluid("dam_break", 0.04);
  const double h = setup.parameters.smoothingLength();
  const Vec3d centre{ 0.9, 0.12, 0.3 };
  const double radius = 0.12;
  const DistanceGrid sphere = sphereDistance(centre, radius, 0.02, h);
  CpuStepper<float> stepper(true, setup.parameters, setup.fluid);
  stepper.setObstacles({ sphere });
  double deepest = 0;
  for (int s = 0; s < 240; ++s) // 1 s: the surge reaches the sphere at about 0.25 s
  {
    stepper.step();
    if (s % 10 == 9)
    {
      Snapshot<double> state;
      stepper.read(state);
      for (const Vec3d& x : state.position)
      {
        deepest = std::min(deepest, length(x - centre) - radius);
      }
    }
  }
  // Projected to the trilinear field's zero, within its interpolation error of the true sphere
  // (cell^2 / (4 r) = 0.8 mm) and float rounding: never a spacing inside.
  EXPECT_GT(deepest, -0.002);
  EXPECT_TRUE(stepper.statistics().finite);
  EXPECT_LT(stepper.statistics().maxSpeed, 7.5);
}

TEST(Obstacle, SerialAndOpenMPStayBitIdentical)
{
  const test::PresetFluid setup = test::presetFluid("dam_break", 0.05);
  const DistanceGrid sphere =
    sphereDistance({ 0.9, 0.12, 0.3 }, 0.12, 0.025, setup.parameters.smoothingLength());
  CpuStepper<float> serial(false, setup.parameters, setup.fluid);
  CpuStepper<float> openmp(true, setup.parameters, setup.fluid);
  serial.setObstacles({ sphere });
  openmp.setObstacles({ sphere });
  for (int s = 0; s < 80; ++s)
  {
    serial.step();
    openmp.step();
  }
  Snapshot<float> a, b;
  serial.read(a);
  openmp.read(b);
  ASSERT_EQ(a.id, b.id);
  EXPECT_EQ(std::memcmp(a.position.data(), b.position.data(), a.position.size() * sizeof(a.position[0])), 0);
  EXPECT_EQ(std::memcmp(a.velocity.data(), b.velocity.data(), a.velocity.size() * sizeof(a.velocity[0])), 0);
}

namespace
{

// `ranks` CPU sub-domains (threads) of the dam break at 4 cm with a sphere just beyond the
// column's face (within h of its front particles from the start), `steps` steps in double;
// every rank's particles, rank after rank.
Snapshot<double> decomposedWithSphere(int ranks, int steps, std::size_t* ghosts = nullptr)
{
  const test::PresetFluid setup = test::presetFluid("dam_break", 0.04);
  const DistanceGrid sphere = sphereDistance({ 0.5, 0.1, 0.3 }, 0.09, 0.02, 0.08);
  std::vector<Snapshot<double>> parts(static_cast<std::size_t>(ranks));
  distributed::runThreadCluster(ranks, [&](distributed::Communicator& communicator) {
    distributed::SubdomainStepper<double> stepper(communicator, false, setup.parameters, setup.fluid);
    stepper.setObstacles({ sphere });
    for (int s = 0; s < steps; ++s)
    {
      stepper.step();
    }
    if (ghosts && communicator.rank() == 0)
    {
      *ghosts = stepper.lastExchange().ghosts;
    }
    stepper.read(parts[static_cast<std::size_t>(communicator.rank())]);
  });
  return test::joined(parts);
}

} // namespace

TEST(Obstacle, DecomposedCpuRanksMatchOneRankAndTheSerialBackend)
{
  // One rank runs the same stages on the same particles in the same order as the serial
  // stepper: not one bit may differ, solids included.
  const test::PresetFluid setup = test::presetFluid("dam_break", 0.04);
  auto serial = makeStepper(Backend::Serial, Precision::Double, setup.parameters, setup.fluid);
  serial->setObstacles({ sphereDistance({ 0.5, 0.1, 0.3 }, 0.09, 0.02, 0.08) });
  for (int s = 0; s < 20; ++s)
  {
    serial->step();
  }
  Snapshot<double> reference;
  serial->read(reference);
  const Snapshot<double> one = decomposedWithSphere(1, 20);
  ASSERT_EQ(one.id, reference.id);
  const std::size_t n = reference.id.size();
  EXPECT_EQ(std::memcmp(one.position.data(), reference.position.data(), n * sizeof(Vec3d)), 0);
  EXPECT_EQ(std::memcmp(one.density.data(), reference.density.data(), n * sizeof(double)), 0);

  // The solid changed the flow (else the comparisons below would say nothing about it).
  auto free = makeStepper(Backend::Serial, Precision::Double, setup.parameters, setup.fluid);
  for (int s = 0; s < 20; ++s)
  {
    free->step();
  }
  Snapshot<double> without;
  free->read(without);
  EXPECT_GT(test::maxRelativePositionError(without, reference), 1e-6);

  // More ranks sum a particle's neighbours in another order: rounding only (~1e-16 a sum, well
  // under 1e-9 after ten steps), where a solid missing on a rank moves its particles by ~1e-3.
  const Snapshot<double> ten = decomposedWithSphere(1, 10);
  for (int ranks : { 2, 3 })
  {
    std::size_t ghosts = 0;
    const Snapshot<double> many = decomposedWithSphere(ranks, 10, &ghosts);
    EXPECT_LE(test::maxRelativePositionError(many, ten), 1e-9) << ranks << " ranks";
    EXPECT_GT(ghosts, 0u) << ranks << " ranks: rank 0 had no ghosts";
  }
}

namespace
{

// The dam break's tank with a sphere standing on the floor in the surge's way and a box wall
// that cuts into the column's far corner: the fluid inside the box is removed.
const char* const kSceneWithSolids = R"({
  "name": "dam_break_solids",
  "domain": { "min": [0, 0, 0], "max": [1.6, 0.8, 0.6] },
  "fluid": [ { "type": "box", "min": [0, 0, 0], "max": [0.4, 0.6, 0.6] } ],
  "obstacles": [
    { "type": "sphere", "center": [0.9, 0.12, 0.3], "radius": 0.12 },
    { "type": "box", "min": [0.3, -0.5, -0.5], "max": [0.5, 0.2, 0.2] }
  ]
})";

std::string sceneError(const std::string& obstacles)
{
  try
  {
    parseScene(R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
      "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}],
      "obstacles": )" + obstacles + "}");
  }
  catch (const InvalidInput& error)
  {
    return error.what();
  }
  return "";
}

} // namespace

TEST(Obstacle, ASceneFileNamesItsSolidsAndTheFluidInsideThemIsRemoved)
{
  const Scene scene = parseScene(kSceneWithSolids);
  ASSERT_EQ(scene.solids.size(), 2u);
  Parameters p;
  p.particleSpacing = 0.04;
  Simulation simulation(scene, p, Backend::OpenMP, Precision::Single);
  // The column is 10 x 15 x 15 sites; the box takes x 0.3..0.4 (2 sites) by y < 0.2 (5) by
  // z < 0.2 (5) of it: 50 particles.
  EXPECT_EQ(simulation.seededInsideSolids(), 50u);
  EXPECT_EQ(simulation.stepper().size(), 10u * 15 * 15 - 50);
  EXPECT_EQ(simulation.idCount(), static_cast<std::int64_t>(simulation.stepper().size()));
  simulation.advanceTo(0.5);
  Snapshot<double> state;
  simulation.stepper().read(state);
  double deepest = 0;
  for (const Vec3d& x : state.position)
  {
    deepest = std::min(deepest, length(x - Vec3d{ 0.9, 0.12, 0.3 }) - 0.12);
    if (x.x > 0.3 && x.x < 0.5 && x.y < 0.2 && x.z < 0.2)
    {
      deepest = std::min(deepest, -std::min({ x.x - 0.3, 0.5 - x.x, 0.2 - x.y, 0.2 - x.z }));
    }
  }
  EXPECT_GT(deepest, -0.002); // as for the sphere above: the field's interpolation and rounding
}

TEST(Obstacle, SceneErrorsNameTheObstacle)
{
  EXPECT_NE(sceneError("3").find(".obstacles = 3: must be an array"), std::string::npos)
    << sceneError("3");
  EXPECT_NE(sceneError(R"([{"type": "cone"}])").find(".obstacles[0].type"), std::string::npos);
  EXPECT_NE(sceneError(R"([{"type": "sphere", "center": [0, 0, 0], "radius": -1}])")
              .find(".obstacles[0].radius = -1: must be > 0"),
    std::string::npos);
  EXPECT_NE(sceneError(R"([{"type": "box", "min": [0, 0, 0], "max": [1, 0, 1]}])")
              .find(".obstacles[0].max"),
    std::string::npos);
  EXPECT_NE(sceneError(R"([{"type": "box", "min": [0, 0, 0], "max": [1, 1, 1], "size": 2}])")
              .find("size"),
    std::string::npos);
  // Outside the domain: named when the run is built.
  Scene scene = parseScene(R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
    "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}],
    "obstacles": [{"type": "sphere", "center": [5, 5, 5], "radius": 0.5}]})");
  Parameters p;
  p.particleSpacing = 0.05;
  try
  {
    Simulation simulation(scene, p, Backend::Serial, Precision::Single);
    ADD_FAILURE() << "an obstacle outside the domain was accepted";
  }
  catch (const InvalidInput& error)
  {
    EXPECT_NE(std::string(error.what()).find("obstacles[0]: lies outside the domain"),
      std::string::npos)
      << error.what();
  }
}

TEST(Obstacle, AMeshObstacleNamesItsFileRelativeToTheSceneFile)
{
  EXPECT_NE(sceneError(R"([{"type": "mesh"}])").find(".obstacles[0]"), std::string::npos);
  EXPECT_NE(sceneError(R"([{"type": "mesh", "file": 3}])").find(".obstacles[0].file = 3"),
    std::string::npos);
  EXPECT_NE(sceneError(R"([{"type": "mesh", "file": "a.stl", "thickness": -0.1}])")
              .find(".obstacles[0].thickness = -0.1: must be >= 0"),
    std::string::npos);

  // The file is named relative to the scene file's folder.
  const std::filesystem::path folder =
    std::filesystem::temp_directory_path() / ("pbf_mesh_scene_" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  const std::filesystem::path path = folder / "scene.json";
  {
    std::ofstream out(path);
    out << R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
      "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}],
      "obstacles": [{"type": "mesh", "file": "parts/rock.stl", "thickness": 0.02}]})";
  }
  const Scene scene = loadSceneFile(path.string());
  std::filesystem::remove_all(folder);
  ASSERT_EQ(scene.solids.size(), 1u);
  EXPECT_EQ(scene.solids[0].kind, SolidRegion::Kind::Mesh);
  EXPECT_EQ(scene.solids[0].file, (folder / "parts" / "rock.stl").string());
  EXPECT_EQ(scene.solids[0].thickness, 0.02);

  // Without the plugin nothing reads the file: the solver says so instead of running without it.
  Parameters p;
  p.particleSpacing = 0.05;
  try
  {
    Simulation simulation(scene, p, Backend::Serial, Precision::Single);
    ADD_FAILURE() << "a mesh obstacle nobody read was accepted";
  }
  catch (const InvalidInput& error)
  {
    const std::string text = error.what();
    EXPECT_NE(text.find("obstacles[0].file = \"" + scene.solids[0].file + "\""), std::string::npos)
      << text;
    EXPECT_NE(text.find("ParaView plugin"), std::string::npos) << text;
  }
}
