// Surface tension (Parameters::surfaceTension, Solver/Physics/SurfaceTension.h): bad values are
// named, a drop at rest is pulled in by about 2 sigma / R over its surface while a flat surface
// feels nothing, and every CPU backend agrees. The drop's oscillation against Rayleigh's period
// is in Testing/Validation (Droplet.*).
#include "Backends.h"
#include "Distributed/SubdomainStepper.h"
#include "Distributed/ThreadCluster.h"
#include "Equations.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>

using namespace pbf;

namespace
{

constexpr double kPi = 3.14159265358979323846;

std::string errorOf(const Parameters& p)
{
  try
  {
    p.validate();
  }
  catch (const InvalidInput& e)
  {
    return e.what();
  }
  return "";
}

// A sphere of `radius` on the lattice of spacing s at the centre (2 R, 2 R, 2 R) of a cube 4 R
// wide (away from the origin, where a relative error has no scale), without gravity, s_corr,
// viscosity or vorticity: what moves it in its first step is the surface force alone.
struct Drop
{
  Scene scene;
  Parameters parameters;
  ParticleBatch fluid;
};
Drop dropAtRest(double radius, double s, double sigma)
{
  Drop d;
  d.scene.domain = { { 0, 0, 0 }, { 4 * radius, 4 * radius, 4 * radius } };
  d.scene.spheres.push_back({ { 2 * radius, 2 * radius, 2 * radius }, radius, {}, 0 });
  d.parameters = withSceneDomain(Parameters(), d.scene);
  d.parameters.particleSpacing = s;
  d.parameters.gravity = { 0, 0, 0 };
  d.parameters.surfaceTension = sigma;
  d.parameters.sCorrK = 0;
  d.parameters.xsphViscosity = 0;
  d.parameters.xsphHyperViscosity = 0;
  d.parameters.vorticityEpsilon = 0;
  d.parameters.timeStepping = TimeStepping::Fixed;
  d.parameters.timeStep = 1e-3;
  d.fluid = fillScene(d.scene, d.parameters);
  return d;
}

} // namespace

TEST(SurfaceTension, BadValuesAreNamed)
{
  Parameters p;
  p.surfaceTension = -1;
  EXPECT_NE(errorOf(p).find("surfaceTension = -1"), std::string::npos) << errorOf(p);
  p.surfaceTension = 0.072;
  Liquid water, oil;
  water.name = "water";
  oil.name = "oil";
  oil.restDensity = 800;
  oil.surfaceTension = -0.5;
  p.liquids = { water, oil };
  EXPECT_NE(errorOf(p).find("liquids[1].surfaceTension = -0.5"), std::string::npos) << errorOf(p);
  EXPECT_NE(errorOf(p).find("\"oil\""), std::string::npos) << errorOf(p);
  // A liquid without its own takes the parameter's.
  p.liquids[1].surfaceTension = 0.03;
  EXPECT_EQ(errorOf(p), "");
  EXPECT_EQ(p.liquidSurfaceTension(0), 0.072);
  EXPECT_EQ(p.liquidSurfaceTension(1), 0.03);
  EXPECT_EQ(p.largestSurfaceTension(), 0.072);
  const std::string scene = R"({ "name": "x", "domain": { "min": [0, 0, 0], "max": [1, 1, 1] },
    "liquids": [ { "name": "water", "restDensity": 1000, "surfaceTension": -2 } ],
    "fluid": [ { "type": "box", "min": [0, 0, 0], "max": [0.2, 0.2, 0.2] } ] })";
  try
  {
    parseScene(scene);
    ADD_FAILURE() << "a negative surface tension parsed";
  }
  catch (const InvalidInput& e)
  {
    EXPECT_NE(std::string(e.what()).find(".liquids[0].surfaceTension = -2"), std::string::npos)
      << e.what();
  }
}

namespace
{
// The message of a scene that does not parse; "" when it parses.
std::string sceneError(const std::string& liquids, const std::string& obstacles = "")
{
  const std::string scene = R"({ "domain": { "min": [0, 0, 0], "max": [1, 1, 1] }, "liquids": )" +
    liquids + R"(, "fluid": [ { "type": "box", "min": [0, 0, 0], "max": [0.2, 0.2, 0.2] } ])" +
    obstacles + "}";
  try
  {
    parseScene(scene);
  }
  catch (const InvalidInput& e)
  {
    return e.what();
  }
  return "";
}
} // namespace

