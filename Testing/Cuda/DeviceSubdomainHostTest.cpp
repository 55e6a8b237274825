// The CUDA sub-domain stepper's algorithm (Cuda/DeviceSubdomainStepper.h) run on the host
// executor, ranks as threads: the decomposition, the migration, the ghost protocol and the mask
// bound across ranks are checked here on any machine (label "solver"); CudaSubdomainTest.cpp
// runs the same on a GPU.
#include "Backends.h"
#include "DecomposedRuns.h"
#include "HostExecutor.h"

#include "Cuda/DeviceSubdomainStepper.h"
#include "Distributed/FluidPieces.h"
#include "Distributed/SubdomainStepper.h"
#include "SignedDistance.h"
#include "SpeedHistogram.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <memory>

using namespace pbf;
using namespace pbf::test;

namespace
{

template <class Real>
DecomposedFactory onHost(bool backwards = false, double skin = 0.02, bool masks = true)
{
  return [=](distributed::Communicator& communicator, const PresetFluid& setup) {
    return std::unique_ptr<distributed::DecomposedStepper>(
      new cuda::DeviceSubdomainStepper<Real, HostDevicePolicy>(communicator, setup.parameters,
        setup.fluid, std::make_unique<HostDevicePolicy>(backwards), skin, masks));
  };
}

// Bit-for-bit comparison matched by id.
void expectBitIdentical(const Snapshot<double>& a, const Snapshot<double>& b)
{
  ASSERT_EQ(a.id.size(), b.id.size());
  const std::map<std::int64_t, std::size_t> at = indexById(b);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.id.size(); ++i)
  {
    const auto found = at.find(a.id[i]);
    ASSERT_NE(found, at.end()) << "id " << a.id[i];
    const std::size_t j = found->second;
    differ += std::memcmp(&a.position[i], &b.position[j], sizeof(Vec3d)) != 0 ||
      std::memcmp(&a.velocity[i], &b.velocity[j], sizeof(Vec3d)) != 0 ||
      std::memcmp(&a.density[i], &b.density[j], sizeof(double)) != 0 ||
      std::memcmp(&a.lambda[i], &b.lambda[j], sizeof(double)) != 0 ||
      std::memcmp(&a.pressure[i], &b.pressure[j], sizeof(double)) != 0;
  }
  EXPECT_EQ(differ, 0u) << "particles with a different bit";
}

// The serial backend's state after `steps` steps with one solid.
// The CPU sub-domain stepper, serial on each rank: the other decomposed stepper the GPU one is
// held to.
DecomposedFactory serialSubdomains()
{
  return [](distributed::Communicator& communicator, const PresetFluid& fluid) {
    return std::unique_ptr<distributed::DecomposedStepper>(new distributed::SubdomainStepper<double>(
      communicator, false, fluid.parameters, fluid.fluid));
  };
}

// A sphere that rolls along -x at 1 m/s and turns about z at 10 rad/s, from t = 0 (the fixed
// steps' time).
SolidMotion rollingSphere()
{
  SolidMotion m;
  m.pivot = { 0.5, 0.1, 0.3 };
  m.keyframes.push_back({ 0.0, { 0, 0, 0 }, Rotation{} });
  m.keyframes.push_back({ 0.1, { -0.1, 0, 0 }, Rotation::fromDegrees({ 0, 0, 57.2957795 }) });
  return m;
}

// Where `motion` puts the solid at the end of step s.
std::vector<SolidPose> poseAfterStep(const SolidMotion& motion, const Parameters& p, int s)
{
  return { motion.at((s + 1) * p.timeStep) };
}

// loads, when given, receives each step's loads: the solid's, then the six walls'.
Snapshot<double> serialWithSolid(const PresetFluid& setup, const DistanceGrid& solid, int steps,
  const SolidMotion& motion = {}, std::vector<std::vector<SolidLoad>>* loads = nullptr)
{
  auto serial = makeStepper(Backend::Serial, Precision::Double, setup.parameters, setup.fluid);
  serial->setObstacles({ solid });
  for (int s = 0; s < steps; ++s)
  {
    if (motion.moves())
    {
      serial->setObstaclePoses(poseAfterStep(motion, setup.parameters, s));
    }
    serial->step();
    if (loads)
    {
      loads->push_back(serial->lastStep().loads);
    }
  }
  Snapshot<double> state;
  serial->read(state);
  return state;
}

} // namespace

TEST(DeviceSubdomainOnHost, OneRankIsBitIdenticalToTheSerialBackend)
{
  // One rank has no ghosts and migrates nothing: StepSchedule's stages in StepSchedule's order,
  // which reproduce the serial backend bit for bit (DeviceStepperHostTest).
  const PresetFluid setup = presetFluid("dam_break", 0.04);
  const Snapshot<double> reference = serialState(setup, 10, Precision::Double);
  const DecomposedOutcome one = runDecomposed(1, setup, 10, onHost<double>());
  EXPECT_EQ(one.state.id, reference.id); // the same cell order, too
  expectBitIdentical(one.state, reference);
}

