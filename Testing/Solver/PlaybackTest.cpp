// The playback core (Solver/Run/Playback.h) that the VTK algorithm drives: any frame in any order
// is bit-identical to a straight run, checkpoints are thinned evenly within the budget, one row
// per frame, a stop leaves a whole step, a device fault keeps what the CPU can go on from, ranks
// stop together; and the backend choice.
#include "BackendChoice.h"
#include "Distributed/ThreadCluster.h"
#include "Playback.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <stdexcept>

using namespace pbf;

namespace
{

// The dam break at 8 cm (245 particles): a dozen frames of 1/60 s take a fraction of a second.
PlaybackKey damBreakKey(Backend backend = Backend::Serial)
{
  PlaybackKey key;
  key.scene = "preset dam_break";
  key.parameters.particleSpacing = 0.08;
  key.frameInterval = 1.0 / 60.0;
  key.backend = backend;
  key.precision = Precision::Double;
  return key;
}

// What the VTK algorithm's builder does, on the CPU whatever the key says (the device-fault
// test plays a CUDA run without a GPU).
Playback::Build builder(const PlaybackKey& key)
{
  return [key]() {
    return std::make_unique<Simulation>(presetScene("dam_break"), key.parameters,
      Backend::Serial, key.precision);
  };
}

Snapshot<double> stateOf(const Playback& playback)
{
  Snapshot<double> snapshot;
  playback.live()->stepper().read(snapshot);
  return snapshot;
}

bool sameBits(const Snapshot<double>& a, const Snapshot<double>& b)
{
  const std::size_t n = a.id.size();
  return a.id == b.id &&
    std::memcmp(a.position.data(), b.position.data(), n * sizeof(a.position[0])) == 0 &&
    std::memcmp(a.velocity.data(), b.velocity.data(), n * sizeof(a.velocity[0])) == 0;
}

// The state at `frame` of a run straight to it.
Snapshot<double> straightTo(int frame)
{
  Playback playback;
  playback.adopt(damBreakKey());
  playback.configureCheckpoints(0, 0);
  playback.reach(frame, builder(damBreakKey()), nullptr);
  return stateOf(playback);
}

} // namespace

TEST(Playback, AnyOrderGivesTheFramesOfAStraightRun)
{
  const Snapshot<double> frame5 = straightTo(5), frame12 = straightTo(12);
  Playback playback;
  playback.adopt(damBreakKey());
  playback.configureCheckpoints(4, std::size_t(1) << 30);
  const auto build = builder(damBreakKey());
  // Forwards past it, back (from the checkpoint of frame 4), forwards (live), and again.
  EXPECT_EQ(playback.reach(9, build, nullptr).resumedFrom, "initial");
  FrameReached back = playback.reach(5, build, nullptr);
  EXPECT_EQ(back.resumedFrom, "checkpoint");
  EXPECT_TRUE(sameBits(stateOf(playback), frame5));
  EXPECT_EQ(playback.reach(12, build, nullptr).resumedFrom, "checkpoint"); // 8 is nearer than 5
  EXPECT_TRUE(sameBits(stateOf(playback), frame12));
  EXPECT_EQ(playback.reach(12, build, nullptr).steps, 0u);
  playback.reach(5, build, nullptr);
  EXPECT_TRUE(sameBits(stateOf(playback), frame5));
}

TEST(Playback, CheckpointsAreThinnedEvenlyWithinTheBudgetKeepingTheFirst)
{
  Playback probe;
  probe.adopt(damBreakKey());
  probe.configureCheckpoints(1, std::size_t(1) << 30);
  probe.reach(0, builder(damBreakKey()), nullptr);
  const std::size_t one = probe.checkpointBytes(); // the dam break's count stays: all equal

  // 3.5 checkpoints fit: frames 0-3 force stride 2 ({0, 2}), 4 and 6 stride 4 ({0, 4}), then 8.
  Playback playback;
  playback.adopt(damBreakKey());
  playback.configureCheckpoints(1, one * 7 / 2);
  playback.reach(8, builder(damBreakKey()), nullptr);
  EXPECT_EQ(playback.checkpointFrames(), (std::vector<int>{ 0, 4, 8 }));
  EXPECT_LE(playback.checkpointBytes(), one * 7 / 2);
  // A smaller budget thins what is held at once; 0 frames keeps none.
  playback.configureCheckpoints(1, one * 2);
  EXPECT_EQ(playback.checkpointFrames(), (std::vector<int>{ 0, 8 }));
  playback.configureCheckpoints(0, one * 2);
  EXPECT_TRUE(playback.checkpointFrames().empty());
  EXPECT_EQ(playback.checkpointBytes(), 0u);
}

