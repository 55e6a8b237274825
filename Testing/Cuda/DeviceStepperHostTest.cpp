// The single-GPU stepper (Cuda/DeviceStepper.h) run on the host device policy: its schedule must
// reproduce the serial backend bit for bit, with neighbour masks (any skin, so any number of
// rebuilds) and with the cell walk, with the step captured as a graph or queued stage by stage;
// and its memory, checkpoints, scans, solids and faults behave as on the GPU. This runs
// everywhere (label "solver"); the GPU itself is tested in CudaStepperTest.cpp.
#include "Backends.h"
#include "HostExecutor.h"

#include "Cuda/DeviceStepper.h"
#include "Cuda/NeighborMasks.h"
#include "DeviceFault.h"
#include "Scene.h"
#include "Solids.h"
#include "Stepper.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

template <class Real>
using HostStepper = cuda::DeviceStepper<Real, test::HostDevicePolicy>;

struct Case
{
  const char* scene;
  int iterations;
  bool masks;
  double skin;
  bool backwards;
  double tolerance = 0; // densityErrorTolerance [%]: adaptive mode when > 0
  bool graphs = true;
  double hyper = 0;     // xsphHyperViscosity
  double chebyshev = 0; // chebyshevRho
  double sigma = 0;     // surfaceTension [N/m]
  double contactAngle = 90; // [degrees]
  bool tankLoads = false;   // the walls' loads too, checked step by step (expectSameLoads)
  bool pressureMean = false; // the pressure a running mean over the steps (setTimeStep)
};

cuda::Options optionsOf(const Case& c)
{
  cuda::Options o;
  o.search = c.masks ? cuda::NeighborSearch::RowMasks : cuda::NeighborSearch::CellWalk;
  o.skin = c.skin;
  o.graphs = c.graphs;
  return o;
}

template <class Real>
std::unique_ptr<HostStepper<Real>> hostStepper(const Parameters& p, const ParticleBatch& initial,
  const cuda::Options& options, bool backwards = false, test::HostDevicePolicy** policy = nullptr)
{
  auto device = std::make_unique<test::HostDevicePolicy>(backwards);
  if (policy)
  {
    *policy = device.get();
  }
  return std::make_unique<HostStepper<Real>>(p, initial, options, std::move(device));
}

Parameters fixedParameters(const Case& c, const Scene& scene)
{
  Parameters p;
  p.particleSpacing = 0.04;
  p.solverIterations = c.iterations;
  p.densityErrorTolerance = c.tolerance;
  p.xsphHyperViscosity = c.hyper;
  p.chebyshevRho = c.chebyshev;
  p.surfaceTension = c.sigma;
  p.contactAngle = c.contactAngle;
  p.tankLoads = c.tankLoads;
  return withSceneDomain(p, scene);
}

// A step's loads on the device schedule against the serial backend's: the same terms added in
// another order (blocks of 512 on the CPU; per warp over the step's projections, then a fixed
// tree, on the device), so the same to 1e-12 of the largest force, while a projection's share
// missed (an adaptive step's last, a blended one) is ~1e-1 of a wall's load. Returns whether a
// wall was pressed.
bool expectSameLoads(const Stepper& serial, const Stepper& device, int step)
{
  const std::vector<SolidLoad> expected = serial.lastStep().loads;
  const std::vector<SolidLoad> loads = device.lastStep().loads;
  EXPECT_EQ(loads.size(), expected.size()) << "step " << step;
  double largest = 1e-6;
  for (const SolidLoad& load : expected)
  {
    largest = std::max(largest, length(load.force));
  }
  bool pressed = false;
  for (std::size_t o = 0; o < std::min(loads.size(), expected.size()); ++o)
  {
    EXPECT_LE(length(loads[o].force - expected[o].force), 1e-12 * largest) << step << " " << o;
    EXPECT_LE(length(loads[o].torque - expected[o].torque), 1e-11 * largest) << step << " " << o;
    pressed = pressed || length(expected[o].force) > 0;
  }
  return pressed;
}

template <class Real>
Snapshot<Real> stateOf(const Stepper& stepper)
{
  Snapshot<Real> s;
  stepper.read(s);
  return s;
}