TEST(DeviceSubdomainOnHost, TwoAndThreeRanksMatchTheSerialBackendAfterTenStepsInDouble)
{
  // Ranks sum a particle's neighbours in another order (a cell's particles arrive in another
  // order after migration, and ghosts come after the owned particles), so results differ from
  // the serial backend by rounding: ~1e-16 per sum, grown over ten steps to well under the
  // required 1e-9, while a neighbour missed or counted twice moves a particle by ~1e-3 of its
  // coordinate.
  const PresetFluid setup = presetFluid("dam_break", 0.04);
  const Snapshot<double> reference = serialState(setup, 10, Precision::Double);
  for (int ranks : { 2, 3 })
  {
    const DecomposedOutcome many = runDecomposed(ranks, setup, 10, onHost<double>(), true);
    const double error = maxRelativePositionError(many.state, reference);
    std::printf("%d ranks, 10 steps: max relative error %.3g\n", ranks, error);
    EXPECT_LE(error, 1e-9) << ranks << " ranks";
    EXPECT_GT(many.ghosts, 0u) << ranks << " ranks: no ghosts";
    for (const std::vector<std::uint64_t>& counts : many.counts)
    {
      for (std::uint64_t c : counts)
      {
        EXPECT_GT(c, 0u);
      }
    }
  }
}

TEST(DeviceSubdomainOnHost, ParticlesMigrateAndTheCutMoves)
{
  // The dam collapses towards +x: over 60 steps the cut follows the particles and particles
  // cross borders; the state must still match the serial backend (looser: 60 steps let the
  // rounding differences grow, to 1.1e-12 here; 1e-6 is still three orders below a wrong
  // neighbour: without the lambda refresh this reads 0.56).
  const PresetFluid setup = presetFluid("dam_break", 0.04);
  const Snapshot<double> reference = serialState(setup, 60, Precision::Double);
  const DecomposedOutcome two = runDecomposed(2, setup, 60, onHost<double>());
  const double error = maxRelativePositionError(two.state, reference);
  std::printf("2 ranks, 60 steps: %llu migrated, %d new cuts, max relative error %.3g\n",
    static_cast<unsigned long long>(two.migrated), two.cutsMoved, error);
  EXPECT_GT(two.migrated, 0u);
  EXPECT_GT(two.cutsMoved, 0);
  EXPECT_LE(error, 1e-6);
}

TEST(DeviceSubdomainOnHost, APressureMeanMigratesWithItsParticles)
{
  // The pressure's running mean over 60 steps (Stepper::setTimeStep) on 2 and 3 ranks: the
  // particles that cross a border carry their mean (the migrant record), the holes they leave
  // are filled with the mean of the particle moved in, and the cell sort gathers it. Against
  // the serial backend's mean: rounding only, 1e-6 of the largest pressure as the positions
  // above; a mean lost in a migration (read as 0 or another particle's) misses by O(1).
  const PresetFluid setup = presetFluid("dam_break", 0.04);
  const double dt = setup.parameters.timeStep;
  const auto meanStep = [dt](Stepper& stepper, int s) { stepper.setTimeStep(dt, s * dt); };
  auto serial = makeStepper(Backend::Serial, Precision::Double, setup.parameters, setup.fluid);
  for (int s = 0; s < 60; ++s)
  {
    meanStep(*serial, s);
    serial->step();
  }
  Snapshot<double> reference;
  serial->read(reference);
  for (int ranks : { 2, 3 })
  {
    const DecomposedOutcome many =
      runDecomposed(ranks, setup, 60, onHost<double>(), false, meanStep);
    const double error = maxRelativePressureError(many.state, reference);
    std::printf("%d ranks, 60 steps' pressure mean: %llu migrated, max relative error %.3g\n",
      ranks, static_cast<unsigned long long>(many.migrated), error);
    EXPECT_GT(many.migrated, 0u) << ranks << " ranks";
    EXPECT_LE(error, 1e-6) << ranks << " ranks";
  }
}

TEST(DeviceSubdomainOnHost, SinglePrecisionMatchesTheSerialBackendAfterOneStep)
{
  // Reordered float sums: a few ulps of a position after 4 iterations, ~1e-7 relative; 1e-5 is
  // far above that and far below a wrong neighbour.
  const PresetFluid setup = presetFluid("dam_break", 0.04);
  const Snapshot<double> reference = serialState(setup, 1, Precision::Single);
  const DecomposedOutcome two = runDecomposed(2, setup, 1, onHost<float>());
  EXPECT_LE(maxRelativePositionError(two.state, reference), 1e-5);
}