TEST(SurfaceTension, BadContactAnglesAreNamed)
{
  Parameters p;
  p.contactAngle = 200;
  EXPECT_NE(errorOf(p).find("contactAngle = 200"), std::string::npos) << errorOf(p);
  p.contactAngle = 120;
  Liquid water;
  water.name = "water";
  water.wallContactAngle = -5;
  p.liquids = { water };
  EXPECT_NE(errorOf(p).find("liquids[0].contactAngles.walls = -5"), std::string::npos)
    << errorOf(p);
  // A liquid without its own takes the parameter's; 90 everywhere is no adhesion.
  p.liquids[0].wallContactAngle = std::nan("");
  EXPECT_EQ(errorOf(p), "");
  EXPECT_EQ(p.liquidWallContactAngle(0), 120.0);
  p.surfaceTension = 0.07;
  EXPECT_TRUE(p.wallAdhesion());
  p.contactAngle = 90;
  EXPECT_FALSE(p.wallAdhesion());

  const std::string cup =
    R"(, "obstacles": [ { "type": "sphere", "name": "cup", "center": [0.6, 0.6, 0.6], "radius": 0.1 } ])";
  EXPECT_EQ(sceneError(R"([ { "name": "water", "restDensity": 1000, "contactAngles": { "walls": 60 } } ])"), "");
  std::string e = sceneError(
    R"([ { "name": "water", "restDensity": 1000, "contactAngles": { "walls": 190 } } ])");
  EXPECT_NE(e.find(".liquids[0].contactAngles.walls = 190: must lie in [0, 180]"), std::string::npos) << e;
  e = sceneError(R"([ { "name": "water", "restDensity": 1000, "contactAngles": { "cupp": 60 } } ])", cup);
  EXPECT_NE(e.find(".liquids[0].contactAngles.cupp = 60"), std::string::npos) << e;
  EXPECT_NE(e.find("no solid"), std::string::npos) << e;
  EXPECT_NE(e.find("named solids: cup"), std::string::npos) << e;
  e = sceneError(R"([ { "name": "water", "restDensity": 1000, "contactAngles": 60 } ])");
  EXPECT_NE(e.find(".liquids[0].contactAngles = 60"), std::string::npos) << e;
  // A solid's angle: the obstacle's for every liquid, a liquid's by the solid's name for that one.
  const std::string two = R"([ { "name": "water", "restDensity": 1000, "contactAngles": { "cup": 60 } },
    { "name": "oil", "restDensity": 800 } ])";
  const std::string cupAt120 =
    R"(, "obstacles": [ { "type": "sphere", "name": "cup", "center": [0.6, 0.6, 0.6], "radius": 0.1,
    "contactAngle": 120 } ])";
  EXPECT_EQ(sceneError(two, cupAt120), "");
  const Scene scene = parseScene(R"({ "domain": { "min": [0, 0, 0], "max": [1, 1, 1] }, "liquids": )" +
    two + R"(, "fluid": [ { "type": "box", "min": [0, 0, 0], "max": [0.2, 0.2, 0.2] } ])" +
    cupAt120 + "}");
  EXPECT_EQ(scene.solids.at(0).contactAngle[0], 60.0);
  EXPECT_EQ(scene.solids.at(0).contactAngle[1], 120.0);
  EXPECT_EQ(scene.solids.at(0).contactAngle[2], 120.0);
  // And through the field into the stages: cos 60 for water, cos 120 for oil, exactly 0 at 90.
  DistanceGrid grid;
  grid.contactAngle = scene.solids[0].contactAngle;
  grid.contactAngle[2] = 90.0;
  grid.cell = 1;
  const DistanceGridView<double> view = grid.view<double>(nullptr, nullptr);
  EXPECT_NEAR(view.contactCos[0], 0.5, 1e-15);
  EXPECT_NEAR(view.contactCos[1], -0.5, 1e-15);
  EXPECT_EQ(view.contactCos[2], 0.0);
  e = sceneError(R"([ { "name": "water", "restDensity": 1000 } ])",
    R"(, "obstacles": [ { "type": "box", "min": [0.5, 0, 0], "max": [0.6, 1, 1], "contactAngle": -1 } ])");
  EXPECT_NE(e.find(".obstacles[0].contactAngle = -1: must lie in [0, 180]"), std::string::npos) << e;
}