template <class Real>
void compareWithSerial(const Case& c, int steps, double* builds = nullptr)
{
  const Scene scene = presetScene(c.scene);
  const Parameters p = fixedParameters(c, scene);
  const ParticleBatch initial = fillScene(scene, p);
  const Precision precision = sizeof(Real) == 4 ? Precision::Single : Precision::Double;
  auto serial = makeStepper(Backend::Serial, precision, p, initial);
  auto device = hostStepper<Real>(p, initial, optionsOf(c), c.backwards);
  int serialIterations = 0, deviceIterations = 0;
  bool pressed = false;
  for (int s = 0; s < steps; ++s)
  {
    if (c.pressureMean)
    {
      serial->setTimeStep(p.timeStep, s * p.timeStep);
      device->setTimeStep(p.timeStep, s * p.timeStep);
    }
    serial->step();
    device->step();
    serialIterations += serial->lastStep().iterations;
    deviceIterations += device->lastStep().iterations;
    if (c.tankLoads)
    {
      ASSERT_EQ(serial->lastStep().loads.size(), kMirrorWalls);
      pressed = expectSameLoads(*serial, *device, s) || pressed;
    }
  }
  EXPECT_EQ(pressed, c.tankLoads) << "the tank's loads were asked for and never pressed";
  if (c.tolerance > 0)
  {
    EXPECT_EQ(deviceIterations, serialIterations);
    // The tolerance must both stop some steps early and not others, or nothing was tested.
    EXPECT_LT(serialIterations, steps * c.iterations);
    EXPECT_GT(serialIterations, steps);
  }
  SCOPED_TRACE(std::string(c.scene) + ", " + std::to_string(c.iterations) + " iterations, " +
    (c.masks ? "masks, skin " + std::to_string(c.skin) : std::string("cell walk")) +
    (c.backwards ? ", backwards" : "") + (c.graphs ? ", graphs" : ", stage by stage") +
    (c.pressureMean ? ", pressure's mean" : ""));
  test::expectBitIdentical(stateOf<Real>(*serial), stateOf<Real>(*device));
  if (builds)
  {
    // Per particle: 1 a step when every particle keeps its masks, 5 when all rebuild in every
    // pass of 4 projections.
    *builds = double(device->diagnostics().maskBuilds) / double(initial.position.size());
  }
}

} // namespace

TEST(StepSchedule, CellWalkReproducesTheSerialBackendBitForBit)
{
  compareWithSerial<float>({ "dam_break", 4, false, 0.1, false }, 40);
  compareWithSerial<double>({ "blob", 3, false, 0.1, true }, 40);
}

TEST(StepSchedule, NeighborMasksReproduceTheSerialBackendBitForBit)
{
  for (bool backwards : { false, true })
  {
    compareWithSerial<float>({ "dam_break", 4, true, 0.1, backwards }, 60);
    compareWithSerial<double>({ "double_dam_break", 3, true, 0.1, backwards }, 60);
  }
}

TEST(StepSchedule, XsphHyperViscosityReproducesTheSerialBackendBitForBit)
{
  // The bi-Laplacian reads every neighbour's XSPH sum in the confinement pass, where the device
  // schedule keeps the sums in x's buffer and writes the velocity over omega.
  compareWithSerial<float>({ "dam_break", 4, true, 0.1, true, 0, true, 0.05 }, 40);
  compareWithSerial<double>({ "double_dam_break", 3, false, 0.1, false, 0, false, 0.1 }, 40);
}

TEST(StepSchedule, ParticlesRebuildTheirMasksOnlyWhereTheyMovedAndStayExact)
{
  // The dam break at a skin of 0.005 h: where the fluid falls fast the particles rebuild, where it
  // rests they keep the masks of the sort. Both must happen, and the bits must not change.
  double builds = 0;
  const int steps = 60;
  compareWithSerial<float>({ "dam_break", 4, true, 0.005, false }, steps, &builds);
  const double perStep = (builds - 1.0) / steps; // less the build at rest
  EXPECT_GT(perStep, 1.05);
  EXPECT_LT(perStep, 4.5);
  std::printf("dam break, skin 0.005 h: %.3f mask builds per particle and step\n", perStep);
}

TEST(StepSchedule, MasksStayExactWhenEveryPassMustRebuildThem)
{
  // A skin this thin is exceeded by the first corrections, so most passes rebuild: the
  // rebuild path must give the same bits as the walk. The blob falls fast onto the pool.
  double thin = 0, thick = 0;
  compareWithSerial<float>({ "blob", 4, true, 1e-4, false }, 60, &thin);
  compareWithSerial<float>({ "blob", 4, true, 0.5, false }, 60, &thick);
  // One build at rest plus at least one per step; the thin skin must rebuild far more often.
  EXPECT_GE(thick, 61.0);
  EXPECT_GT(thin, 2 * thick);
}

TEST(StepSchedule, AdaptiveIterationsReproduceTheSerialBackendBitForBit)
{
  // Steps that meet the tolerance early skip their remaining projections on the device too: in
  // a captured step as conditional bodies that do not run, stage by stage as passes that return
  // at once. Either way the positions end in the buffer of the last projection run, an even or
  // an odd one, and the step's end moves them where the captured step expects them.
  for (bool graphs : { true, false })
  {
    compareWithSerial<float>({ "dam_break", 6, true, 0.1, false, 0.05, graphs }, 60);
    compareWithSerial<double>({ "blob", 5, false, 0.1, true, 0.05, graphs }, 60);
    // The tank's loads: summed by the corrections that ran, whatever the step's count.
    compareWithSerial<double>(
      { "dam_break", 6, true, 0.1, false, 0.05, graphs, 0, 0, 0, 90, true }, 30);
  }
}