TEST(Playback, EveryFrameGetsOneRowAndKeepsItsFirst)
{
  Playback playback;
  playback.adopt(damBreakKey());
  playback.configureCheckpoints(2, std::size_t(1) << 30);
  const auto build = builder(damBreakKey());
  playback.reach(6, build, nullptr);
  ASSERT_EQ(playback.rows().size(), 7u);
  const FrameRow third = playback.rows().at(3);
  EXPECT_TRUE(std::isnan(playback.rows().at(0).substeps)); // frame 0 took no step
  EXPECT_GE(third.substeps, 1.0);
  EXPECT_NEAR(third.time, 3.0 / 60.0, 1e-15); // frames land exactly on k * interval
  EXPECT_EQ(third.particles, static_cast<std::int64_t>(playback.live()->stepper().size()));
  const auto version = playback.rowsVersion();
  playback.reach(3, build, nullptr); // again, from the checkpoint of frame 2
  EXPECT_EQ(playback.rowsVersion(), version);
  EXPECT_EQ(playback.rows().at(3).millisecondsPerStep, third.millisecondsPerStep);
}

TEST(Playback, AStopLeavesAWholeStepThatTheNextRequestGoesOnFrom)
{
  const Snapshot<double> frame6 = straightTo(6);
  Playback playback;
  playback.adopt(damBreakKey());
  playback.configureCheckpoints(0, 0);
  int calls = 0;
  const FrameReached stopped =
    playback.reach(6, builder(damBreakKey()), [&](double fraction) {
      EXPECT_GT(fraction, 0.0);
      EXPECT_LE(fraction, 1.0);
      return ++calls == 7;
    });
  EXPECT_TRUE(stopped.aborted);
  EXPECT_EQ(stopped.steps, 7u);
  EXPECT_EQ(playback.live()->stepCount(), 7u);
  const FrameReached resumed = playback.reach(6, builder(damBreakKey()), nullptr);
  EXPECT_FALSE(resumed.aborted);
  EXPECT_EQ(resumed.resumedFrom, "live");
  EXPECT_EQ(resumed.resumedFromStep, 7u);
  EXPECT_TRUE(sameBits(stateOf(playback), frame6));
}

TEST(Playback, AnotherKeyDropsEverythingAndTheSameKeepsIt)
{
  Playback playback;
  playback.configureCheckpoints(2, std::size_t(1) << 30);
  EXPECT_TRUE(playback.adopt(damBreakKey()));
  playback.reach(4, builder(damBreakKey()), nullptr);
  EXPECT_FALSE(playback.adopt(damBreakKey()));
  EXPECT_EQ(playback.checkpointFrames(), (std::vector<int>{ 0, 2, 4 }));
  PlaybackKey other = damBreakKey();
  other.parameters.xsphViscosity *= 2;
  EXPECT_TRUE(playback.adopt(other));
  EXPECT_TRUE(playback.checkpointFrames().empty());
  EXPECT_TRUE(playback.rows().empty());
  EXPECT_EQ(playback.live(), nullptr);
  PlaybackKey hyper = other;
  hyper.parameters.xsphHyperViscosity += 0.05;
  EXPECT_TRUE(playback.adopt(hyper));
}

TEST(Playback, ADeviceFaultKeepsTheCheckpointsAndRowsForTheCpu)
{
  // A CUDA run (played here on the CPU by the builder) whose GPU fails on the way to frame 7.
  Playback playback;
  playback.adopt(damBreakKey(Backend::CUDA));
  playback.configureCheckpoints(2, std::size_t(1) << 30);
  playback.reach(5, builder(damBreakKey()), nullptr);
  EXPECT_EQ(playback.afterDeviceFault(7, /*fallBack=*/false), "frame 4 (a checkpoint)");
  EXPECT_EQ(playback.live(), nullptr);
  EXPECT_EQ(playback.key().backend, Backend::CUDA); // Backend CUDA: the request fails

  // The user moves the run to the CPU: the same run, so nothing is lost.
  playback.adopt(damBreakKey(Backend::OpenMP));
  EXPECT_EQ(playback.key().backend, Backend::OpenMP);
  EXPECT_EQ(playback.checkpointFrames(), (std::vector<int>{ 0, 2, 4 }));
  EXPECT_EQ(playback.rows().size(), 6u);
  EXPECT_EQ(playback.reach(7, builder(damBreakKey()), nullptr).resumedFrom, "checkpoint");

  // Backend Auto falls back at once; before any checkpoint, from the initial state.
  Playback early;
  early.adopt(damBreakKey(Backend::CUDA));
  early.configureCheckpoints(0, 0);
  EXPECT_EQ(early.afterDeviceFault(3, /*fallBack=*/true), "the initial state");
  EXPECT_EQ(early.key().backend, Backend::OpenMP);
}

