// Behaviour of the PBF step on small scenes: rest, symmetry, stability of vorticity confinement.
#include "Backends.h"
#include "CpuStepper.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

using namespace pbf;
using namespace pbf::test;

TEST(Physics, InitialLatticeReadsRestDensityEverywhereIncludingAtTheWalls)
{
  // Mirror walls continue the lattice beyond the box, so corner and face sites read rho_0 too.
  Parameters p;
  for (Precision precision : { Precision::Single, Precision::Double })
  {
    const Scene block = restingBlock(10, p.particleSpacing);
    Simulation simulation(block, p, Backend::Serial, precision);
    Snapshot<double> s;
    simulation.stepper().read(s);
    // Double: summation rounding only. Single: ~30 terms of 1e-7 relative rounding each.
    const double tolerance = precision == Precision::Double ? 1e-12 : 1e-5;
    std::size_t checked = 0;
    for (std::size_t i = 0; i < s.density.size(); ++i)
    {
      // The top is a free surface, not a wall: particles within h of it lack neighbours.
      if (s.position[i].y < block.boxes[0].max.y - p.smoothingLength())
      {
        ASSERT_NEAR(s.density[i] / p.restDensity, 1.0, tolerance);
        ++checked;
      }
    }
    EXPECT_EQ(checked, 10u * 10u * 8u); // every layer but the top two
  }
}

TEST(Physics, RestingBlockStaysAtRest)
{
  Parameters p;
  Simulation simulation(restingBlock(12, p.particleSpacing), p, Backend::OpenMP, Precision::Single);
  simulation.advance(200);
  const Statistics s = simulation.stepper().statistics();
  ASSERT_TRUE(s.finite);
  EXPECT_LT(s.averageDensityError, 0.01); // the required bound: 1% average compression
  // Each step gravity adds g dt of fall that a finite number of Jacobi iterations undoes only
  // approximately, so PBF at rest keeps velocity noise of order g dt (0.04 m/s here). Require the
  // rms below g dt and the largest below 5 g dt, against the ~2 m/s a released column reaches.
  const double gdt = length(p.gravity) * p.timeStep;
  const double mass = calibratedParticleMass(p);
  const double rmsSpeed = std::sqrt(2 * s.kineticEnergy / (mass * s.particles));
  EXPECT_LT(rmsSpeed, gdt);
  EXPECT_LT(s.maxSpeed, 5 * gdt);
  // The block neither sank into the floor nor rose: its potential energy is within 2%.
  Simulation fresh(restingBlock(12, p.particleSpacing), p, Backend::Serial, Precision::Single);
  EXPECT_NEAR(potentialEnergy(simulation) / potentialEnergy(fresh), 1.0, 0.02);
}

TEST(Physics, SymmetricSceneDevelopsNoNetSidewaysMomentum)
{
  // The double dam break is mirror-symmetric in x and fills the tank in z, so the net x and z
  // momentum must stay zero while each column carries momentum of order M sqrt(g H).
  Parameters p;
  p.particleSpacing = 0.04;
  Simulation simulation(presetScene("double_dam_break"), p, Backend::OpenMP, Precision::Double);
  simulation.advance(48); // 0.2 s: both columns are collapsing and spreading fast
  Snapshot<double> s;
  simulation.stepper().read(s);
  const double mass = calibratedParticleMass(p);
  double scale = 0;
  Vec3d momentum{ 0, 0, 0 };
  for (const Vec3d& v : s.velocity)
  {
    scale += mass * length(v);
    momentum += v * mass;
  }
  ASSERT_GT(scale, 0);
  // Mirror symmetry holds up to rounding: measured ~1e-10 of the total absolute momentum at this
  // time. A biased loop order or wall treatment grows linearly from the first step and shows
  // at 1e-3 or more. Later, when the columns collide, rounding differences that flip a neighbour
  // test at r = h are amplified by the splash, so the check is made before that.
  EXPECT_LT(std::abs(momentum.x), 1e-7 * scale) << "scale " << scale;
  EXPECT_LT(std::abs(momentum.z), 1e-7 * scale) << "scale " << scale;
}

TEST(Physics, VorticityConfinementKeepsKineticEnergyBoundedInAClosedBox)
{
  // A dam break in a closed box with confinement 100 times the default, for 3000 steps: the
  // kinetic energy must never exceed what gravity has released, and must decay as the water
  // settles. An unstable confinement term feeds energy in and fails both.
  Parameters p;
#ifdef PBF_SANITIZE
  p.particleSpacing = 0.08; // 245 particles, not 1152: 7 x faster, under the sanitizers' 6 x
#else
  p.particleSpacing = 0.05;
#endif
  p.vorticityEpsilon = 1.0;
  Simulation simulation(presetScene("dam_break"), p, Backend::OpenMP, Precision::Single);
  const double initialPotential = potentialEnergy(simulation);
  double maxKinetic = 0, released = 0;
  for (int block = 0; block < 30; ++block)
  {
    simulation.advance(100);
    const Statistics s = simulation.stepper().statistics();
    ASSERT_TRUE(s.finite) << "step " << simulation.stepCount();
    released = std::max(released, initialPotential - potentialEnergy(simulation));
    maxKinetic = std::max(maxKinetic, s.kineticEnergy);
    ASSERT_LE(s.kineticEnergy, released) << "step " << simulation.stepCount();
  }
  EXPECT_GT(maxKinetic, 0.1 * released); // the flow really moved
  EXPECT_LT(simulation.stepper().statistics().kineticEnergy, 0.02 * maxKinetic);
}