TEST(StepSchedule, ChebyshevAccelerationReproducesTheSerialBackendBitForBit)
{
  // The device schedule reads each particle's positions two projections back from the position
  // buffer it is about to overwrite; the host keeps them in omega's array. Fixed and adaptive
  // counts (an adaptive step may end after an even or an odd projection), masks with a skin thin
  // enough that the blend's larger moves force rebuilds, and the cell walk.
  for (bool graphs : { true, false })
  {
    compareWithSerial<float>({ "dam_break", 5, true, 0.02, false, 0, graphs, 0.05, 0.8 }, 40);
    compareWithSerial<float>({ "dam_break", 8, true, 0.1, true, 0.05, graphs, 0.05, 0.8 }, 40);
    compareWithSerial<double>(
      { "double_dam_break", 6, false, 0.1, false, 0.05, graphs, 0, 0.9 }, 40);
    compareWithSerial<double>(
      { "dam_break", 8, true, 0.1, true, 0.05, graphs, 0.05, 0.8, 0, 90, true }, 30);
  }
}

TEST(StepSchedule, APressureMeanOverStepsFollowsTheSortLikeTheSerialBackend)
{
  // The pressure's running mean (Stepper::setTimeStep) rides on the cell sort's gathers: the
  // dam break falls, its particles change cells every step, and the mean must stay with them.
  for (bool graphs : { true, false })
  {
    Case c{ "dam_break", 4, true, 0.02, false, 0, graphs };
    c.pressureMean = true;
    compareWithSerial<float>(c, 30);
    c.scene = "double_dam_break";
    compareWithSerial<double>(c, 30);
  }
}

TEST(DeviceStepperOnHost, StageByStageAndCapturedStepsAreTheSame)
{
  // Options::graphs off queues every stage at every step; on, the step recorded at construction
  // is replayed with the arguments it was recorded with. Three projections swap x and v every
  // step, so both recorded assignments are replayed.
  compareWithSerial<float>({ "dam_break", 3, true, 0.02, false, 0, false }, 30);
  compareWithSerial<float>({ "dam_break", 3, true, 0.02, false, 0, true }, 30);
}

TEST(DeviceStepperOnHost, TheStepIsCapturedAgainOnlyWhenItsArgumentsChange)
{
  const Scene scene = presetScene("dam_break");
  const Parameters p = fixedParameters({ "dam_break", 4, true, 0.02, false }, scene);
  test::HostDevicePolicy* policy = nullptr;
  auto device = hostStepper<float>(p, fillScene(scene, p), cuda::Options{}, false, &policy);
  EXPECT_EQ(policy->captures(), 0);
  device->step(); // the first step after a change is queued stage by stage
  EXPECT_EQ(policy->captures(), 0);
  for (int s = 0; s < 10; ++s)
  {
    device->step();
  }
  // Four projections keep x and v where they are: one assignment, captured once.
  const long stepped = policy->captures();
  EXPECT_EQ(stepped, 1);
  device->setTimeStep(p.timeStep / 2); // the step size is read on the device: no new capture
  device->step();
  EXPECT_EQ(policy->captures(), stepped);
  ParticleBatch more;
  more.position = { Vec3d{ 0.8, 0.5, 0.1 } };
  more.velocity = { Vec3d{ 0, 0, 0 } };
  more.id = { 1000000 };
  device->append(more); // another particle count: captured again at the second step
  device->step();
  EXPECT_EQ(policy->captures(), stepped);
  device->step();
  EXPECT_EQ(policy->captures(), stepped + 1);
  // Three projections swap x and v every step: both assignments, each captured once.
  Parameters odd = p;
  odd.solverIterations = 3;
  test::HostDevicePolicy* oddPolicy = nullptr;
  auto swapping = hostStepper<float>(odd, fillScene(scene, odd), cuda::Options{}, false, &oddPolicy);
  for (int s = 0; s < 7; ++s)
  {
    swapping->step();
  }
  EXPECT_EQ(oddPolicy->captures(), 2);
}

TEST(DeviceStepperOnHost, EmittersGrowTheArraysLikeTheSerialBackend)
{
  // The arrays start with room for 1024 particles; each batch below passes the capacity, so the
  // state (the pressure's running mean with it) goes through the host into larger arrays.
  // Bit-identical: the host policy rounds as the serial backend does, and the appended
  // particles join in the same order, their pressure at 0.
  const Scene scene = presetScene("dam_break");
  const Parameters p = fixedParameters({ "dam_break", 4, true, 0.02, false }, scene);
  const ParticleBatch initial = fillScene(scene, p);
  auto serial = makeStepper(Backend::Serial, Precision::Double, p, initial);
  auto device = hostStepper<double>(p, initial, cuda::Options{});
  std::int64_t next = static_cast<std::int64_t>(initial.position.size());
  const std::size_t startCapacity = device->diagnostics().capacity;
  for (int round = 0; round < 3; ++round)
  {
    ParticleBatch batch;
    for (int k = 0; k < 700; ++k)
    {
      batch.position.push_back(
        Vec3d{ 0.62 + 0.04 * (k % 20), 0.42 + 0.04 * ((k / 20) % 5), 0.02 + 0.04 * (k / 100) });
      batch.velocity.push_back(Vec3d{ 0, -0.5, 0 });
      batch.id.push_back(next++);
    }
    serial->append(batch);
    device->append(batch);
    for (int s = 0; s < 5; ++s)
    {
      // One pressure mean over all 15 steps: the larger arrays must keep it.
      const double elapsed = (5 * round + s) * p.timeStep;
      serial->setTimeStep(p.timeStep, elapsed);
      device->setTimeStep(p.timeStep, elapsed);
      serial->step();
      device->step();
    }
  }
  EXPECT_GT(device->diagnostics().capacity, startCapacity);
  EXPECT_EQ(device->size(), initial.position.size() + 2100);
  test::expectBitIdentical(stateOf<double>(*serial), stateOf<double>(*device));
}

