// The CUDA backend against the serial reference (label "gpu"). Without a usable CUDA device every
// test reports SKIPPED, which CTest counts as skipped, not passed.
#include "Backends.h"
#include "Cuda/CudaBackend.h"
#include "DecomposedRuns.h"
#include "RequireGpu.h"
#include "Scene.h"
#include "Simulation.h"
#include "Stepper.h"
#include "TestScenes.h"
#include "WallLoads.h"

#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <utility>
#include <stdexcept>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

// The backend comparisons run the paper's fixed scheme (fixed steps, 4 projections), so that the
// two backends differ by rounding only; the defaults (automatic steps, adaptive projections) are
// tested below on their own (DefaultsAreBitIdenticalAcrossRunsAndResumes, RefinedDamBreak...).
Parameters smallParameters(double spacing)
{
  Parameters p;
  p.particleSpacing = spacing;
  p.timeStepping = TimeStepping::Fixed;
  p.densityErrorTolerance = 0;
  p.solverIterations = 4;
  return p;
}

struct Outcome
{
  Snapshot<double> state;
  Statistics statistics;
};

Outcome run(const std::string& scene, Backend backend, Precision precision, double spacing, int steps)
{
  Simulation simulation(presetScene(scene), smallParameters(spacing), backend, precision);
  simulation.advance(steps);
  Outcome r;
  simulation.stepper().read(r.state);
  r.statistics = simulation.stepper().statistics();
  return r;
}

template <class Real>
Snapshot<Real> runCuda(const std::string& sceneName, Precision precision, int steps,
  const cuda::Options& options, double spacing = 0.04)
{
  const Scene scene = presetScene(sceneName);
  const Parameters p = withSceneDomain(smallParameters(spacing), scene);
  auto stepper = cuda::makeCudaStepper(precision, p, fillScene(scene, p), options);
  for (int s = 0; s < steps; ++s)
  {
    stepper->step();
  }
  Snapshot<Real> out;
  stepper->read(out);
  return out;
}

// The state after two steps in double precision (the comparisons of an option that acts on the
// velocities: positions show it from the second step on).
Snapshot<double> afterTwoSteps(const Scene& scene, const Parameters& p, Backend backend)
{
  Simulation simulation(scene, p, backend, Precision::Double);
  simulation.advance(2);
  Snapshot<double> state;
  simulation.stepper().read(state);
  return state;
}

cuda::Options withSearch(cuda::NeighborSearch search)
{
  cuda::Options o;
  o.search = search;
  return o;
}

} // namespace

TEST(CudaStepper, WithoutADeviceTheBackendIsUnavailableNotBroken)
{
  std::string why;
  if (cudaAvailable(&why))
  {
    GTEST_SKIP() << "a CUDA device is present: this checks the behaviour without one";
  }
  EXPECT_FALSE(why.empty());
  Parameters p;
  const Scene scene = presetScene("dam_break");
  p = withSceneDomain(p, scene);
  EXPECT_THROW(makeStepper(Backend::CUDA, Precision::Single, p, fillScene(scene, p)),
    std::runtime_error);
}

TEST(CudaStepper, DescribesItsDevice)
{
  PBF_REQUIRE_GPU();
  const Scene scene = presetScene("dam_break");
  const Parameters p = withSceneDomain(smallParameters(0.04), scene);
  auto stepper = makeStepper(Backend::CUDA, Precision::Single, p, fillScene(scene, p));
  EXPECT_EQ(stepper->backend(), Backend::CUDA);
  EXPECT_EQ(stepper->description().rfind("CUDA, ", 0), 0u) << stepper->description();
  EXPECT_GT(stepper->description().size(), 6u);
}

TEST(CudaStepper, OneStepMatchesSerialInSinglePrecision)
{
  PBF_REQUIRE_GPU();
  // The GPU differs from the host only in rounding: nvcc fuses a * b + c into one FMA (the x86-64
  // host build does not) and CUDA's powf may differ from glibc's by an ulp or two. After one step
  // (4 Jacobi iterations) that is a few ulps of the position, ~1e-7 relative in float; 1e-5 is
  // far above that and far below a wrong neighbour or a missed term (>= 1e-4 of the spacing).
  const Outcome serial = run("dam_break", Backend::Serial, Precision::Single, 0.02, 1);
  for (auto search : { cuda::NeighborSearch::RowMasks, cuda::NeighborSearch::CellWalk })
  {
    const Scene scene = presetScene("dam_break");
    const Parameters p = withSceneDomain(smallParameters(0.02), scene);
    auto gpu = cuda::makeCudaStepper(Precision::Single, p, fillScene(scene, p), withSearch(search));
    gpu->step();
    Snapshot<double> state;
    gpu->read(state);
    EXPECT_LE(test::maxRelativePositionError(state, serial.state), 1e-5);
  }
}