// A drop of 10 spacings at rest: in its first step each particle's velocity is dt times its
// surface acceleration, whose inward pull summed over the drop, sum m a . (-x / |x|), is the
// Laplace pressure over the surface, 2 sigma / R 4 pi R^2. The lattice's sphere is ragged on the
// scale of a spacing, and its normals, smoothed over twice the kernel's support, see a somewhat
// rounder surface at its edges: measured -18.3 % (+25.5 % with the particles' own normals). A
// sign error or a lost calibration (without the colour share the pull is about half) fails the
// 35 % bound; the drop's oscillation (Droplet.*) checks the force's effect within 15 %.
TEST(SurfaceTension, ADropAtRestIsPulledInByTheLaplacePressure)
{
  const double radius = 0.1, s = 0.01, sigma = 2.0;
  const Drop d = dropAtRest(radius, s, sigma);
  auto stepper = makeStepper(Backend::OpenMP, Precision::Double, d.parameters, d.fluid);
  stepper->step();
  Snapshot<double> out;
  stepper->read(out);
  const double m = calibratedParticleMass(d.parameters);
  double inward = 0;
  const Vec3d centre{ 2 * radius, 2 * radius, 2 * radius };
  for (std::size_t i = 0; i < out.position.size(); ++i)
  {
    const Vec3d x = out.position[i] - centre;
    if (length(x) > s / 2) // the centre's particle has no direction (and feels nothing)
    {
      inward -= m * dot(out.velocity[i], x) / (length(x) * d.parameters.timeStep);
    }
  }
  const double laplace = 2 * sigma / radius * 4 * kPi * radius * radius;
  std::printf("inward pull %.4f N against 2 sigma / R 4 pi R^2 = %.4f N (%+.1f %%), %zu particles\n",
    inward, laplace, 100 * (inward / laplace - 1), out.position.size());
  EXPECT_NEAR(inward, laplace, 0.35 * laplace);
}

// A flat surface feels nothing: fluid filling the bottom of a box without gravity stays at rest
// in its first step, up to the walls, whose mirror images continue the colour (the surface meets
// them at a right angle).
TEST(SurfaceTension, AFlatSurfaceFeelsNothing)
{
  Scene scene;
  scene.domain = { { 0, 0, 0 }, { 0.2, 0.2, 0.2 } };
  scene.boxes.push_back({ { 0, 0, 0 }, { 0.2, 0.1, 0.2 }, {}, 0 });
  Parameters p = dropAtRest(0.1, 0.01, 2.0).parameters;
  p.domain = scene.domain;
  auto stepper = makeStepper(Backend::OpenMP, Precision::Double, p, fillScene(scene, p));
  stepper->step();
  Snapshot<double> out;
  stepper->read(out);
  double fastest = 0;
  for (std::size_t i = 0; i < out.position.size(); ++i)
  {
    fastest = std::max(fastest, length(out.velocity[i]));
  }
  // Rounding only (measured 1.4e-14 m/s); a drop's surface of this spacing moves at about
  // 1e-3 m/s in its first step, and the same fluid without the walls' images in the colour
  // moved at 0.025 m/s where its surface meets them.
  EXPECT_LT(fastest, 1e-9) << "the flat surface moved";
}