TEST(DeviceStepperOnHost, ACheckpointResumesBitIdentically)
{
  const Scene scene = presetScene("double_dam_break");
  const Parameters p = fixedParameters({ "double_dam_break", 4, true, 0.02, false }, scene);
  const ParticleBatch initial = fillScene(scene, p);
  auto straight = hostStepper<float>(p, initial, cuda::Options{});
  auto resumed = hostStepper<float>(p, initial, cuda::Options{});
  for (int s = 0; s < 20; ++s)
  {
    straight->step();
    resumed->step();
  }
  const Snapshot<float> at20 = stateOf<float>(*resumed);
  for (int s = 0; s < 7; ++s)
  {
    resumed->step();
  }
  resumed->load(at20);
  for (int s = 0; s < 20; ++s)
  {
    straight->step();
    resumed->step();
  }
  test::expectBitIdentical(stateOf<float>(*straight), stateOf<float>(*resumed));
  // A checkpoint of the other precision is refused, naming it.
  Snapshot<double> wrong;
  resumed->read(wrong);
  try
  {
    resumed->load(wrong);
    ADD_FAILURE() << "a double checkpoint was loaded into a single-precision stepper";
  }
  catch (const InvalidInput& error)
  {
    EXPECT_NE(std::string(error.what()).find("checkpoint precision = double"), std::string::npos)
      << error.what();
  }
}

TEST(DeviceStepperOnHost, ScansAgreeWithTheSerialBackend)
{
  const Scene scene = presetScene("dam_break");
  const Parameters p = fixedParameters({ "dam_break", 4, true, 0.02, false }, scene);
  const ParticleBatch initial = fillScene(scene, p);
  auto serial = makeStepper(Backend::Serial, Precision::Double, p, initial);
  auto device = hostStepper<double>(p, initial, cuda::Options{});
  for (int s = 0; s < 30; ++s)
  {
    serial->step();
    device->step();
  }
  const Statistics a = serial->statistics();
  const Statistics b = device->statistics();
  // The same particles (bit for bit, above) counted and summed in the same order: equal, except
  // the sums, which the device policy adds in particle order as the CPU does; 1e-12 relative
  // leaves room for a different association only.
  EXPECT_EQ(b.particles, a.particles);
  EXPECT_EQ(b.averageNeighbors, a.averageNeighbors);
  EXPECT_EQ(b.maxDensityError, a.maxDensityError);
  EXPECT_EQ(b.maxSpeed, a.maxSpeed);
  EXPECT_NEAR(b.averageDensityError, a.averageDensityError, 1e-12 * a.averageDensityError);
  EXPECT_NEAR(b.kineticEnergy, a.kineticEnergy, 1e-12 * a.kineticEnergy);
  EXPECT_TRUE(b.finite);
  EXPECT_GT(a.maxSpeed, 0.1); // the column is falling: the scans saw a moving fluid
  const Health h = device->health();
  const Health reference = serial->health();
  EXPECT_EQ(h.maxSpeed, reference.maxSpeed);
  // The same speeds binned alike (the bits of the same speed^2): the same percentile.
  EXPECT_EQ(h.robustSpeed, reference.robustSpeed);
  EXPECT_GT(h.robustSpeed, 0.1);
  EXPECT_EQ(h.nonFinite, 0u);
  EXPECT_NEAR(h.maxDensityError, std::max(reference.maxDensityError, 0.0), 1e-15);
}