TEST(CudaStepper, OneStepMatchesSerialInDoublePrecision)
{
  PBF_REQUIRE_GPU();
  // The same rounding differences in double are ~1e-16 relative, grown by the solver to ~1e-14;
  // 1e-12 leaves a margin of 100 while still catching any difference in the arithmetic.
  const Outcome serial = run("dam_break", Backend::Serial, Precision::Double, 0.02, 1);
  const Outcome gpu = run("dam_break", Backend::CUDA, Precision::Double, 0.02, 1);
  EXPECT_LE(test::maxRelativePositionError(gpu.state, serial.state), 1e-12);
  // The pressure is lambda's sum over the projections, rounded alike: 1e-9 of its largest value.
  EXPECT_LE(test::maxRelativePressureError(gpu.state, serial.state), 1e-9);
  // Statistics are computed on the GPU: the same formulas, summed in another order (1e-15
  // relative), so 1e-9 relative for the quantities that vary continuously with the positions.
  const Statistics& g = gpu.statistics;
  const Statistics& c = serial.statistics;
  EXPECT_NEAR(g.kineticEnergy, c.kineticEnergy, 1e-9 * c.kineticEnergy);
  EXPECT_NEAR(g.momentum.y, c.momentum.y, 1e-9 * std::abs(c.momentum.y));
  EXPECT_NEAR(g.averageDensityError, c.averageDensityError, 1e-9 * c.averageDensityError);
  EXPECT_NEAR(g.maxDensityError, c.maxDensityError, 1e-9 * c.maxDensityError);
  EXPECT_NEAR(g.maxSpeed, c.maxSpeed, 1e-9 * c.maxSpeed);
  EXPECT_EQ(g.particles, c.particles);
  EXPECT_TRUE(g.finite);
}

TEST(CudaStepper, StatisticsCountTheSameNeighborsAsTheHost)
{
  PBF_REQUIRE_GPU();
  // Before any step both backends hold the lattice itself, where many pairs sit at exactly h:
  // the neighbour count is exact there, and the density, computed on each, agrees to rounding.
  for (Precision precision : { Precision::Single, Precision::Double })
  {
    const Outcome serial = run("dam_break", Backend::Serial, precision, 0.02, 0);
    const Outcome gpu = run("dam_break", Backend::CUDA, precision, 0.02, 0);
    EXPECT_EQ(gpu.statistics.averageNeighbors, serial.statistics.averageNeighbors);
    EXPECT_NEAR(gpu.statistics.maxDensityError, serial.statistics.maxDensityError, 1e-5);
  }
}

// Means over the steps 1..steps of the average density error and of the kinetic energy.
static std::pair<double, double> meanStatistics(Backend backend, Precision precision, int steps)
{
  Simulation simulation(presetScene("dam_break"), smallParameters(0.04), backend, precision);
  double error = 0, kinetic = 0;
  for (int s = 0; s < steps; ++s)
  {
    simulation.advance(1);
    const Statistics statistics = simulation.stepper().statistics();
    EXPECT_TRUE(statistics.finite);
    error += statistics.averageDensityError / steps;
    kinetic += statistics.kineticEnergy / steps;
  }
  return { error, kinetic };
}

TEST(CudaStepper, TwoHundredStepsOfADamBreakTrackSerialStatistics)
{
  PBF_REQUIRE_GPU();
  // The dam break is chaotic: moving every particle of the serial run by one ulp changes its
  // average density error at step 200 by 7-18% (float and double alike; the kinetic energy by up
  // to 1%), so single steps of two runs that round differently are not comparable. Their means
  // over the 200 steps are: the same perturbation moves them by 0.06% (error) and 0.02% (energy)
  // in double, 0.4-1.1% and 0.2-0.7% in float. So 1% in double, and 3% in float, where the
  // chaos alone uses up to 1.1%. Both are far below what a missing term (s_corr, XSPH,
  // vorticity) or a wrong neighbour set changes (tens of percent).
  for (Precision precision : { Precision::Double, Precision::Single })
  {
    SCOPED_TRACE(toString(precision));
    const double tolerance = precision == Precision::Double ? 0.01 : 0.03;
    const auto serial = meanStatistics(Backend::Serial, precision, 200);
    const auto gpu = meanStatistics(Backend::CUDA, precision, 200);
    EXPECT_NEAR(gpu.first, serial.first, tolerance * serial.first);
    EXPECT_NEAR(gpu.second, serial.second, tolerance * serial.second);
  }
}

TEST(CudaStepper, TwoRunsAreBitIdentical)
{
  PBF_REQUIRE_GPU();
  // No atomics feed the state, and the sort is stable: a run is reproducible to the bit.
  const cuda::Options defaults;
  test::expectBitIdentical(runCuda<float>("dam_break", Precision::Single, 100, defaults),
    runCuda<float>("dam_break", Precision::Single, 100, defaults));
  test::expectBitIdentical(runCuda<double>("blob", Precision::Double, 100, defaults),
    runCuda<double>("blob", Precision::Double, 100, defaults));
}

