// Several solids on the CUDA sub-domain stepper's ranks (Cuda/DeviceSubdomainStepper.h), run on
// the host executor, ranks as threads (label "solver"): each solid's load comes from its own
// slot of every rank's sums. DeviceSubdomainHostTest.cpp checks one solid.
#include "Backends.h"
#include "DecomposedRuns.h"
#include "HostExecutor.h"

#include "Cuda/DeviceSubdomainStepper.h"
#include "SignedDistance.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <vector>

using namespace pbf;
using namespace pbf::test;

namespace
{

DecomposedFactory onHostWith(const std::vector<DistanceGrid>& solids)
{
  return [&solids](distributed::Communicator& communicator, const PresetFluid& setup) {
    auto stepper = std::unique_ptr<distributed::DecomposedStepper>(
      new cuda::DeviceSubdomainStepper<double, HostDevicePolicy>(communicator, setup.parameters,
        setup.fluid, std::make_unique<HostDevicePolicy>(false), 0.02, true));
    stepper->setObstacles(solids); // collective, as Simulation calls it on every rank
    return stepper;
  };
}

} // namespace

// A column of water 0.4 m wide collapsing onto a floor of two plates, the first under x < 0.3 m
// and the second beyond, so that the loads differ (after 10 steps 185 N and 8.7 N down) and the
// cuts of 2 and 3 ranks run through the first (its load summed over every rank, the second's
// over the last). On 1 to 3 ranks each solid's load after each of 10 steps is the serial
// backend's to the positions' rounding, 1e-9 of the largest force on that solid, as
// SolidsMatchTheSerialBackend bounds one solid's (ranks sum in another order, ~1e-16 a sum
// grown over the steps), where the other solid's load is off by a third of it or more.
TEST(DeviceSubdomainOnHost, TwoSolidsEachGetTheSerialBackendsLoadOnOneToThreeRanks)
{
  Scene scene;
  scene.domain = { { 0, 0, 0 }, { 1.0, 0.8, 0.4 } };
  scene.boxes.push_back({ { 0, 0.08, 0 }, { 0.4, 0.6, 0.4 }, { 0, 0, 0 } });
  const PresetFluid setup = sceneFluid(scene, 0.04);
  const std::vector<DistanceGrid> plates = {
    boxDistance({ { 0, 0, 0 }, { 0.3, 0.08, 0.4 } }, 0.02, 0.08),
    boxDistance({ { 0.3, 0, 0 }, { 1.0, 0.08, 0.4 } }, 0.02, 0.08) };
  const int steps = 10;
  auto serial = makeStepper(Backend::Serial, Precision::Double, setup.parameters, setup.fluid);
  serial->setObstacles(plates);
  std::vector<std::vector<SolidLoad>> reference;
  for (int s = 0; s < steps; ++s)
  {
    serial->step();
    // The two plates' loads alone: the tank's are not asked for (Parameters::tankLoads).
    const std::vector<SolidLoad>& loads = serial->lastStep().loads;
    ASSERT_EQ(loads.size(), 2u);
    reference.push_back({ loads[0], loads[1] });
  }
  double largest[2] = { 0, 0 };
  for (const std::vector<SolidLoad>& loads : reference)
  {
    for (std::size_t o = 0; o < 2; ++o)
    {
      largest[o] = std::max(largest[o], length(loads[o].force));
    }
  }
  const SolidLoad& last = reference.back()[0];
  std::printf("serial, last step: plate 0 %.4f N, plate 1 %.4f N along y\n", last.force.y,
    reference.back()[1].force.y);
  ASSERT_GT(largest[1], 0.0) << "the fluid never pressed the second plate";
  EXPECT_GT(length(reference.back()[0].force - reference.back()[1].force), 0.3 * largest[0])
    << "the plates' loads must differ for the test to tell their slots apart";
  for (int ranks : { 1, 2, 3 })
  {
    const DecomposedOutcome run = runDecomposed(ranks, setup, steps, onHostWith(plates));
    ASSERT_EQ(run.loads.size(), reference.size());
    for (std::size_t s = 0; s < reference.size(); ++s)
    {
      ASSERT_EQ(run.loads[s].size(), 2u) << ranks << " ranks";
      for (std::size_t o = 0; o < 2; ++o)
      {
        EXPECT_LE(length(run.loads[s][o].force - reference[s][o].force), 1e-9 * largest[o])
          << ranks << " ranks, step " << s << ", plate " << o;
        EXPECT_LE(length(run.loads[s][o].torque - reference[s][o].torque), 1e-9 * largest[o])
          << ranks << " ranks, step " << s << ", plate " << o;
      }
    }
    EXPECT_TRUE(run.loadsAgreeOnEveryRank) << ranks << " ranks";
    if (ranks > 1)
    {
      EXPECT_GT(run.ghosts, 0u) << ranks << " ranks";
    }
  }
}
