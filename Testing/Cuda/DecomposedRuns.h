// Runs a decomposed stepper on N ranks as threads (ThreadCluster) and gathers what the tests of
// the CUDA sub-domain stepper compare: the particles of every rank, and per step the statistics,
// the counts per rank and what each rank exchanged. Shared by the host-executor tests (label
// solver) and the GPU tests (label gpu).
#pragma once

#include "Backends.h"
#include "Distributed/SubdomainStepper.h"
#include "Distributed/ThreadCluster.h"
#include "Scene.h"
#include "Stepper.h"
#include "TestScenes.h"

#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <vector>

namespace pbf::test
{

struct DecomposedOutcome
{
  Snapshot<double> state;          // every rank's particles, rank after rank
  std::vector<Statistics> history; // after each step (with history)
  std::vector<std::vector<std::uint64_t>> counts; // particles per rank after each step
  std::uint64_t migrated = 0;      // particles received by any rank, over all steps
  std::uint64_t ghosts = 0;        // ghosts received by any rank, over all steps
  int cutsMoved = 0;               // steps that began with a new cut (rank 0's count)
  std::vector<std::vector<SolidLoad>> loads; // rank 0's lastStep().loads after each step
  bool loadsAgreeOnEveryRank = true; // every rank reported rank 0's loads, bit for bit
};

using DecomposedFactory = std::function<std::unique_ptr<distributed::DecomposedStepper>(
  distributed::Communicator&, const PresetFluid&)>;

// beforeStep(stepper, s), when given, runs on every rank before step s (a moving solid's pose).
inline DecomposedOutcome runDecomposed(int ranks, const PresetFluid& setup, int steps,
  const DecomposedFactory& make, bool history = false,
  const std::function<void(Stepper&, int)>& beforeStep = {})
{
  std::vector<Snapshot<double>> parts(static_cast<std::size_t>(ranks));
  std::vector<std::uint64_t> migrated(static_cast<std::size_t>(ranks), 0);
  std::vector<std::uint64_t> ghosts(static_cast<std::size_t>(ranks), 0);
  std::vector<std::vector<std::vector<SolidLoad>>> loads(static_cast<std::size_t>(ranks));
  DecomposedOutcome outcome;
  distributed::runThreadCluster(ranks, [&](distributed::Communicator& communicator) {
    const auto r = static_cast<std::size_t>(communicator.rank());
    std::unique_ptr<distributed::DecomposedStepper> stepper = make(communicator, setup);
    for (int s = 0; s < steps; ++s)
    {
      if (beforeStep)
      {
        beforeStep(*stepper, s);
      }
      stepper->step();
      migrated[r] += stepper->lastExchange().migrated;
      ghosts[r] += stepper->lastExchange().ghosts;
      loads[r].push_back(stepper->lastStep().loads);
      if (r == 0)
      {
        outcome.cutsMoved += stepper->lastExchange().cutMoved ? 1 : 0;
      }
      if (history)
      {
        const Statistics statistics = stepper->statistics();
        const std::vector<std::uint64_t> counts = stepper->particlesPerRank();
        if (r == 0)
        {
          outcome.history.push_back(statistics);
          outcome.counts.push_back(counts);
        }
      }
    }
    stepper->read(parts[r]);
  });
  outcome.state = joined(parts);
  outcome.loads = loads[0];
  for (std::size_t r = 0; r < parts.size(); ++r)
  {
    outcome.migrated += migrated[r];
    outcome.ghosts += ghosts[r];
    for (std::size_t s = 0; s < loads[r].size(); ++s)
    {
      for (std::size_t o = 0; o < loads[r][s].size(); ++o)
      {
        const SolidLoad& a = loads[r][s][o];
        const SolidLoad& b = loads[0][s].at(o);
        outcome.loadsAgreeOnEveryRank = outcome.loadsAgreeOnEveryRank &&
          a.force.x == b.force.x && a.force.y == b.force.y && a.force.z == b.force.z &&
          a.torque.x == b.torque.x && a.torque.y == b.torque.y && a.torque.z == b.torque.z;
      }
    }
  }
  return outcome;
}

// The serial backend's state after `steps` steps, in double.
inline Snapshot<double> serialState(const PresetFluid& setup, int steps, Precision precision)
{
  auto serial = makeStepper(Backend::Serial, precision, setup.parameters, setup.fluid);
  for (int s = 0; s < steps; ++s)
  {
    serial->step();
  }
  Snapshot<double> state;
  serial->read(state);
  return state;
}

// The outflow tests' zones in the dam break at 4 cm: a box through the column and a strip of
// the floor, which remove particles at once and then as the fluid runs into them.
inline std::vector<Box> outflowTestZones()
{
  return { Box{ { 0.1, 0.25, -0.1 }, { 0.3, 0.35, 0.7 } },
    Box{ { 0.3, -0.1, -0.1 }, { 0.5, 0.1, 0.7 } } };
}

// `steps` steps, the zones' particles removed before each step after the first (as Simulation
// removes them after each step), on the serial backend (into `removed`, the state returned) or on
// `ranks` ranks (each rank's own count of all into `counted`).
inline Snapshot<double> serialWithOutflows(
  const PresetFluid& setup, const std::vector<Box>& zones, int steps, std::size_t& removed)
{
  auto serial = makeStepper(Backend::Serial, Precision::Double, setup.parameters, setup.fluid);
  removed = 0;
  for (int s = 0; s < steps; ++s)
  {
    removed += s > 0 ? serial->removeOutflow(zones) : 0;
    serial->step();
  }
  Snapshot<double> state;
  serial->read(state);
  return state;
}

inline DecomposedOutcome decomposedWithOutflows(int ranks, const PresetFluid& setup,
  const std::vector<Box>& zones, int steps, const DecomposedFactory& make,
  std::vector<std::size_t>& counted)
{
  counted.assign(static_cast<std::size_t>(ranks), 0);
  return runDecomposed(ranks, setup, steps, make, false, [&](Stepper& stepper, int s) {
    if (s > 0)
    {
      const auto& d = dynamic_cast<const distributed::DecomposedStepper&>(stepper);
      counted[static_cast<std::size_t>(d.rank())] += stepper.removeOutflow(zones);
    }
  });
}

// `setup` on 1 to 3 ranks of `make` against the serial backend after `steps` steps, `solid` placed
// on both when given: every particle of its own liquid; one rank bit for bit and in the serial
// order when `oneRankBitForBit` (the host executor), every rank count within 1e-9 otherwise
// (rounding only across ranks and on the GPU, as the other decomposed comparisons, where a ghost
// of the wrong liquid or with a stale colour gradient moves particles by orders of magnitude
// more).
inline void expectRanksMatchSerial(const PresetFluid& setup, int steps,
  const DecomposedFactory& make, const DistanceGrid* solid, bool oneRankBitForBit)
{
  auto serial = makeStepper(Backend::Serial, Precision::Double, setup.parameters, setup.fluid);
  if (solid)
  {
    serial->setObstacles({ *solid });
  }
  for (int s = 0; s < steps; ++s)
  {
    serial->step();
  }
  Snapshot<double> reference;
  serial->read(reference);
  const DecomposedFactory placed = [&](distributed::Communicator& communicator,
                                     const PresetFluid& fluid) {
    auto stepper = make(communicator, fluid);
    if (solid)
    {
      stepper->setObstacles({ *solid });
    }
    return stepper;
  };
  for (int ranks : { 1, 2, 3 })
  {
    const DecomposedOutcome run = runDecomposed(ranks, setup, steps, placed);
    if (!reference.liquid.empty())
    {
      EXPECT_EQ(liquidsById(run.state), liquidsById(reference)) << ranks << " ranks";
    }
    if (ranks == 1 && oneRankBitForBit)
    {
      expectBitIdentical(run.state, reference);
      continue;
    }
    if (ranks > 1)
    {
      EXPECT_GT(run.ghosts, 0u) << ranks << " ranks";
    }
    const double error = maxRelativePositionError(run.state, reference);
    std::printf("%d ranks, %d steps: max relative position error %.3g\n", ranks, steps, error);
    EXPECT_LE(error, 1e-9) << ranks << " ranks";
  }
}

} // namespace pbf::test