namespace
{

// The dam break with solids, 40 steps on the serial backend and on the device schedule: the same
// bits, and each step's loads on the solids and on the six mirror walls the same to 1e-12 of the
// largest force (the serial backend adds a particle's terms in blocks of 512 in order, the device
// a solid's in a tree of 256 lanes and a wall's per warp in the correction: the same doubles in
// another order, 2^-52 each at most times the ~1000 terms a sum holds).
// Returns how many initial particles the solids removed.
// With `moving`, the sphere rolls into the column and the box turns, their poses set before each
// step as Simulation sets them.
template <class Real>
std::size_t expectSolidsAsSerial(double wallFriction, bool moving = false, double hyper = 0,
  double sigma = 0, double solidAngle = 90)
{
  Scene scene = test::damBreakWithSolids();
  for (SolidRegion& solid : scene.solids)
  {
    solid.contactAngle.fill(solidAngle);
  }
  if (moving)
  {
    scene.solids[0].motion.keyframes = { { 0.0, { 0, 0, 0 }, Rotation{} },
      { 0.1, { -0.1, 0, 0 }, Rotation::fromDegrees({ 0, 0, 60 }) } };
    scene.solids[1].motion.keyframes = { { 0.0, { 0, 0, 0 }, Rotation{} },
      { 0.1, { 0, 0.02, 0 }, Rotation::fromDegrees({ 0, 10, 0 }) } };
  }
  Parameters p = fixedParameters({ "dam_break", 4, true, 0.02, false }, scene);
  p.wallFriction = wallFriction;
  p.tankLoads = true;
  p.xsphHyperViscosity = hyper;
  p.surfaceTension = sigma;
  const std::vector<DistanceGrid> solids = solidFields(scene.solids, p);
  const std::vector<SolidMotion> motions = solidMotions(scene.solids);
  std::size_t removed = 0;
  const ParticleBatch initial =
    outsideSolids(fillScene(scene, p), solids, posesAt(motions, 0.0), removed);
  const Precision precision = sizeof(Real) == 4 ? Precision::Single : Precision::Double;
  auto serial = makeStepper(Backend::Serial, precision, p, initial);
  auto device = hostStepper<Real>(p, initial, cuda::Options{});
  serial->setObstacles(solids, posesAt(motions, 0.0));
  device->setObstacles(solids, posesAt(motions, 0.0));
  bool pushed = false;
  for (int s = 0; s < 40; ++s)
  {
    const std::vector<SolidPose> poses = posesAt(motions, (s + 1) * p.timeStep);
    if (moving)
    {
      serial->setObstaclePoses(poses);
      device->setObstaclePoses(poses);
    }
    serial->step();
    device->step();
    const std::vector<SolidLoad> expected = serial->lastStep().loads;
    const std::vector<SolidLoad> loads = device->lastStep().loads;
    EXPECT_EQ(expected.size(), solids.size() + kMirrorWalls);
    EXPECT_EQ(loads.size(), expected.size()) << "the solids' loads, then the walls'";
    for (std::size_t o = 0; o < std::min(loads.size(), expected.size()); ++o)
    {
      const double largest = std::max(length(expected[o].force), 1e-6);
      const double scale = largest * (1.0 + length(scene.domain.max - scene.domain.min));
      EXPECT_NEAR(loads[o].force.x, expected[o].force.x, 1e-12 * largest) << s << " " << o;
      EXPECT_NEAR(loads[o].force.y, expected[o].force.y, 1e-12 * largest) << s << " " << o;
      EXPECT_NEAR(loads[o].force.z, expected[o].force.z, 1e-12 * largest) << s << " " << o;
      EXPECT_NEAR(loads[o].torque.x, expected[o].torque.x, 1e-12 * scale) << s << " " << o;
      EXPECT_NEAR(loads[o].torque.y, expected[o].torque.y, 1e-12 * scale) << s << " " << o;
      EXPECT_NEAR(loads[o].torque.z, expected[o].torque.z, 1e-12 * scale) << s << " " << o;
      pushed = pushed || length(loads[o].force) > 0;
    }
  }
  test::expectBitIdentical(stateOf<Real>(*serial), stateOf<Real>(*device));
  EXPECT_TRUE(pushed) << "the fluid never reached a solid: the loads were not tested";
  return removed;
}

} // namespace

TEST(DeviceStepperOnHost, SolidsMatchTheSerialBackend)
{
  EXPECT_GT(expectSolidsAsSerial<double>(0.0), 0u);
}

TEST(DeviceStepperOnHost, WallFrictionReproducesTheSerialBackendBitForBit)
{
  // Friction at the box's walls (the images of the neighbours) and at the solids (the image of
  // the particle itself), in the vorticity pass of the device schedule.
  expectSolidsAsSerial<float>(0.7);
  // With the bi-Laplacian the walls' share of XSPH's sum is smoothed with the fluid's.
  expectSolidsAsSerial<double>(0.7, false, 0.05);
}

TEST(DeviceStepperOnHost, MovingSolidsReproduceTheSerialBackendBitForBit)
{
  // The poses reach the device as views uploaded before the step the graph replays.
  EXPECT_GT(expectSolidsAsSerial<double>(0.0, true), 0u);
  expectSolidsAsSerial<float>(0.5, true);
}

TEST(DeviceStepperOnHost, MoreParticlesThanFreeMemoryIsInvalidInputNamingTheCount)
{
  const Scene scene = presetScene("dam_break");
  const Parameters p = fixedParameters({ "dam_break", 4, true, 0.02, false }, scene);
  const ParticleBatch initial = fillScene(scene, p);
  auto device = std::make_unique<test::HostDevicePolicy>();
  device->setFreeMemory(std::size_t(1) << 20); // 1 MiB: less than the head room alone
  try
  {
    HostStepper<float> stepper(p, initial, cuda::Options{}, std::move(device));
    ADD_FAILURE() << "constructed in 1 MiB";
  }
  catch (const InvalidInput& error)
  {
    const std::string message = error.what();
    EXPECT_NE(message.find("particle count = " + std::to_string(initial.position.size())),
      std::string::npos)
      << message;
    EXPECT_NE(message.find("MiB free"), std::string::npos) << message;
  }
}