TEST(DeviceSubdomainOnHost, MasksVisitingOrderAndSkinChangeNoBit)
{
  // Each stage visited backwards (a stage reading what another particle of it writes would
  // differ, and so would a pass whose border and interior launches depended on each other),
  // masks off (the 27-cell walk) and any skin: all bit-identical. The masks must stay exact
  // across ranks although ghosts move by their owners' corrections.
  const PresetFluid setup = presetFluid("dam_break", 0.04);
  const DecomposedOutcome base = runDecomposed(3, setup, 10, onHost<double>());
  expectBitIdentical(runDecomposed(3, setup, 10, onHost<double>(true)).state, base.state);
  expectBitIdentical(runDecomposed(3, setup, 10, onHost<double>(false, 0.02, false)).state,
    base.state);
  for (double skin : { 1e-4, 0.3 })
  {
    expectBitIdentical(runDecomposed(3, setup, 10, onHost<double>(false, skin)).state, base.state);
  }
}

TEST(DeviceSubdomainOnHost, AdaptiveIterationsMatchTheSerialBackend)
{
  // Adaptive mode (the default): the ranks reduce the mean compression together after each
  // density pass and stop together. One rank sums it in the serial backend's blocks, so every
  // step stops at the same projection and the state is the same to the bit. Two and three ranks
  // sum in another order (per rank, then the ranks), which moves the mean by rounding only: the
  // same projections are taken as long as no step's mean lies within that rounding of the
  // tolerance, and positions then agree as in the fixed-count test (1e-9 m, see
  // TwoAndThreeRanksMatchTheSerialBackendAfterTenStepsInDouble).
  PresetFluid setup = presetFluid("dam_break", 0.08);
  setup.parameters.densityErrorTolerance = 0.2;
  setup.parameters.solverIterations = 40;
  const Snapshot<double> reference = serialState(setup, 10, Precision::Double);
  const DecomposedOutcome one = runDecomposed(1, setup, 10, onHost<double>());
  expectBitIdentical(one.state, reference);
  for (int ranks : { 2, 3 })
  {
    const DecomposedOutcome outcome = runDecomposed(ranks, setup, 10, onHost<double>());
    ASSERT_EQ(outcome.state.id.size(), reference.id.size());
    const std::map<std::int64_t, std::size_t> at = indexById(reference);
    double worst = 0;
    for (std::size_t i = 0; i < outcome.state.id.size(); ++i)
    {
      const Vec3d d = outcome.state.position[i] - reference.position[at.at(outcome.state.id[i])];
      worst = std::max(worst, length(d));
    }
    EXPECT_LT(worst, 1e-9) << ranks << " ranks";
  }
}

TEST(DeviceSubdomainOnHost, HealthIsTheRanksReducedScanOfTheState)
{
  // health() runs every automatic step, so it scans on the device and sends 4 KB a rank. It
  // must give every rank what a scan of the whole state gives: the fastest particle, the speeds'
  // 99.9th percentile (the next step's size) and the largest compression, to the bit (maxima
  // and integer counts, no sums of reals).
  const PresetFluid setup = presetFluid("dam_break", 0.08);
  std::vector<Health> seen(3);
  std::vector<Snapshot<double>> parts(3);
  distributed::runThreadCluster(3, [&](distributed::Communicator& communicator) {
    const auto r = static_cast<std::size_t>(communicator.rank());
    auto stepper = onHost<double>()(communicator, setup);
    for (int s = 0; s < 5; ++s)
    {
      stepper->step();
    }
    seen[r] = stepper->health();
    stepper->read(parts[r]);
  });
  double speed = 0, error = 0;
  std::vector<std::uint64_t> counts(kSpeedBins, 0);
  for (const Snapshot<double>& part : parts)
  {
    for (std::size_t i = 0; i < part.id.size(); ++i)
    {
      speed = std::max(speed, std::sqrt(dot(part.velocity[i], part.velocity[i])));
      error = std::max(error, part.density[i] / setup.parameters.restDensity - 1.0);
      ++counts[static_cast<std::size_t>(speedBin(dot(part.velocity[i], part.velocity[i])))];
    }
  }
  ASSERT_GT(speed, 0.0); // the column is falling
  for (const Health& h : seen)
  {
    EXPECT_EQ(h.maxSpeed, speed);
    EXPECT_EQ(h.robustSpeed, robustSpeed(counts.data(), speed));
    EXPECT_EQ(h.maxDensityError, std::max(error, 0.0));
    EXPECT_EQ(h.nonFinite, 0u);
  }
}