TEST(CudaStepper, NeighborMasksAndGraphsChangeNoBit)
{
  PBF_REQUIRE_GPU();
  // Masks skip only candidates that cannot be within h and keep the walk's order; a graph replays
  // the same kernels. So every combination gives the same bits, whatever the skin.
  cuda::Options walk = withSearch(cuda::NeighborSearch::CellWalk);
  walk.graphs = false;
  const auto reference = runCuda<float>("blob", Precision::Single, 80, walk);
  for (double skin : { 1e-4, 0.05, 0.3 })
  {
    for (bool graphs : { false, true })
    {
      cuda::Options o;
      o.skin = skin;
      o.graphs = graphs;
      SCOPED_TRACE("skin " + std::to_string(skin) + (graphs ? ", graphs" : ""));
      test::expectBitIdentical(reference, runCuda<float>("blob", Precision::Single, 80, o));
    }
  }
  // Three iterations swap the x and v buffers every step.
  const Scene scene = presetScene("dam_break");
  Parameters p = withSceneDomain(smallParameters(0.04), scene);
  p.solverIterations = 3;
  auto a = cuda::makeCudaStepper(Precision::Single, p, fillScene(scene, p), walk);
  auto b = cuda::makeCudaStepper(Precision::Single, p, fillScene(scene, p), cuda::Options{});
  for (int s = 0; s < 41; ++s)
  {
    a->step();
    b->step();
  }
  Snapshot<float> sa, sb;
  a->read(sa);
  b->read(sb);
  test::expectBitIdentical(sa, sb);
}

TEST(CudaStepper, EmittersGrowTheDeviceArraysLikeTheSerialBackend)
{
  PBF_REQUIRE_GPU();
  // At this spacing the stream emits about 125 particles a step: the device arrays start with
  // room for 1024 and are reallocated three times within 20 steps. The jet is chaotic once it
  // lands (moving the nozzle by one ulp changes positions by 4e-12 relative at step 20 and 2e-2
  // at step 100, on the CPU alone), so compare early, in double, at 1e-8: the GPU rounds
  // differently at every operation, not once, and 1e-8 is still six orders below a particle out
  // of place (1e-2).
  const Outcome serial = run("stream", Backend::Serial, Precision::Double, 0.01, 20);
  const Outcome gpu = run("stream", Backend::CUDA, Precision::Double, 0.01, 20);
  ASSERT_GT(gpu.state.id.size(), 2304u);
  ASSERT_EQ(gpu.state.id.size(), serial.state.id.size());
  EXPECT_LE(test::maxRelativePositionError(gpu.state, serial.state), 1e-8);
}

TEST(CudaStepper, MoreParticlesThanFreeMemoryIsInvalidInput)
{
  PBF_REQUIRE_GPU();
  // Take nearly all free memory, then ask for 2M particles (about 220 MiB).
  std::vector<void*> hog;
  std::size_t freeBytes = 0, totalBytes = 0;
  ASSERT_EQ(cudaMemGetInfo(&freeBytes, &totalBytes), cudaSuccess);
  std::size_t chunk = std::size_t(1) << 30;
  while (chunk >= (std::size_t(1) << 20))
  {
    ASSERT_EQ(cudaMemGetInfo(&freeBytes, &totalBytes), cudaSuccess);
    if (freeBytes < (std::size_t(48) << 20))
    {
      break;
    }
    void* p = nullptr;
    if (chunk < freeBytes - (std::size_t(32) << 20) && cudaMalloc(&p, chunk) == cudaSuccess)
    {
      hog.push_back(p);
    }
    else
    {
      cudaGetLastError();
      chunk /= 2;
    }
  }
  std::string message;
  try
  {
    Scene scene = presetScene("dam_break");
    Parameters p = withSceneDomain(smallParameters(0.004), scene); // 100 x 150 x 150 particles
    makeStepper(Backend::CUDA, Precision::Single, p, fillScene(scene, p));
  }
  catch (const InvalidInput& error)
  {
    message = error.what();
  }
  catch (const std::exception& error)
  {
    ADD_FAILURE() << "expected InvalidInput, got: " << error.what();
  }
  for (void* p : hog)
  {
    cudaFree(p);
  }
  EXPECT_NE(message.find("particle count = 2250000"), std::string::npos) << message;
  EXPECT_NE(message.find("MiB free"), std::string::npos) << message;
  // The device is still usable afterwards.
  const Outcome after = run("dam_break", Backend::CUDA, Precision::Single, 0.04, 2);
  EXPECT_TRUE(after.statistics.finite);
}