// OpenMP is bit-identical to serial and one rank too; two and three ranks are within 1e-9
// (DistributedTest's bound), which needs each ghost's colour gradient.
TEST(SurfaceTension, EveryCpuBackendAgrees)
{
  Drop d = dropAtRest(0.06, 0.01, std::getenv("PBF_SIGMA0") ? 0.0 : 2.0);
  d.parameters.sCorrK = 0.1;
  d.parameters.densityErrorTolerance = 0;
  d.parameters.solverIterations = 4;
  auto run = [&](Backend backend) {
    auto stepper = makeStepper(backend, Precision::Double, d.parameters, d.fluid);
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
  double moved = 0;
  for (std::size_t i = 0; i < serial.position.size(); ++i)
  {
    moved = std::max(moved, length(serial.velocity[i]));
  }
  EXPECT_GT(moved, 1e-4) << "the drop's surface did not move";
  for (int ranks : { 1, 2, 3 })
  {
    std::vector<Snapshot<double>> parts(static_cast<std::size_t>(ranks));
    distributed::runThreadCluster(ranks, [&](distributed::Communicator& communicator) {
      distributed::SubdomainStepper<double> stepper(communicator, false, d.parameters, d.fluid);
      for (int s = 0; s < 20; ++s)
      {
        stepper.step();
      }
      stepper.read(parts[static_cast<std::size_t>(communicator.rank())]);
    });
    EXPECT_LE(test::maxRelativePositionError(test::joined(parts), serial), ranks == 1 ? 0.0 : 1e-9)
      << ranks << " ranks";
  }
}

// Young's force at a wall for the walls' contact angle theta, from the parameters through the
// step's wallCos (StepTime) into wallYoungForce: a surface particle h/4 above the floor whose
// normal n = (-0.6, 0.8, 0) (into the liquid, which lies towards -x) gets sigma cos(theta) per
// unit length of the line, along the floor away from the liquid (+x) for theta < 90, towards it
// for theta > 90, none at 90: F = (n.nw nw - n) cos(theta) |grad c| 2 (1 - d / h) / h. The
// tolerance is rounding: 1e-15 relative on cos(theta) (cos of the rounded pi / 2 is 6e-17) and
// on the force's few products (1e-13 of its scale); sin(theta) in place of cos(theta) is off by
// 0.37 at 60 degrees and by 1 at 90.
TEST(SurfaceTension, YoungsForceAtAWallIsAlongTheWallByTheContactAnglesCosine)
{
  Parameters p;
  p.domain = { { 0, 0, 0 }, { 1, 1, 1 } };
  p.particleSpacing = 0.02;
  p.surfaceTension = 0.072;
  const double h = p.smoothingLength();
  const Vec3d n{ -0.6, 0.8, 0 };        // unit, into the liquid: the liquid lies towards -x
  const Vec3d gradC = n * (1.06 / h);   // a flat surface's |grad c| h (SurfaceTension.h)
  const double d = 0.25 * h;            // above the floor, the nearest wall
  const Vec3d at{ 0.5, d, 0.5 };
  const double line = length(gradC) * 2 * (1 - d / h) / h;
  for (double theta : { 60.0, 90.0, 120.0 })
  {
    p.contactAngle = theta;
    const double cosTheta = std::cos(theta * kPi / 180);
    const StepTime<double> time = StepTime<double>::make(p, calibrateLattice(p), 1e-3);
    EXPECT_NEAR(time.wallCos[0], cosTheta, 1e-15) << theta << " degrees";
    const Coefficients<double> c = Coefficients<double>::make(p);
    EXPECT_EQ(c.wallAdhesion, theta != 90.0);
    const Vec3d f = wallYoungForce(at, n, gradC, c, time.wallCos[0]);
    // Along the floor, +x (0.6, the outward normal's part along it) times cos(theta).
    EXPECT_NEAR(f.x, 0.6 * cosTheta * line, 1e-13 * line) << theta << " degrees";
    EXPECT_NEAR(f.y, 0, 1e-13 * line) << theta << " degrees";
    EXPECT_NEAR(f.z, 0, 1e-13 * line) << theta << " degrees";
    if (theta != 90.0)
    {
      EXPECT_EQ(f.x > 0, theta < 90) << "away from the liquid below 90 degrees, towards it above";
    }
    // Beyond h from every wall: no force.
    const Vec3d far = wallYoungForce(Vec3d{ 0.5, 0.5, 0.5 }, n, gradC, c, time.wallCos[0]);
    EXPECT_EQ(length(far), 0.0);
  }
}