TEST(DeviceSubdomainOnHost, ADeviceFaultOnOneRankStopsEveryRankWithTheSameError)
{
  // Rank 1's device faults in the middle of a step (a synchronisation throws, as a CUDA error
  // does). Before ranks failed together, the other two then waited forever in the step's next
  // exchange (this test hung until CTest's timeout); now every rank throws a DeviceFault with
  // the same text, which names rank 1 and the fault.
  const PresetFluid setup = presetFluid("dam_break", 0.08);
  std::vector<std::string> errors(3);
  std::vector<int> steps(3, 0);
  distributed::runThreadCluster(3, [&](distributed::Communicator& communicator) {
    const auto r = static_cast<std::size_t>(communicator.rank());
    auto policy = std::make_unique<HostDevicePolicy>();
    HostDevicePolicy* device = policy.get();
    cuda::DeviceSubdomainStepper<double, HostDevicePolicy> stepper(
      communicator, setup.parameters, setup.fluid, std::move(policy));
    const long perStep = faultMidNextStep(stepper, *device, r == 1);
    ASSERT_GE(perStep, 2) << "a step waits for the device before its exchanges";
    try
    {
      for (int s = 0; s < 3; ++s)
      {
        stepper.step();
        ++steps[r];
      }
      errors[r] = "no error";
    }
    catch (const DeviceFault& fault)
    {
      errors[r] = fault.what();
    }
    catch (const std::exception& other)
    {
      errors[r] = std::string("not a DeviceFault: ") + other.what();
    }
  });
  EXPECT_NE(errors[0].find("rank 1 of 3: injected device fault"), std::string::npos) << errors[0];
  EXPECT_EQ(errors[1], errors[0]);
  EXPECT_EQ(errors[2], errors[0]);
  EXPECT_EQ(steps[1], 0) << "rank 1 faulted in its next step";
  EXPECT_EQ(steps[0], 0) << "rank 0 cannot finish the step without rank 1";
  EXPECT_EQ(steps[2], 0) << "rank 2 cannot finish the step without rank 1";
}

TEST(DeviceSubdomainOnHost, ACheckpointLoadedOnTheSameRanksContinuesBitIdentically)
{
  // loadState of the decomposed CUDA stepper's algorithm (what the filter's checkpoints and
  // scrubbing call on GPU ranks): a stepper that loads each rank's particles of step 10 takes the
  // same steps as the run that went on, bit for bit, with the adaptive projections and the
  // health scans of the defaults in between.
  PresetFluid setup = presetFluid("dam_break", 0.06);
  setup.parameters.densityErrorTolerance = Parameters().densityErrorTolerance;
  setup.parameters.solverIterations = Parameters().solverIterations;
  std::vector<Snapshot<double>> straight(3), resumed(3);
  distributed::runThreadCluster(3, [&](distributed::Communicator& communicator) {
    const auto r = static_cast<std::size_t>(communicator.rank());
    auto first = onHost<double>()(communicator, setup);
    for (int s = 0; s < 10; ++s)
    {
      first->step();
    }
    Snapshot<double> checkpoint;
    first->read(checkpoint);
    for (int s = 0; s < 8; ++s)
    {
      first->health();
      first->step();
    }
    first->read(straight[r]);
    auto second = onHost<double>()(communicator, setup);
    second->load(checkpoint);
    for (int s = 0; s < 8; ++s)
    {
      second->health();
      second->step();
    }
    second->read(resumed[r]);
  });
  std::size_t total = 0;
  for (std::size_t r = 0; r < 3; ++r)
  {
    total += straight[r].id.size();
    expectBitIdentical(straight[r], resumed[r]);
  }
  EXPECT_EQ(total, setup.fluid.position.size());
}