TEST(CudaStepper, CheckpointRestoresBitIdentically)
{
  PBF_REQUIRE_GPU();
  // load() replaces the device state with a snapshot; the steps that follow must be the ones that
  // followed it. The stream's emitters are state too, kept by Simulation.
  for (const char* scene : { "dam_break", "stream" })
  {
    Simulation straight(presetScene(scene), smallParameters(0.04), Backend::CUDA, Precision::Single);
    straight.advance(50);
    Simulation resumed(presetScene(scene), smallParameters(0.04), Backend::CUDA, Precision::Single);
    resumed.advance(20);
    const SimulationCheckpoint at20 = resumed.checkpoint();
    resumed.advance(17);
    resumed.restore(at20);
    resumed.advance(30);
    Snapshot<float> a, b;
    straight.stepper().read(a);
    resumed.stepper().read(b);
    SCOPED_TRACE(scene);
    test::expectBitIdentical(a, b);
  }
}

TEST(CudaStepper, AdaptiveIterationsFollowTheSerialBackend)
{
  PBF_REQUIRE_GPU();
  // Adaptive mode stops projecting once the mean compression is within the tolerance. The GPU sums
  // that mean in another order than the CPU and rounds differently (FMA) throughout, so the runs
  // drift apart by rounding: over 40 steps in double that moved the final mean by 9e-7 relative
  // on the H200, far too little to flip a decision unless the mean lands within that of the
  // tolerance. So the iteration counts must agree, and the final errors within 1e-4 relative.
  Parameters p = smallParameters(0.04);
  p.solverIterations = 6;
  p.densityErrorTolerance = 0.05;
  Simulation serial(presetScene("dam_break"), p, Backend::Serial, Precision::Double);
  Simulation gpu(presetScene("dam_break"), p, Backend::CUDA, Precision::Double);
  const AdvanceReport a = serial.advance(40);
  const AdvanceReport b = gpu.advance(40);
  EXPECT_EQ(b.iterations, a.iterations);
  EXPECT_LT(a.iterations, 40 * 6); // some steps stopped early
  EXPECT_NEAR(b.densityError, a.densityError, 1e-4 * a.densityError);
}

TEST(CudaStepper, AdaptiveStepsAreTheSameCapturedOrStageByStage)
{
  PBF_REQUIRE_GPU();
  // A captured step skips the projections after the tolerance is met as conditional graph nodes
  // that do not run; stage by stage they are launched and return at once. Both must leave the
  // same bits, with an even and an odd cap (the positions then end in either buffer).
  const Scene scene = presetScene("dam_break");
  for (int cap : { 6, 7 })
  {
    Parameters p = withSceneDomain(smallParameters(0.04), scene);
    p.solverIterations = cap;
    p.densityErrorTolerance = 0.05;
    cuda::Options staged;
    staged.graphs = false;
    auto a = cuda::makeCudaStepper(Precision::Single, p, fillScene(scene, p), staged);
    auto b = cuda::makeCudaStepper(Precision::Single, p, fillScene(scene, p), cuda::Options{});
    int iterationsA = 0, iterationsB = 0;
    const int steps = 40;
    for (int s = 0; s < steps; ++s)
    {
      a->step();
      b->step();
      iterationsA += a->lastStep().iterations;
      iterationsB += b->lastStep().iterations;
    }
    SCOPED_TRACE("cap " + std::to_string(cap));
    EXPECT_EQ(iterationsA, iterationsB);
    EXPECT_LT(iterationsB, steps * cap); // some steps stopped early
    EXPECT_GT(iterationsB, steps);       // and some projected more than once
    Snapshot<float> sa, sb;
    a->read(sa);
    b->read(sb);
    test::expectBitIdentical(sa, sb);
  }
}

TEST(CudaStepper, DefaultsAreBitIdenticalAcrossRunsAndResumes)
{
  PBF_REQUIRE_GPU();
  // Automatic steps and adaptive projections on the GPU: each step's size comes from the device's
  // health scan (maxima only) and each step's projections from its compression reduction (fixed
  // blocks), so two runs frame by frame are the same to the bit, and so is a run resumed from a
  // checkpoint taken at a frame.
  Parameters p;
  p.particleSpacing = 0.04;
  const Scene scene = presetScene("dam_break");
  Simulation a(scene, p, Backend::CUDA, Precision::Single);
  Simulation b(scene, p, Backend::CUDA, Precision::Single);
  SimulationCheckpoint at5;
  for (int frame = 1; frame <= 12; ++frame)
  {
    a.advanceTo(frame / 60.0);
    b.advanceTo(frame / 60.0);
    if (frame == 5)
    {
      at5 = b.checkpoint();
    }
  }
  b.advanceTo(14 / 60.0); // past the frame, then back
  b.restore(at5);
  for (int frame = 6; frame <= 12; ++frame)
  {
    b.advanceTo(frame / 60.0);
  }
  EXPECT_EQ(a.time(), 12 / 60.0);
  EXPECT_EQ(a.stepCount(), b.stepCount());
  EXPECT_GT(a.stepCount(), 12u * 4u); // the CFL step is below 1/240 s here
  Snapshot<float> x, y;
  a.stepper().read(x);
  b.stepper().read(y);
  test::expectBitIdentical(x, y);
}