TEST(Physics, OneStepsConfinementIsEpsilonTimesNCrossOmegaAndLinearInEpsilon)
{
  // A block in the shear flow v = (a (y - y_b)^2, 0, 0), y_b below it: omega = -2 a (y - y_b) z,
  // so |omega| grows along +y, N = y and eq. 16 gives f = epsilon (N x omega) =
  // -2 a epsilon (y - y_b) x, an acceleration. One step at several epsilon from the same state,
  // without gravity or XSPH: the projections and the rest do not depend on epsilon, so the
  // difference of the new velocities from epsilon = 0 is the confinement's dt f alone.
  Parameters p;
  p.gravity = { 0, 0, 0 };
  p.xsphViscosity = 0;
  p.xsphHyperViscosity = 0;
  p.timeStepping = TimeStepping::Fixed;
  p.densityErrorTolerance = 0; // a fixed count of projections: the same work at every epsilon
  p.solverIterations = 4;
  const double s = p.particleSpacing, a = 2.0, yb = 0.3 - 4 * s;
  p.domain = { { 0, 0, 0 }, { 1, 1, 1 } };
  Scene scene;
  scene.domain = p.domain;
  scene.boxes.push_back({ { 0.3, 0.3, 0.3 }, { 0.3 + 16 * s, 0.3 + 16 * s, 0.3 + 16 * s },
    { 0, 0, 0 } });
  ParticleBatch block = fillScene(scene, p);
  for (std::size_t i = 0; i < block.position.size(); ++i)
  {
    const double y = block.position[i].y - yb;
    block.velocity[i] = { a * y * y, 0, 0 };
  }
  auto velocities = [&](double epsilon) {
    Parameters q = p;
    q.vorticityEpsilon = epsilon;
    CpuStepper<double> stepper(false, q, block);
    stepper.step();
    Snapshot<double> state;
    stepper.read(state);
    std::map<std::int64_t, std::pair<Vec3d, Vec3d>> byId; // id -> (position, velocity)
    for (std::size_t i = 0; i < state.id.size(); ++i)
    {
      byId[state.id[i]] = { state.position[i], state.velocity[i] };
    }
    return byId;
  };
  const double epsilon = 0.5; // m/s
  const auto none = velocities(0.0), once = velocities(epsilon), twice = velocities(2 * epsilon);
  const double h = p.smoothingLength();
  double worst = 0, worstLinear = 0;
  std::size_t checked = 0;
  for (const auto& [id, state] : none)
  {
    const Vec3d& x = state.first;
    // The bulk: 2 h from every face of the block, where eta (a sum over h of omega, itself a sum
    // over h) sees full neighbourhoods; within 2 h of a face the error reaches 28 %.
    if (std::min({ x.x, x.y, x.z }) < 0.3 + 2 * h ||
      std::max({ x.x, x.y, x.z }) > 0.3 + 16 * s - 2 * h)
    {
      continue;
    }
    const Vec3d confinement = once.at(id).second - state.second;
    const Vec3d expected{ -2 * a * (x.y - yb) * epsilon * p.timeStep, 0, 0 };
    worst = std::max(worst, length(confinement - expected) / length(expected));
    const Vec3d doubled = twice.at(id).second - state.second;
    worstLinear = std::max(worstLinear, length(doubled - confinement * 2.0) / length(expected));
    ++checked;
  }
  std::printf("confinement of %zu bulk particles: worst error %.3g of eps (N x omega) dt, "
              "linearity %.3g\n", checked, worst, worstLinear);
  EXPECT_GT(checked, 500u);
  // The SPH curl and gradient of a quadratic field on the lattice: within 10 % of the exact
  // (measured 5.3 %: the spiky gradient's moment on the calibrated lattice is not exactly the
  // identity); a doubled or halved confinement is 100 % or 50 % off.
  EXPECT_LT(worst, 0.1);
  // Linear in epsilon: the velocity is v + eps dt (N x omega), rounding of doubles on velocities
  // 1e4 times the difference apart (1e-16 x 1e4).
  EXPECT_LT(worstLinear, 1e-9);
}

TEST(Physics, ParticlesStayInsideTheDomain)
{
  Parameters p;
  p.particleSpacing = 0.04;
  Simulation simulation(presetScene("blob"), p, Backend::OpenMP, Precision::Single);
  simulation.advance(200);
  Snapshot<double> s;
  simulation.stepper().read(s);
  const Box& d = simulation.parameters().domain;
  for (const Vec3d& x : s.position)
  {
    ASSERT_TRUE(x.x >= d.min.x && x.y >= d.min.y && x.z >= d.min.z && x.x <= d.max.x &&
      x.y <= d.max.y && x.z <= d.max.z);
  }
}