TEST(DeviceSubdomainOnHost, SolidsMatchTheSerialBackend)
{
  // A sphere just beyond the column's face, within h of its front particles from the start.
  PresetFluid setup = presetFluid("dam_break", 0.04);
  setup.parameters.tankLoads = true;
  const DistanceGrid sphere = sphereDistance({ 0.5, 0.1, 0.3 }, 0.09, 0.02, 0.08);
  std::vector<std::vector<SolidLoad>> loads;
  const Snapshot<double> reference = serialWithSolid(setup, sphere, 10, {}, &loads);
  const DecomposedFactory plain = onHost<double>();
  const DecomposedFactory withSphere = [&](distributed::Communicator& communicator,
                                         const PresetFluid& fluid) {
    auto stepper = plain(communicator, fluid);
    stepper->setObstacles({ sphere }); // collective, as Simulation calls it on every rank
    return stepper;
  };
  // One rank: StepSchedule's stages in the serial order, solids included: the same bits.
  expectBitIdentical(runDecomposed(1, setup, 10, withSphere).state, reference);
  // The solid changed the flow, so the comparisons say something about it.
  EXPECT_GT(maxRelativePositionError(serialState(setup, 10, Precision::Double), reference), 1e-6);
  // More ranks: rounding only (see TwoAndThreeRanksMatchTheSerialBackendAfterTenStepsInDouble),
  // where a rank without the solid would move its particles by ~1e-3.
  for (int ranks : { 2, 3 })
  {
    const DecomposedOutcome many = runDecomposed(ranks, setup, 10, withSphere, true);
    EXPECT_LE(maxRelativePositionError(many.state, reference), 1e-9) << ranks << " ranks";
    EXPECT_GT(many.ghosts, 0u) << ranks << " ranks: no ghosts";
    // Every rank's share of the sphere's load and of each wall's (summed per warp in the
    // correction), added in rank order: the serial loads to the positions' rounding (1e-9 of
    // the largest force, the floor's) and the same on every rank. A rank that missed its share
    // of the sphere would be off by ~1e-2 of its load, ~1e-4 of the floor's.
    ASSERT_EQ(many.loads.size(), loads.size());
    double largest = 0, sphereLargest = 0;
    for (const std::vector<SolidLoad>& step : loads)
    {
      ASSERT_EQ(step.size(), 1u + kMirrorWalls);
      sphereLargest = std::max(sphereLargest, length(step[0].force));
      for (const SolidLoad& load : step)
      {
        largest = std::max(largest, length(load.force));
      }
    }
    ASSERT_GT(sphereLargest, 0.0) << "the fluid never pressed the sphere";
    for (std::size_t s = 0; s < loads.size(); ++s)
    {
      ASSERT_EQ(many.loads[s].size(), loads[s].size());
      for (std::size_t o = 0; o < loads[s].size(); ++o)
      {
        const double tolerance = 1e-9 * (o == 0 ? sphereLargest : largest);
        EXPECT_LE(length(many.loads[s][o].force - loads[s][o].force), tolerance) << s << " " << o;
        EXPECT_LE(length(many.loads[s][o].torque - loads[s][o].torque), tolerance) << s << " " << o;
      }
    }
    EXPECT_TRUE(many.loadsAgreeOnEveryRank) << ranks << " ranks";
  }
}

TEST(DeviceSubdomainOnHost, WallFrictionMatchesTheSerialBackendOnBothDecomposedSteppers)
{
  // Friction at the box's walls and at a sphere: a ghost's velocity is refreshed before the
  // vorticity pass, so its images and its own share are the ones its owner sees.
  PresetFluid setup = presetFluid("dam_break", 0.04);
  setup.parameters.wallFriction = 0.8;
  const DistanceGrid sphere = sphereDistance({ 0.5, 0.1, 0.3 }, 0.09, 0.02, 0.08);
  const Snapshot<double> reference = serialWithSolid(setup, sphere, 10);
  PresetFluid slipping = setup;
  slipping.parameters.wallFriction = 0.0;
  const DecomposedFactory onDevice = onHost<double>();
  const DecomposedFactory onCpu = serialSubdomains();
  for (const DecomposedFactory& plain : { onDevice, onCpu })
  {
    const DecomposedFactory withSphere = [&](distributed::Communicator& communicator,
                                           const PresetFluid& fluid) {
      auto stepper = plain(communicator, fluid);
      stepper->setObstacles({ sphere });
      return stepper;
    };
    // Friction changed the flow, so the comparisons say something about it.
    EXPECT_GT(maxRelativePositionError(runDecomposed(1, slipping, 10, withSphere).state, reference),
      1e-6);
    for (int ranks : { 1, 2, 3 })
    {
      const DecomposedOutcome many = runDecomposed(ranks, setup, 10, withSphere);
      // As the solids' test: rounding only across ranks (1e-9), where a missed image would move
      // a particle by ~1e-4 of its position.
      EXPECT_LE(maxRelativePositionError(many.state, reference), 1e-9) << ranks << " ranks";
    }
  }
}

namespace
{

// A solver option on both decomposed steppers, 1 to 3 ranks, against the serial backend: the dam
// break with `set` applied to its parameters, and without. Rounding only across ranks (1e-9, as
// the other decomposed comparisons), where a ghost's value left stale moves particles by orders of
// magnitude more; and the option must have changed the flow, or the comparison says nothing.
template <class Set>
void expectOptionMatchesSerialOnBothDecomposedSteppers(Set&& set)
{
  const PresetFluid off = presetFluid("dam_break", 0.04);
  PresetFluid on = off;
  set(on.parameters);
  const Snapshot<double> reference = serialState(on, 10, Precision::Double);
  for (const DecomposedFactory& factory : { onHost<double>(), serialSubdomains() })
  {
    EXPECT_GT(maxRelativePositionError(runDecomposed(1, off, 10, factory).state, reference), 1e-9);
    for (int ranks : { 1, 2, 3 })
    {
      EXPECT_LE(maxRelativePositionError(runDecomposed(ranks, on, 10, factory).state, reference),
        1e-9)
        << ranks << " ranks";
    }
  }
}

} // namespace