TEST(CudaStepper, RefinedDamBreakAtAMillionParticlesHolds)
{
  PBF_REQUIRE_GPU();
  // The refined dam break's case: the dam_break preset at s = 5 mm (1,152,000 particles) with the
  // defaults blew up by step 60 before (max density error 3,779 %, 408 m/s). The first 0.25 s
  // (the column's collapse, where it blew up) must hold the required bounds in every frame: mean
  // compression <= 0.5 %, max <= 10 %, no particle faster than 3 sqrt(g H) = 7.3 m/s.
  Parameters p;
  p.particleSpacing = 0.005;
  Simulation simulation(presetScene("dam_break"), p, Backend::CUDA, Precision::Single);
  ASSERT_EQ(simulation.stepper().size(), 1152000u);
  for (int frame = 1; frame <= 15; ++frame)
  {
    ASSERT_NO_THROW(simulation.advanceTo(frame / 60.0)) << "frame " << frame;
    const Statistics s = simulation.stepper().statistics();
    EXPECT_LE(s.averageDensityError, 0.005) << "frame " << frame;
    EXPECT_LE(s.maxDensityError, 0.10) << "frame " << frame;
    EXPECT_LE(s.maxSpeed, 7.3) << "frame " << frame;
  }
  EXPECT_EQ(simulation.time(), 0.25);
}

TEST(CudaStepper, TheDivergenceCheckStopsABlowUpOnTheGpu)
{
  PBF_REQUIRE_GPU();
  // On the GPU the check runs at every frame with fixed steps (and after every automatic step):
  // frames of one step each must stop at the step where the fluid piles up, never hand out a
  // frame of it, and blame the time step.
  // The serial divergence test's blow-up (DivergenceTest.cpp, HugeTimeStepIsCaughtAtTheStepItHappens).
  Simulation simulation(presetScene("dam_break"), test::hugeFixedStep(), Backend::CUDA, Precision::Single);
  int frames = 0;
  try
  {
    for (int k = 1; k <= 60; ++k)
    {
      simulation.advanceTo(0.05 * k);
      ++frames;
      const Statistics s = simulation.stepper().statistics();
      ASSERT_LT(s.maxDensityError, 2.0) << "frame " << k << " handed out a blown-up state";
    }
    FAIL() << "60 steps of 0.05 s on the GPU and no divergence found";
  }
  catch (const SimulationDiverged& error)
  {
    std::printf("CUDA: %s\n", error.what());
    EXPECT_LE(error.step(), 6u);
    EXPECT_EQ(static_cast<int>(error.step()), frames + 1) << "caught at the frame it happened";
    EXPECT_NE(error.cause().find("time step dt = 0.05 s is too large"), std::string::npos)
      << error.cause();
  }
}

TEST(CudaStepper, SolidsMatchTheSerialBackend)
{
  PBF_REQUIRE_GPU();
  // Double precision, the fixed scheme: as OneStepMatchesSerialInDoublePrecision, rounding only
  // (1e-12 relative after a step), now with the solids' terms in every pass.
  const Scene scene = test::damBreakWithSolids();
  Parameters p = smallParameters(0.04);
  p.tankLoads = true;
  Simulation serial(scene, p, Backend::Serial, Precision::Double);
  Simulation gpu(scene, p, Backend::CUDA, Precision::Double);
  ASSERT_EQ(gpu.stepper().size(), serial.stepper().size());
  ASSERT_GT(gpu.seededInsideSolids(), 0u);
  serial.advance(1);
  gpu.advance(1);
  Snapshot<double> a, b;
  serial.stepper().read(a);
  gpu.stepper().read(b);
  EXPECT_LE(test::maxRelativePositionError(b, a), 1e-12);
  // The loads on the solids, summed on the device in fixed trees, then the six mirror walls',
  // summed per warp inside the correction: the serial ones to the same rounding (1e-12 of the
  // largest force, per kind), where a missed particle would be off by ~1e-3 of a load.
  const std::vector<SolidLoad> expected = serial.stepper().lastStep().loads;
  const std::vector<SolidLoad> loads = gpu.stepper().lastStep().loads;
  ASSERT_EQ(expected.size(), scene.solids.size() + kMirrorWalls);
  ASSERT_EQ(loads.size(), expected.size());
  double solidLargest = 0, wallLargest = 0;
  for (std::size_t o = 0; o < loads.size(); ++o)
  {
    double& largest = o < scene.solids.size() ? solidLargest : wallLargest;
    largest = std::max(largest, length(expected[o].force));
  }
  ASSERT_GT(solidLargest, 0.0) << "the fluid pressed no solid in the first step";
  ASSERT_GT(wallLargest, 0.0) << "the fluid pressed no wall in the first step";
  for (std::size_t o = 0; o < loads.size(); ++o)
  {
    const double largest = o < scene.solids.size() ? solidLargest : wallLargest;
    EXPECT_LE(length(loads[o].force - expected[o].force), 1e-12 * largest) << o;
    EXPECT_LE(length(loads[o].torque - expected[o].torque), 1e-12 * largest) << o;
  }
}