TEST(Physics, LambdaIsThePapersStepForTheDensityConstraint)
{
  // The density constraint's strength, checked against the paper's equations written out here
  // (poly6 density, eq. 2; C_i = rho_i / rho_0 - 1, eq. 1; spiky gradients, eq. 8; lambda_i,
  // eq. 11), not against an earlier output of the code: with adaptive projections a weaker
  // lambda only takes more iterations, and the flow tests cannot see it.
  Parameters p;
  p.particleSpacing = 0.05;
  p.timeStepping = TimeStepping::Fixed;
  p.densityErrorTolerance = 0;
  p.solverIterations = 1; // lambda is evaluated once, at the predicted = initial positions
  p.gravity = { 0.0, 0.0, 0.0 };
  p.mirrorWalls = false;
  p.domain = { { -1.0, -1.0, -1.0 }, { 1.0, 1.0, 1.0 } }; // no wall within reach
  const double s = p.particleSpacing, h = p.smoothingLength(), rho0 = p.restDensity;

  // The kernels of the paper.
  const double pi = 3.14159265358979323846;
  auto poly6 = [&](double r2) { return r2 < h * h ? 315.0 / (64.0 * pi * std::pow(h, 9)) * std::pow(h * h - r2, 3) : 0.0; };
  auto spiky = [&](const Vec3d& r) {
    const double d = std::sqrt(dot(r, r));
    return d > 0 && d < h ? r * (-45.0 / (pi * std::pow(h, 6)) * (h - d) * (h - d) / d) : Vec3d{ 0, 0, 0 };
  };
  // The mass that makes the rest lattice read rho_0, and the bulk denominator that scales epsilon,
  // summed over the lattice here.
  double latticeSum = 0;
  std::vector<Vec3d> sites;
  const int reach = static_cast<int>(std::ceil(h / s));
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int c = -reach; c <= reach; ++c)
      {
        const Vec3d r{ a * s, b * s, c * s };
        latticeSum += poly6(dot(r, r));
        sites.push_back(r);
      }
  const double mass = rho0 / latticeSum;
  double bulkDenominator = 0;
  for (const Vec3d& r : sites)
  {
    const Vec3d g = spiky(r) * (mass / rho0);
    bulkDenominator += dot(g, g);
  }
  const LatticeCalibration lattice = calibrateLattice(p);
  EXPECT_NEAR(lattice.mass, mass, 1e-12 * mass);
  EXPECT_NEAR(lattice.gradientSum, bulkDenominator, 1e-9 * bulkDenominator);

  // A block compressed to 0.96 s, jittered so that no sum cancels by symmetry.
  ParticleBatch batch;
  std::int64_t id = 0;
  for (int a = 0; a < 7; ++a)
    for (int b = 0; b < 7; ++b)
      for (int c = 0; c < 7; ++c)
      {
        const double j = 0.03 * s * std::sin(1.7 * a + 2.3 * b + 3.1 * c);
        batch.position.push_back({ 0.96 * s * a + j, 0.96 * s * b - 0.5 * j, 0.96 * s * c + 0.7 * j });
        batch.velocity.push_back({ 0, 0, 0 });
        batch.id.push_back(id++);
      }
  auto stepper = makeStepper(Backend::Serial, Precision::Double, p, batch);
  stepper->step();
  Snapshot<double> out;
  stepper->read(out);

  const std::size_t n = batch.position.size();
  double worst = 0, strongest = 0;
  for (std::size_t k = 0; k < out.id.size(); ++k)
  {
    const std::size_t i = static_cast<std::size_t>(out.id[k]);
    double rho = 0, sumGradJ2 = 0;
    Vec3d gradI{ 0, 0, 0 };
    for (std::size_t j = 0; j < n; ++j)
    {
      const Vec3d r = batch.position[i] - batch.position[j];
      rho += mass * poly6(dot(r, r));
      const Vec3d g = spiky(r) * (mass / rho0);
      gradI += g;
      sumGradJ2 += dot(g, g);
    }
    const double C = std::max(rho / rho0 - 1.0, 0.0); // the unilateral constraint (default)
    const double lambda = -lattice.jacobiRelaxation * C /
      (sumGradJ2 + dot(gradI, gradI) + p.relaxation * bulkDenominator);
    EXPECT_NEAR(out.density[k], rho, 1e-10 * rho) << "particle " << i;
    worst = std::max(worst, std::abs(out.lambda[k] - lambda));
    strongest = std::max(strongest, std::abs(lambda));
  }
  // The block is compressed by about 13 %: lambda is far from 0, and double precision sums in
  // another order agree to ~1e-15 of it.
  ASSERT_GT(strongest, 0.0);
  EXPECT_LT(worst, 1e-9 * strongest) << "largest |lambda| " << strongest;
}