TEST(DeviceSubdomainOnHost, XsphHyperViscosityMatchesTheSerialBackendOnBothDecomposedSteppers)
{
  // The bi-Laplacian reads the ghosts' XSPH sums, refreshed with their omega.
  expectOptionMatchesSerialOnBothDecomposedSteppers(
    [](Parameters& p) { p.xsphHyperViscosity = 0.1; });
}

TEST(DeviceSubdomainOnHost, ChebyshevAccelerationMatchesTheSerialBackendOnBothDecomposedSteppers)
{
  // Each owned particle blends its own positions two projections back; the ghosts' positions
  // arrive blended from their owners with every projection's refresh.
  expectOptionMatchesSerialOnBothDecomposedSteppers([](Parameters& p) { p.chebyshevRho = 0.8; });
}

TEST(DeviceSubdomainOnHost, MovingSolidsMatchTheSerialBackendOnBothDecomposedSteppers)
{
  // A sphere rolling into the column, with friction so that its surface velocity counts: every
  // rank places it alike before each step.
  PresetFluid setup = presetFluid("dam_break", 0.04);
  setup.parameters.wallFriction = 0.5;
  const DistanceGrid sphere = sphereDistance({ 0.5, 0.1, 0.3 }, 0.09, 0.02, 0.08);
  const SolidMotion motion = rollingSphere();
  const Snapshot<double> reference = serialWithSolid(setup, sphere, 10, motion);
  // The motion changed the flow, so the comparisons say something about it.
  EXPECT_GT(maxRelativePositionError(serialWithSolid(setup, sphere, 10), reference), 1e-6);
  const auto place = [&](Stepper& stepper, int s) {
    stepper.setObstaclePoses(poseAfterStep(motion, setup.parameters, s));
  };
  const DecomposedFactory onDevice = onHost<double>();
  const DecomposedFactory onCpu = serialSubdomains();
  for (const DecomposedFactory& plain : { onDevice, onCpu })
  {
    const DecomposedFactory withSphere = [&](distributed::Communicator& communicator,
                                           const PresetFluid& fluid) {
      auto stepper = plain(communicator, fluid);
      stepper->setObstacles({ sphere }, { motion.at(0.0) });
      return stepper;
    };
    expectBitIdentical(runDecomposed(1, setup, 10, withSphere, false, place).state, reference);
    for (int ranks : { 2, 3 })
    {
      // Rounding only across ranks (1e-9, as the static solids' test), where a rank placing the
      // sphere at another time would move its particles by ~1e-3.
      const DecomposedOutcome many = runDecomposed(ranks, setup, 10, withSphere, false, place);
      EXPECT_LE(maxRelativePositionError(many.state, reference), 1e-9) << ranks << " ranks";
    }
  }
}

// Outflows on the GPU ranks: each rank removes its own particles in the zones between steps (a
// stable selection over the owned ones, gathered as the step's end gathers them) and every rank
// returns the count of all. One rank is the serial backend's removal bit for bit; two and three
// remove the same particles (rounding apart, 1e-9 as above, and no particle near a zone's face
// by that much).
TEST(DeviceSubdomainOnHost, OutflowsRemoveOnEveryRankAsTheSerialBackendDoes)
{
  const PresetFluid setup = presetFluid("dam_break", 0.04);
  const std::vector<Box> zones = outflowTestZones();
  const int steps = 12;
  std::size_t removed = 0;
  const Snapshot<double> reference = serialWithOutflows(setup, zones, steps, removed);
  ASSERT_GT(removed, 50u);
  for (int ranks : { 1, 2, 3 })
  {
    std::vector<std::size_t> counted;
    const DecomposedOutcome run =
      decomposedWithOutflows(ranks, setup, zones, steps, onHost<double>(), counted);
    for (std::size_t count : counted)
    {
      EXPECT_EQ(count, removed) << ranks << " ranks: every rank returns the count of all";
    }
    if (ranks == 1)
    {
      EXPECT_EQ(run.state.id, reference.id);
      expectBitIdentical(run.state, reference);
      continue;
    }
    EXPECT_LE(maxRelativePositionError(run.state, reference), 1e-9) << ranks << " ranks";
  }
}