TEST(CudaStepper, ADynamicBodyMatchesTheSerialBackendAndRepeatsItself)
{
  PBF_REQUIRE_GPU();
  // A box of half the water's density let go with its bottom just under the surface, 30 steps
  // in double precision: each step's load comes back from the device and moves the box on the
  // host, whose pose goes back before the next step. The fluid agrees to rounding, which the
  // coupling carries into the box (1e-9 of its size and of its speed scale, sqrt(g L)); a pose
  // a step late would be off by v dt ~ 1e-4 of its size. Two GPU runs: the same bits.
  Scene scene;
  scene.domain = { { 0, 0, 0 }, { 0.6, 0.6, 0.6 } };
  scene.boxes.push_back({ { 0, 0, 0 }, { 0.6, 0.3, 0.6 }, { 0, 0, 0 } });
  SolidRegion box;
  box.kind = SolidRegion::Kind::Box;
  box.box = { { 0.2, 0.28, 0.2 }, { 0.4, 0.44, 0.4 } };
  box.density = 500;
  box.name = "box";
  scene.solids.push_back(box);
  Parameters p = smallParameters(0.04);
  Simulation serial(scene, p, Backend::Serial, Precision::Double);
  Simulation gpu(scene, p, Backend::CUDA, Precision::Double);
  Simulation again(scene, p, Backend::CUDA, Precision::Double);
  serial.advance(30);
  gpu.advance(30);
  again.advance(30);
  const RigidState& a = serial.bodies().at(0).state;
  const RigidState& b = gpu.bodies().at(0).state;
  const RigidState& c = again.bodies().at(0).state;
  const double size = 0.2;
  const double speed = std::sqrt(9.81 * size);
  EXPECT_GT(length(a.velocity), 1e-3) << "the box did not move: the coupling was not tested";
  EXPECT_LE(length(b.centre - a.centre), 1e-9 * size);
  EXPECT_LE(length(b.velocity - a.velocity), 1e-9 * speed);
  EXPECT_LE(length(b.angularMomentum - a.angularMomentum),
    1e-9 * gpu.bodies()[0].mass.mass * speed * size);
  EXPECT_EQ(b.centre.x, c.centre.x);
  EXPECT_EQ(b.centre.y, c.centre.y);
  EXPECT_EQ(b.centre.z, c.centre.z);
  EXPECT_EQ(b.velocity.y, c.velocity.y);
  EXPECT_EQ(b.orientation.w, c.orientation.w);
  Snapshot<double> fluid, reference;
  serial.stepper().read(reference);
  gpu.stepper().read(fluid);
  EXPECT_LE(test::maxRelativePositionError(fluid, reference), 1e-10);
}

TEST(CudaStepper, WallFrictionMatchesTheSerialBackend)
{
  PBF_REQUIRE_GPU();
  // As SolidsMatchTheSerialBackend, with friction at the box's walls and the solids (the
  // vorticity pass's images). Friction acts on the velocities, so positions show it from the
  // second step on (4.6e-3 relative after two steps on the CPU, against free-slip). Rounding
  // only: 1e-12 after one step (OneStepMatchesSerialInDoublePrecision), 1e-10 after two leaves
  // that a step's growth.
  Parameters p = smallParameters(0.04);
  p.wallFriction = 0.7;
  const Scene scene = test::damBreakWithSolids();
  const Snapshot<double> a = afterTwoSteps(scene, p, Backend::Serial);
  const Snapshot<double> b = afterTwoSteps(scene, p, Backend::CUDA);
  const Snapshot<double> c = afterTwoSteps(scene, smallParameters(0.04), Backend::Serial);
  EXPECT_LE(test::maxRelativePositionError(b, a), 1e-10);
  EXPECT_GT(test::maxRelativePositionError(c, a), 1e-4); // friction changed the flow
}