TEST(DeviceStepperOnHost, AnInjectedFaultSurfacesAtTheNextWait)
{
  const Scene scene = presetScene("dam_break");
  const Parameters p = fixedParameters({ "dam_break", 4, true, 0.02, false }, scene);
  cuda::Options options;
  options.faultAtStep = 3;
  auto device = hostStepper<float>(p, fillScene(scene, p), options);
  device->step();
  device->step();
  EXPECT_NO_THROW(device->synchronize());
  device->step(); // queues the fault; nothing waits yet
  EXPECT_THROW(device->synchronize(), DeviceFault);
}
TEST(MaskSchedule, RebuildsExactlyWhenTheBoundCouldBeExceeded)
{
  const double h = 0.04;
  const MaskSchedule schedule{ 0.1 * h, h, 1e-9, 1 };
  auto bits = [](double d) { return MaskSchedule::doubleToBits(d); };
  // 2 * moved must stay under skin - 1e-3 h = 0.0039 m, with the 1e-3 relative margin.
  const unsigned long long small[3] = { bits(0.0005), bits(0.0005), bits(0.0005) };
  EXPECT_TRUE(schedule.rebuildAt(0, small)); // the first pass of a step always builds
  EXPECT_FALSE(schedule.rebuildAt(1, small));
  EXPECT_FALSE(schedule.rebuildAt(3, small)); // 2 * 0.0015 = 0.003 < 0.0039
  const unsigned long long large[3] = { bits(0.001), bits(0.001), bits(0.001) };
  EXPECT_FALSE(schedule.rebuildAt(1, large));
  EXPECT_TRUE(schedule.rebuildAt(2, large));  // 2 * 0.002 = 0.004 > 0.0039: rebuild here
  EXPECT_FALSE(schedule.rebuildAt(3, large)); // 0.001 since that rebuild
  const unsigned long long nan[2] = { bits(std::numeric_limits<double>::quiet_NaN()), bits(0) };
  EXPECT_TRUE(schedule.rebuildAt(1, nan)); // a NaN displacement never passes for small
  EXPECT_GT(bits(std::numeric_limits<double>::quiet_NaN()),
    bits(std::numeric_limits<double>::infinity())); // and wins an integer max over the bits
}

TEST(MovedSinceSort, AParticleKeepsItsMasksUntilItOrAnyCandidateMovedPastTheSkin)
{
  // A 5 x 5 x 5 grid of cells of h = 1; particle 0 sits in the middle cell (2, 2, 2).
  const double h = 1.0;
  const MaskSchedule schedule{ 0.1 * h, h, 0.0, 1 };
  const GridGeometry<float> g = makeGridGeometry<float>({ { 0, 0, 0 }, { 5, 5, 5 } }, h);
  ASSERT_EQ(g.nx, 5);
  auto key = [&](int x, int y, int z) { return CellKey((z * g.ny + y) * g.nx + x); };
  const CellKey keys[1] = { key(2, 2, 2) };
  const GridView<float> grid{ g, nullptr, keys };
  std::vector<std::uint32_t> cellMoved(std::size_t(g.cellCount()), 0);
  float moved[1] = { 0.0f };
  const MovedSinceSort local{ moved, cellMoved.data() };
  EXPECT_TRUE(local.keeps(grid, 0, schedule, 1));
  // Its own move and a candidate's, 0.06 h together, are within the skin (0.1 h - 1e-3 h).
  local.add(0, keys[0], 0.03);
  cellMoved[key(3, 3, 1)] = MovedSinceSort::bitsOf(0.03f);
  EXPECT_TRUE(local.keeps(grid, 0, schedule, 2));
  // A candidate two cells away cannot reach it: no effect.
  cellMoved[key(4, 2, 2)] = MovedSinceSort::bitsOf(0.5f);
  EXPECT_TRUE(local.keeps(grid, 0, schedule, 2));
  // A corner cell of its 27 whose particle moved 0.07 h: 0.1 h in all, over the bound.
  cellMoved[key(1, 1, 1)] = MovedSinceSort::bitsOf(0.07f);
  EXPECT_FALSE(local.keeps(grid, 0, schedule, 2));
  cellMoved[key(1, 1, 1)] = 0;
  // Its own moves accumulate: 0.03 + 0.05 + the candidate's 0.03 is over too.
  local.add(0, keys[0], 0.05);
  EXPECT_FLOAT_EQ(moved[0], 0.08f);
  EXPECT_EQ(cellMoved[std::size_t(keys[0])], MovedSinceSort::bitsOf(moved[0]));
  EXPECT_FALSE(local.keeps(grid, 0, schedule, 3));
  // Once rebuilt it rebuilds in every later pass of the step, even after a quiet one, and its
  // distance still counts for its neighbours.
  local.mark(0);
  cellMoved[key(3, 3, 1)] = 0;
  EXPECT_FALSE(local.keeps(grid, 0, schedule, 4));
  local.add(0, keys[0], 0.01);
  EXPECT_FLOAT_EQ(moved[0], -0.09f);
  EXPECT_EQ(cellMoved[std::size_t(keys[0])], MovedSinceSort::bitsOf(-moved[0]));
  // A NaN displacement never passes.
  float nan[1] = { std::numeric_limits<float>::quiet_NaN() };
  EXPECT_FALSE((MovedSinceSort{ nan, cellMoved.data() }.keeps(grid, 0, schedule, 1)));
}