// Two liquids on GPU ranks: each particle's liquid travels with its migrant record and its
// ghost's seed, so the density contrast weighs every neighbour as one GPU and the CPU do.
TEST(DeviceSubdomainOnHost, LiquidsMatchTheSerialBackendAndEachParticleKeepsItsLiquid)
{
  const PresetFluid setup = sceneFluid(sideBySideLiquids(), 0.04);
  ASSERT_FALSE(setup.fluid.liquid.empty());
  // The oil's weight changed the flow, so the comparison says something about the liquids.
  PresetFluid plain = setup;
  plain.parameters.liquids.clear();
  plain.fluid.liquid.clear();
  const Snapshot<double> reference = serialState(setup, 10, Precision::Double);
  EXPECT_GT(maxRelativePositionError(serialState(plain, 10, Precision::Double), reference), 1e-6);
  expectRanksMatchSerial(setup, 10, onHost<double>(), nullptr, true);
}

TEST(DeviceSubdomainOnHost, AdaptiveIterationsWithTwoLiquidsTakeEachLiquidsMeanOverTheRanks)
{
  // The ranks add each liquid's sum and count before its mean (the most compressed liquid's
  // decides), as the serial backend averages each liquid over every particle. One rank is the
  // serial backend to the bit; two and three stop at the same projections (see
  // AdaptiveIterationsMatchTheSerialBackend) and agree within rounding.
  PresetFluid setup = sceneFluid(sideBySideLiquids(), 0.05);
  setup.parameters.densityErrorTolerance = 0.5;
  setup.parameters.solverIterations = 40;
  expectRanksMatchSerial(setup, 10, onHost<double>(), nullptr, true);
}

TEST(DeviceSubdomainOnHost, SurfaceTensionAndAdhesionMatchTheSerialBackend)
{
  // The dam break's surface pulled in (sigma 2 N/m at 4 cm), its walls wetting at 60 degrees,
  // and a sphere in the surge at 120: the ghosts' colour gradients and normals are refreshed
  // before the passes that read them (without the normals' refresh 3 ranks read 5e-5 here).
  PresetFluid setup = presetFluid("dam_break", 0.04);
  setup.parameters.surfaceTension = 2.0;
  setup.parameters.contactAngle = 60.0;
  DistanceGrid sphere = sphereDistance({ 0.5, 0.1, 0.3 }, 0.09, 0.02, 0.08);
  sphere.contactAngle.fill(120.0);
  const Snapshot<double> reference = serialWithSolid(setup, sphere, 10);
  PresetFluid without = setup;
  without.parameters.surfaceTension = 0.0;
  EXPECT_GT(maxRelativePositionError(serialWithSolid(without, sphere, 10), reference), 1e-6);
  expectRanksMatchSerial(setup, 10, onHost<double>(), &sphere, true);
  // Without solids, the passes without their images.
  expectRanksMatchSerial(setup, 10, onHost<double>(), nullptr, true);
}

TEST(DeviceSubdomainOnHost, TwoLiquidsWithSurfaceTensionMatchTheSerialBackend)
{
  PresetFluid setup = sceneFluid(sideBySideLiquids(), 0.04);
  setup.parameters.surfaceTension = 1.0;
  expectRanksMatchSerial(setup, 10, onHost<double>(), nullptr, true);
}

namespace
{

using Store = cuda::DeviceParticleStore<float, HostDevicePolicy>;

// A store of `n` particles whose x, density and id read k at particle k.
void fill(Store& store, std::size_t n)
{
  store.reserve(n, 0);
  for (std::size_t k = 0; k < n; ++k)
  {
    store.p.vec[0][k] = Vec3<float>{ float(k), 0.f, 0.f };
    store.p.density[k] = float(k);
    store.p.id[k] = static_cast<std::int64_t>(k);
  }
}

bool holds(const Store& store, std::size_t n)
{
  for (std::size_t k = 0; k < n; ++k)
  {
    if (store.p.vec[0][k].x != float(k) || store.p.density[k] != float(k) ||
      store.p.id[k] != static_cast<std::int64_t>(k))
    {
      return false;
    }
  }
  return true;
}

} // namespace

// A store that fills most of its device grows without holding two arenas at once: by a
// sixteenth, its particles on the host while the old arena makes room; a growth that does not
// fit even then leaves it as it was, with its particles, and names the count.
TEST(DeviceParticleStore, GrowsThroughTheHostWhereBothArenasDoNotFitAndKeepsItsParticles)
{
  const std::size_t n = 100000;
  const std::size_t perParticle = Store::bytesPerParticle(cuda::ParticleArrays{});
  for (bool fits : { true, false })
  {
    HostDevicePolicy device;
    Store store(device, cuda::ParticleArrays{}, 1000, 16);
    fill(store, n);
    const std::size_t held = device.allocatedBytes();
    ASSERT_GE(held, n * perParticle);
    // A sixteenth more (106,250 particles) fits once the old arena is gone, not beside it (the
    // arena's padding and block sums are a few KiB); or only the old arena fits.
    const std::size_t grown = (n + n / 16) * perParticle + (std::size_t(64) << 10);
    device.setFreeMemory(Store::kHeadRoom + (fits ? grown : held));
    if (fits)
    {
      store.reserve(n + 1, n);
      EXPECT_EQ(store.capacity(), n + n / 16);
      EXPECT_LE(device.allocatedBytes(), grown);
    }
    else
    {
      EXPECT_THROW(store.reserve(n + 1, n), InvalidInput);
      EXPECT_EQ(store.capacity(), n);
    }
    EXPECT_TRUE(holds(store, n)) << (fits ? "grown" : "refused");
  }
}