namespace
{

// A solver option, CUDA against serial after two steps (one that acts through the velocities
// shows in the positions from the second step on): the dam break with `set` applied, rounding
// only (1e-10, as WallFrictionMatchesTheSerialBackend); and against the serial run without the
// option, which must differ, or the comparison says nothing about it.
template <class Set>
void expectOptionMatchesSerialAfterTwoSteps(Set&& set)
{
  const Scene scene = presetScene("dam_break");
  const Parameters plain = withSceneDomain(smallParameters(0.04), scene);
  Parameters p = plain;
  set(p);
  const Snapshot<double> a = afterTwoSteps(scene, p, Backend::Serial);
  const Snapshot<double> b = afterTwoSteps(scene, p, Backend::CUDA);
  const Snapshot<double> c = afterTwoSteps(scene, plain, Backend::Serial);
  EXPECT_LE(test::maxRelativePositionError(b, a), 1e-10);
  EXPECT_GT(test::maxRelativePositionError(c, a), 1e-9);
}

} // namespace

TEST(CudaStepper, XsphHyperViscosityMatchesTheSerialBackend)
{
  PBF_REQUIRE_GPU();
  expectOptionMatchesSerialAfterTwoSteps([](Parameters& p) { p.xsphHyperViscosity = 0.1; });
}

TEST(CudaStepper, ChebyshevAccelerationMatchesTheSerialBackend)
{
  PBF_REQUIRE_GPU();
  // The blend reads each particle's positions two projections back from the buffer the
  // correction is about to overwrite; the wrong buffer moves particles by a spacing's fraction.
  expectOptionMatchesSerialAfterTwoSteps([](Parameters& p) { p.chebyshevRho = 0.8; });
}

TEST(CudaStepper, SurfaceTensionMatchesTheSerialBackend)
{
  PBF_REQUIRE_GPU();
  // The colour gradients, their smoothed normals and the curvature's force in the GPU's passes
  // (the buffers exist only with surface tension). It acts on the velocities: 3.6e-5 relative
  // after two steps on the CPU against none at 2 N/m; rounding only between the backends (1e-10,
  // as WallFrictionMatchesTheSerialBackend).
  expectOptionMatchesSerialAfterTwoSteps([](Parameters& p) { p.surfaceTension = 2.0; });
}

TEST(CudaStepper, SurfaceTensionPerLiquidMatchesTheSerialBackendAndRepeatsItself)
{
  PBF_REQUIRE_GPU();
  // Water at 0.07 N/m and oil at 0.03 (each particle's force is its liquid's): rounding only
  // after two steps against the serial backend (1e-10, as above; 2.2e-6 relative against no
  // tension on the CPU), then 40 steps twice on the GPU in single precision, bit-identical.
  const Scene scene = test::twoLiquids();
  Parameters p = withSceneDomain(smallParameters(0.04), scene);
  p.surfaceTension = 0.07;
  p.liquids.at(1).surfaceTension = 0.03;
  const Snapshot<double> a = afterTwoSteps(scene, p, Backend::Serial);
  const Snapshot<double> b = afterTwoSteps(scene, p, Backend::CUDA);
  EXPECT_LE(test::maxRelativePositionError(b, a), 1e-10);
  EXPECT_EQ(a.liquid, b.liquid);
  Simulation first(scene, p, Backend::CUDA, Precision::Single);
  Simulation second(scene, p, Backend::CUDA, Precision::Single);
  first.advance(40);
  second.advance(40);
  Snapshot<double> c, d;
  first.stepper().read(c);
  second.stepper().read(d);
  test::expectBitIdentical(c, d);
  EXPECT_TRUE(first.stepper().statistics().finite);
}

TEST(CudaStepper, MovingSolidsMatchTheSerialBackend)
{
  PBF_REQUIRE_GPU();
  // As WallFrictionMatchesTheSerialBackend, with the sphere rolling into the column and the box
  // turning: the poses reach the device before each step of the captured graph. The motion moves
  // particles from the first step (2.5e-2 relative after two steps on the CPU, against still
  // solids); rounding only between the backends (1e-10, as there).
  Parameters p = smallParameters(0.04);
  p.wallFriction = 0.5;
  Scene scene = test::damBreakWithSolids();
  Scene still = scene;
  scene.solids[0].motion.keyframes = { { 0.0, { 0, 0, 0 }, Rotation{} },
    { 0.1, { -0.1, 0, 0 }, Rotation::fromDegrees({ 0, 0, 60 }) } };
  scene.solids[1].motion.keyframes = { { 0.0, { 0, 0, 0 }, Rotation{} },
    { 0.1, { 0, 0.02, 0 }, Rotation::fromDegrees({ 0, 10, 0 }) } };
  const Snapshot<double> a = afterTwoSteps(scene, p, Backend::Serial);
  const Snapshot<double> b = afterTwoSteps(scene, p, Backend::CUDA);
  const Snapshot<double> c = afterTwoSteps(still, p, Backend::Serial);
  EXPECT_LE(test::maxRelativePositionError(b, a), 1e-10);
  EXPECT_GT(test::maxRelativePositionError(c, a), 1e-3); // the motion changed the flow
}