namespace
{

// test::twoLiquids on the serial backend and on the device schedule, `steps` steps of fixed size
// with `iterations` projections (adaptive with `tolerance` > 0), from the scene's initial fluid
// (the emitter is Simulation's, not the stepper's): the same bits, and in adaptive mode the same
// projections (the mean each step stops at is the most compressed liquid's on both).
template <class Real>
void compareTwoLiquids(bool masks, bool graphs, int iterations, double tolerance, int steps,
  double oilSurfaceTension = 0, bool tankLoads = false)
{
  const Scene scene = test::twoLiquids();
  Parameters p;
  p.particleSpacing = 0.04;
  p.solverIterations = iterations;
  p.densityErrorTolerance = tolerance;
  p.tankLoads = tankLoads;
  p.timeStep = 1.0 / 120.0;
  p = withSceneDomain(p, scene);
  if (oilSurfaceTension > 0)
  {
    // The water takes the run's, the oil its own: each particle's force is its liquid's.
    p.surfaceTension = 0.07;
    p.liquids.at(1).surfaceTension = oilSurfaceTension;
  }
  const ParticleBatch initial = fillScene(scene, p);
  const Precision precision = sizeof(Real) == 4 ? Precision::Single : Precision::Double;
  auto serial = makeStepper(Backend::Serial, precision, p, initial);
  cuda::Options options;
  options.search = masks ? cuda::NeighborSearch::RowMasks : cuda::NeighborSearch::CellWalk;
  options.graphs = graphs;
  auto device = hostStepper<Real>(p, initial, options);
  int serialIterations = 0, deviceIterations = 0;
  for (int s = 0; s < steps; ++s)
  {
    serial->step();
    device->step();
    serialIterations += serial->lastStep().iterations;
    deviceIterations += device->lastStep().iterations;
    if (tankLoads)
    {
      EXPECT_TRUE(expectSameLoads(*serial, *device, s)) << "the liquids press no wall";
    }
  }
  SCOPED_TRACE(std::string(masks ? "masks" : "cell walk") + (graphs ? ", graphs" : "") +
    ", tolerance " + std::to_string(tolerance));
  EXPECT_EQ(deviceIterations, serialIterations);
  if (tolerance > 0)
  {
    EXPECT_LT(serialIterations, steps * iterations);
    EXPECT_GT(serialIterations, steps);
  }
  const Snapshot<Real> a = stateOf<Real>(*serial), b = stateOf<Real>(*device);
  test::expectBitIdentical(a, b);
  EXPECT_EQ(a.liquid, b.liquid);
  ASSERT_EQ(b.liquid.size(), b.id.size());
  EXPECT_GT(std::count(b.liquid.begin(), b.liquid.end(), 1), 100);
}

} // namespace

TEST(StepSchedule, TwoLiquidsReproduceTheSerialBackendBitForBit)
{
  compareTwoLiquids<float>(true, true, 4, 0, 40);
  compareTwoLiquids<double>(false, false, 4, 0, 40);
  compareTwoLiquids<float>(true, true, 8, 0.3, 40);
  compareTwoLiquids<double>(true, false, 8, 0.3, 40);
  compareTwoLiquids<double>(true, true, 8, 0.3, 20, 0, true); // with the tank's loads
}

TEST(StepSchedule, SurfaceTensionReproducesTheSerialBackendBitForBit)
{
  // The colour gradient (with the walls' images) in the vorticity pass, its smoothed normals in a
  // pass of their own, and the curvature's force in the confinement pass, in the buffers that
  // exist only with surface tension: masks and the cell walk, captured and stage by stage, with
  // the walls' friction and the bi-Laplacian beside it, and per liquid.
  Case plain{ "dam_break", 4, true, 0.1, false };
  plain.sigma = 0.5;
  compareWithSerial<float>(plain, 40);
  Case walk{ "double_dam_break", 3, false, 0.1, true, 0, false, 0.05 };
  walk.sigma = 2.0;
  compareWithSerial<double>(walk, 40);
  // With adhesion at the walls (Young's force on the surface particles near them).
  Case wetting{ "dam_break", 4, true, 0.1, false };
  wetting.sigma = 2.0;
  wetting.contactAngle = 60;
  compareWithSerial<float>(wetting, 40);
  compareTwoLiquids<float>(true, true, 4, 0, 40, 0.03);
  compareTwoLiquids<double>(false, false, 4, 0, 40, 0.03);
  // With the walls' friction the vorticity pass walks the images for both.
  expectSolidsAsSerial<double>(0.7, true, 0, 0.5);
  // The solids' images and their contact angles (adhesion at obstacles), still and moving.
  expectSolidsAsSerial<double>(0.0, true, 0, 0.5, 60);
  expectSolidsAsSerial<float>(0.0, false, 0, 2.0, 120);
}