TEST(Playback, RanksStopTogetherWhenOneIsAsked)
{
  // Two ranks as threads, each with its slab's Simulation; only rank 1 is asked to stop, after
  // its third step: both stop there, at the same step, and both go on from it to the same frame.
  const test::PresetFluid setup = test::presetFluid("dam_break", 0.08);
  std::atomic<int> stoppedAt[2] = { { -1 }, { -1 } };
  std::atomic<int> finalStep[2] = { { -1 }, { -1 } };
  distributed::runThreadCluster(2, [&](distributed::Communicator& ranks) {
    PlaybackKey key = damBreakKey(Backend::OpenMP);
    key.ranks = 2;
    Playback playback(&ranks);
    playback.adopt(key);
    playback.configureCheckpoints(2, std::size_t(1) << 30);
    auto build = [&]() {
      return std::make_unique<Simulation>(presetScene("dam_break"), key.parameters,
        Backend::OpenMP, key.precision, &ranks);
    };
    int steps = 0;
    const FrameReached stopped = playback.reach(
      5, build, [&](double) { return ++steps == 3 && ranks.rank() == 1; });
    stoppedAt[ranks.rank()] = stopped.aborted ? static_cast<int>(playback.live()->stepCount()) : 0;
    playback.reach(5, build, nullptr);
    finalStep[ranks.rank()] = static_cast<int>(playback.live()->stepCount());
    // Rows are reduced over the ranks: both hold the same.
    EXPECT_EQ(playback.rows().size(), 6u);
  });
  EXPECT_EQ(stoppedAt[0].load(), 3);
  EXPECT_EQ(stoppedAt[1].load(), 3);
  EXPECT_EQ(finalStep[0].load(), finalStep[1].load());
}

TEST(BackendChoice, AutoTakesTheGpuOrSaysWhyNot)
{
  EXPECT_EQ(chooseBackend(BackendRequest::Auto, true, "").backend, Backend::CUDA);
  const BackendChoice cpu = chooseBackend(BackendRequest::Auto, false, "no device");
  EXPECT_EQ(cpu.backend, Backend::OpenMP);
  EXPECT_EQ(cpu.noCuda, "no device");
  EXPECT_EQ(chooseBackend(BackendRequest::Serial, true, "").backend, Backend::Serial);
  EXPECT_EQ(chooseBackend(BackendRequest::OpenMP, true, "").backend, Backend::OpenMP);
  try
  {
    chooseBackend(BackendRequest::CUDA, false, "cudaErrorNoDevice");
    ADD_FAILURE() << "CUDA without a GPU was accepted";
  }
  catch (const std::runtime_error& error)
  {
    EXPECT_NE(std::string(error.what()).find("cudaErrorNoDevice"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("Auto or CPU (OpenMP)"), std::string::npos);
  }
}

TEST(BackendChoice, RanksTakeTheGpuOnlyWhenEveryRankHasOne)
{
  Backend chosen[3];
  std::string why[3];
  distributed::runThreadCluster(3, [&](distributed::Communicator& ranks) {
    const bool mine = ranks.rank() != 2; // rank 2's host has no GPU
    const BackendChoice choice =
      chooseBackend(BackendRequest::Auto, mine, mine ? "" : "no device", &ranks);
    chosen[ranks.rank()] = choice.backend;
    why[ranks.rank()] = choice.noCuda;
  });
  for (int r = 0; r < 3; ++r)
  {
    EXPECT_EQ(chosen[r], Backend::OpenMP) << "rank " << r;
  }
  EXPECT_EQ(why[0], "another rank of the 3 has no usable GPU");
  EXPECT_EQ(why[2], "rank 2: no device");
}