TEST(CudaStepper, NoParticleEntersASolidOnTheGpu)
{
  PBF_REQUIRE_GPU();
  Parameters p;
  p.particleSpacing = 0.02;
  Simulation gpu(test::damBreakWithSolids(), p, Backend::CUDA, Precision::Single);
  double deepest = 0;
  for (int frame = 1; frame <= 48; ++frame) // 0.8 s: the surge passes the sphere
  {
    gpu.advanceTo(frame / 60.0);
    Snapshot<double> state;
    gpu.stepper().read(state);
    for (const Vec3d& x : state.position)
    {
      deepest = std::min(deepest, length(x - Vec3d{ 0.9, 0.12, 0.3 }) - 0.12);
    }
  }
  // The projection puts a particle on the field's zero: within its interpolation error of the
  // sphere (cell^2 / (4 r) = 0.2 mm at cells of 1 cm) and float rounding.
  EXPECT_GT(deepest, -0.002);
  EXPECT_TRUE(gpu.stepper().statistics().finite);
}

TEST(CudaStepper, TwoLiquidsMatchTheSerialBackendAndRepeatThemselves)
{
  PBF_REQUIRE_GPU();
  // As SolidsMatchTheSerialBackend: double precision, the fixed scheme, rounding only after one
  // step (1e-12 relative), now with each particle's correction weighted by its liquid; then 40
  // steps twice on the GPU, bit-identical, with each particle's liquid and the oil's density in
  // its own units.
  const Scene scene = test::twoLiquids();
  Simulation serial(scene, smallParameters(0.04), Backend::Serial, Precision::Double);
  Simulation gpu(scene, smallParameters(0.04), Backend::CUDA, Precision::Double);
  serial.advance(1);
  gpu.advance(1);
  Snapshot<double> a, b;
  serial.stepper().read(a);
  gpu.stepper().read(b);
  EXPECT_LE(test::maxRelativePositionError(b, a), 1e-12);
  EXPECT_LE(test::maxRelativePressureError(b, a), 1e-9);
  EXPECT_EQ(a.liquid, b.liquid);
  Simulation again(scene, smallParameters(0.04), Backend::CUDA, Precision::Double);
  gpu.advance(39);
  again.advance(40);
  Snapshot<double> c, d;
  gpu.stepper().read(c);
  again.stepper().read(d);
  test::expectBitIdentical(c, d);
  EXPECT_EQ(c.liquid, d.liquid);
  EXPECT_GT(c.id.size(), a.id.size()) << "the nozzle added no oil";
  double oil = 0, count = 0;
  for (std::size_t i = 0; i < c.id.size(); ++i)
  {
    oil += c.liquid.at(i) == 1 ? c.density[i] : 0.0;
    count += c.liquid.at(i) == 1 ? 1.0 : 0.0;
  }
  EXPECT_NEAR(oil / count, 800.0, 80.0);
}

TEST(CudaStepper, OutflowsRemoveWhatTheSerialBackendRemovesAndRepeatThemselves)
{
  PBF_REQUIRE_GPU();
  // The removal between steps (a CUB selection of the kept particles, gathered, the step captured
  // again at the new count): in double the same particles go on every step as on the serial
  // backend, and the positions differ by rounding only (1e-9 relative after 30 steps, as the
  // decomposed comparisons allow; a particle kept or removed wrongly fails the count or the id
  // match outright).
  const Scene scene = presetScene("dam_break");
  const Parameters p = withSceneDomain(smallParameters(0.04), scene);
  const ParticleBatch initial = fillScene(scene, p);
  const std::vector<Box> zones = test::outflowTestZones();
  auto serial = makeStepper(Backend::Serial, Precision::Double, p, initial);
  auto gpu = makeStepper(Backend::CUDA, Precision::Double, p, initial);
  std::size_t removed = 0;
  for (int s = 0; s < 30; ++s)
  {
    serial->step();
    gpu->step();
    const std::size_t a = serial->removeOutflow(zones);
    ASSERT_EQ(gpu->removeOutflow(zones), a) << "step " << s;
    removed += a;
  }
  EXPECT_GT(removed, 50u);
  Snapshot<double> a, b;
  serial->read(a);
  gpu->read(b);
  EXPECT_LE(test::maxRelativePositionError(b, a), 1e-9);
  // The channel (an inflow by rate, the +x face an outflow) for 3 s in single precision, twice:
  // the same particles, bit for bit, and the same count gone.
  Parameters q;
  q.particleSpacing = 0.04;
  Simulation first(presetScene("channel"), q, Backend::CUDA, Precision::Single);
  Simulation second(presetScene("channel"), q, Backend::CUDA, Precision::Single);
  first.advanceTo(3.0);
  second.advanceTo(3.0);
  EXPECT_GT(first.removedCount(), 100u);
  EXPECT_EQ(first.removedCount(), second.removedCount());
  Snapshot<float> c, d;
  first.stepper().read(c);
  second.stepper().read(d);
  test::expectBitIdentical(c, d);
}