// The fluid in pieces, one a rank (the filter's input under a parallel pipeline): each rank's
// piece goes to the ranks that own its particles, and the run is the run of ranks handed the
// whole batch, the same particles on the same ranks in the same order, to the bit.
TEST(DeviceSubdomainOnHost, RanksGivenPiecesOfTheFluidRunAsRanksHandedItWhole)
{
  const PresetFluid setup = sceneFluid(sideBySideLiquids(), 0.04);
  const DecomposedFactory fromPieces = [](distributed::Communicator& communicator,
                                         const PresetFluid& whole) {
    // The rank's share of the batch in its own order, which cuts across the slabs.
    const ParticleBatch& all = whole.fluid;
    const std::size_t n = all.position.size();
    const auto r = static_cast<std::size_t>(communicator.rank());
    const auto k = static_cast<std::size_t>(communicator.size());
    const auto from = static_cast<std::ptrdiff_t>(n * r / k);
    const auto to = static_cast<std::ptrdiff_t>(n * (r + 1) / k);
    ParticleBatch piece;
    piece.position.assign(all.position.begin() + from, all.position.begin() + to);
    piece.velocity.assign(all.velocity.begin() + from, all.velocity.begin() + to);
    piece.id.assign(all.id.begin() + from, all.id.begin() + to);
    piece.liquid.assign(all.liquid.begin() + from, all.liquid.begin() + to);
    const distributed::FluidPieces fluid(piece, communicator);
    return std::unique_ptr<distributed::DecomposedStepper>(
      new cuda::DeviceSubdomainStepper<double, HostDevicePolicy>(communicator, whole.parameters,
        fluid, std::make_unique<HostDevicePolicy>()));
  };
  for (int ranks : { 2, 3 })
  {
    SCOPED_TRACE(std::to_string(ranks) + " ranks");
    const DecomposedOutcome pieces = runDecomposed(ranks, setup, 6, fromPieces);
    const DecomposedOutcome handed = runDecomposed(ranks, setup, 6, onHost<double>());
    EXPECT_EQ(pieces.state.id, handed.state.id);
    EXPECT_EQ(pieces.state.liquid, handed.state.liquid);
    expectBitIdentical(pieces.state, handed.state);
  }
}

// Each GPU rank sorts its particles in a window of the domain's grid: its slab's columns and its
// ghosts', less the empty ones, so that its cell offsets are its share of the domain's (a
// billion particles on four GPUs otherwise hold the whole domain's offsets on each: 153 bytes a
// particle against 144 on one). The runs above are the same bits as before the window.
TEST(DeviceSubdomainOnHost, EachRankSortsInAWindowOfItsSlabAndGhostColumns)
{
  const PresetFluid setup = presetFluid("dam_break", 0.04);
  std::vector<std::uint32_t> window(3), domain(3);
  std::vector<distributed::Slabs> slabs(3);
  distributed::runThreadCluster(3, [&](distributed::Communicator& communicator) {
    const auto r = static_cast<std::size_t>(communicator.rank());
    cuda::DeviceSubdomainStepper<double, HostDevicePolicy> stepper(
      communicator, setup.parameters, setup.fluid, std::make_unique<HostDevicePolicy>());
    for (int s = 0; s < 5; ++s)
    {
      stepper.step();
    }
    window[r] = stepper.windowCells();
    domain[r] = stepper.domainCells();
    slabs[r] = stepper.slabs();
  });
  const GridGeometry<double> g =
    makeGridGeometry<double>(setup.parameters.domain, setup.parameters.smoothingLength());
  std::uint64_t sum = 0;
  for (std::size_t r = 0; r < 3; ++r)
  {
    SCOPED_TRACE("rank " + std::to_string(r));
    EXPECT_EQ(domain[r], g.cellCount());
    const int columns = slabs[r].first[r + 1] - slabs[r].first[r] + (r > 0) + (r < 2);
    EXPECT_GT(window[r], 0u);
    EXPECT_LE(window[r], static_cast<std::uint32_t>(columns * g.ny * g.nz));
    sum += window[r];
  }
  // The dam's water fills 0.58 of the tank's 1.6 m: the windows together hold well under the
  // domain's cells (ghost columns counted twice).
  EXPECT_LT(sum, g.cellCount() / 2) << sum << " of " << g.cellCount();
}