// Through Simulation: the nozzle's oil grows the device arrays (their liquids kept through the
// host), a checkpoint resumes bit-identically with every particle's liquid, and the scans weigh
// each particle by its liquid's mass as the serial backend does (the same particles summed in the
// same order: 1e-12 relative leaves room for another association only).
TEST(DeviceStepperOnHost, TwoLiquidsGrowResumeAndScanAsTheSerialBackend)
{
  Parameters p;
  p.particleSpacing = 0.04;
  p.timeStepping = TimeStepping::Fixed;
  p.timeStep = 1.0 / 120.0;
  const Scene scene = test::twoLiquids();
  auto make = [&](Backend backend) {
    const Parameters q = withSceneDomain(p, scene);
    const ParticleBatch initial = fillScene(scene, q);
    return backend == Backend::Serial
      ? makeStepper(Backend::Serial, Precision::Double, q, initial)
      : std::unique_ptr<Stepper>(hostStepper<double>(q, initial, cuda::Options{}));
  };
  auto serial = make(Backend::Serial);
  auto device = make(Backend::CUDA);
  const std::size_t start = device->size();
  // The nozzle's layers, as Simulation emits them: one batch of oil every few steps.
  std::int64_t nextId = static_cast<std::int64_t>(start);
  Snapshot<double> checkpoint;
  for (int s = 0; s < 36; ++s)
  {
    if (s % 4 == 0 && s < 24)
    {
      ParticleBatch batch;
      for (int a = -1; a <= 1; ++a)
      {
        for (int b = -1; b <= 1; ++b)
        {
          batch.position.push_back({ 0.6 + 0.04 * a, 0.5, 0.12 + 0.04 * b });
          batch.velocity.push_back({ 0, -1, 0 });
          batch.id.push_back(nextId++);
          batch.liquid.push_back(1);
        }
      }
      serial->append(batch);
      device->append(batch);
    }
    serial->step();
    device->step();
    if (s == 20)
    {
      device->read(checkpoint);
    }
  }
  ASSERT_GT(device->size(), start);
  const Snapshot<double> a = stateOf<double>(*serial), b = stateOf<double>(*device);
  test::expectBitIdentical(a, b);
  EXPECT_EQ(a.liquid, b.liquid);
  const Statistics sa = serial->statistics(), sb = device->statistics();
  EXPECT_NEAR(sb.kineticEnergy, sa.kineticEnergy, 1e-12 * sa.kineticEnergy);
  EXPECT_NEAR(sb.averageDensityError, sa.averageDensityError, 1e-12 * sa.averageDensityError);
  // The checkpoint after step 21, loaded into a fresh stepper, gives the last 15 steps again (no
  // batch came after it).
  auto resumed = make(Backend::CUDA);
  resumed->load(checkpoint);
  for (int s = 0; s < 15; ++s)
  {
    resumed->step();
  }
  const Snapshot<double> c = stateOf<double>(*resumed);
  test::expectBitIdentical(c, b);
  EXPECT_EQ(c.liquid, b.liquid);
  // And the densities come back in each liquid's units: the oil reads about 800.
  double oil = 0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < c.id.size(); ++i)
  {
    if (c.liquid[i] == 1)
    {
      oil += c.density[i];
      ++count;
    }
  }
  ASSERT_GT(count, 0u);
  EXPECT_NEAR(oil / double(count), 800.0, 80.0);
}

// Outflows on the GPU schedule: the kept particles selected stably and gathered (x and v back
// into the buffers the captured steps start from), the step captured again at the new count.
// Bit-identical to the serial backend's removal, with two liquids (whose bytes go along) and
// without, captured and stage by stage, over steps that remove particles and steps that do not.
TEST(DeviceStepperOnHost, OutflowsRemoveWhatTheSerialBackendRemoves)
{
  Parameters p;
  p.particleSpacing = 0.04;
  p.timeStepping = TimeStepping::Fixed;
  p.timeStep = 1.0 / 120.0;
  // A box through the liquids' interface and the floor's right half: particles leave at once
  // and then as the fluid runs into it.
  const std::vector<Box> zones = { Box{ { 0.0, 0.25, 0.0 }, { 0.3, 0.35, 0.3 } },
    Box{ { 0.7, -0.1, -0.1 }, { 1.1, 0.1, 0.7 } } };
  for (const bool liquids : { true, false })
  {
    for (const bool graphs : { true, false })
    {
      const Scene scene = liquids ? test::twoLiquids() : presetScene("dam_break");
      const Parameters q = withSceneDomain(p, scene);
      const ParticleBatch initial = fillScene(scene, q);
      auto serial = makeStepper(Backend::Serial, Precision::Double, q, initial);
      cuda::Options options;
      options.graphs = graphs;
      auto device = hostStepper<double>(q, initial, options);
      std::size_t removed = 0;
      int quiet = 0; // steps that removed nothing
      for (int s = 0; s < 30; ++s)
      {
        serial->step();
        device->step();
        const std::size_t a = serial->removeOutflow(zones);
        ASSERT_EQ(device->removeOutflow(zones), a) << "step " << s;
        removed += a;
        quiet += a == 0 ? 1 : 0;
      }
      SCOPED_TRACE(std::string(liquids ? "two liquids" : "one liquid") +
        (graphs ? ", graphs" : ", stage by stage"));
      EXPECT_GT(removed, 50u);
      EXPECT_GT(quiet, 0);
      EXPECT_EQ(device->size(), initial.position.size() - removed);
      const Snapshot<double> a = stateOf<double>(*serial), b = stateOf<double>(*device);
      test::expectBitIdentical(a, b);
      EXPECT_EQ(a.liquid, b.liquid);
    }
  }
}
