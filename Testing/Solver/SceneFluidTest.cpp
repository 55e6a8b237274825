// A scene's fluid generated in parts (Scene/SceneFluid.h): the whole of it is fillScene less the
// solids' share, bit for bit and with the same ids; slabs of it partition it; and a decomposed run
// whose ranks each generate only their slab is bit for bit the run whose ranks are each handed
// the whole batch.
#include "SceneFluid.h"

#include "Distributed/ThreadCluster.h"
#include "Simulation.h"
#include "Solids.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <vector>

using namespace pbf;

namespace
{

Parameters at(double spacing, const Scene& scene)
{
  Parameters p;
  p.particleSpacing = spacing;
  return withSceneDomain(p, scene);
}

void expectSameBatch(const ParticleBatch& a, const ParticleBatch& b)
{
  ASSERT_EQ(a.position.size(), b.position.size());
  const std::size_t n = a.position.size();
  EXPECT_EQ(a.id, b.id);
  EXPECT_EQ(a.liquid, b.liquid);
  EXPECT_EQ(std::memcmp(a.position.data(), b.position.data(), n * sizeof(Vec3d)), 0);
  EXPECT_EQ(std::memcmp(a.velocity.data(), b.velocity.data(), n * sizeof(Vec3d)), 0);
}

} // namespace

TEST(SceneFluid, TheWholeIsFillSceneLessTheSolidsBitForBit)
{
  for (const Scene& scene : { test::damBreakWithSolids(), test::twoLiquids() })
  {
    const Parameters p = at(0.04, scene);
    const std::vector<DistanceGrid> solids = solidFields(scene.solids, p);
    std::size_t removed = 0;
    const ParticleBatch whole = outsideSolids(fillScene(scene, p), solids, {}, removed);
    const SceneFluid fluid(scene, p, solids);
    EXPECT_EQ(fluid.size(), whole.position.size());
    EXPECT_EQ(fluid.insideSolids(), removed);
    expectSameBatch(fluid.where([](const Vec3d&) { return true; }), whole);
    std::size_t visited = 0;
    fluid.forEachPosition([&](const Vec3d& x) {
      EXPECT_EQ(std::memcmp(&x, &whole.position[visited], sizeof x), 0) << visited;
      ++visited;
    });
    EXPECT_EQ(visited, whole.position.size());
  }
  // The solids take a share of the dam break's column, so the ids are renumbered past it.
  const Scene scene = test::damBreakWithSolids();
  const Parameters p = at(0.04, scene);
  EXPECT_GT(SceneFluid(scene, p, solidFields(scene.solids, p)).insideSolids(), 0u);
}

TEST(SceneFluid, SlabsPartitionTheFluidAndKeepTheWholesIds)
{
  const Scene scene = test::damBreakWithSolids();
  const Parameters p = at(0.04, scene);
  const std::vector<DistanceGrid> solids = solidFields(scene.solids, p);
  const SceneFluid fluid(scene, p, solids);
  const ParticleBatch whole = fluid.where([](const Vec3d&) { return true; });
  ParticleBatch joined;
  for (const auto& [lo, hi] : { std::pair{ -1.0, 0.13 }, std::pair{ 0.13, 0.29 }, std::pair{ 0.29, 9.0 } })
  {
    const ParticleBatch part = fluid.where([lo = lo, hi = hi](const Vec3d& x) { return x.x >= lo && x.x < hi; });
    EXPECT_GT(part.position.size(), 0u);
    joined.position.insert(joined.position.end(), part.position.begin(), part.position.end());
    joined.velocity.insert(joined.velocity.end(), part.velocity.begin(), part.velocity.end());
    joined.id.insert(joined.id.end(), part.id.begin(), part.id.end());
  }
  // Back in the whole's order: by id.
  std::vector<std::size_t> order(joined.id.size());
  for (std::size_t i = 0; i < order.size(); ++i)
  {
    order[i] = i;
  }
  std::sort(order.begin(), order.end(),
    [&](std::size_t a, std::size_t b) { return joined.id[a] < joined.id[b]; });
  ParticleBatch sorted;
  for (std::size_t i : order)
  {
    sorted.position.push_back(joined.position[i]);
    sorted.velocity.push_back(joined.velocity[i]);
    sorted.id.push_back(joined.id[i]);
  }
  expectSameBatch(sorted, whole);
}

// Each rank generates only its slab, or each is handed the whole batch: the same particles on
// the same ranks in the same order, so the runs are the same to the bit, solids and liquids
// included.
TEST(SceneFluid, RanksThatGenerateTheirSlabRunAsRanksHandedTheWholeBatch)
{
  for (const Scene& scene : { test::damBreakWithSolids(), test::sideBySideLiquids() })
  {
    Parameters p;
    p.particleSpacing = 0.05;
    const ParticleBatch whole = fillScene(scene, withSceneDomain(p, scene));
    for (int ranks : { 2, 3 })
    {
      std::vector<Snapshot<double>> generated(static_cast<std::size_t>(ranks));
      std::vector<Snapshot<double>> handed(static_cast<std::size_t>(ranks));
      distributed::runThreadCluster(ranks, [&](distributed::Communicator& communicator) {
        const auto r = static_cast<std::size_t>(communicator.rank());
        Simulation a(scene, p, Backend::Serial, Precision::Double, &communicator);
        Simulation b(scene, p, Backend::Serial, Precision::Double, whole, &communicator);
        a.advance(8);
        b.advance(8);
        a.stepper().read(generated[r]);
        b.stepper().read(handed[r]);
      });
      for (int r = 0; r < ranks; ++r)
      {
        SCOPED_TRACE(scene.name + ", rank " + std::to_string(r) + " of " + std::to_string(ranks));
        EXPECT_GT(generated[static_cast<std::size_t>(r)].id.size(), 0u);
        test::expectBitIdentical(generated[static_cast<std::size_t>(r)], handed[static_cast<std::size_t>(r)]);
        EXPECT_EQ(generated[static_cast<std::size_t>(r)].liquid, handed[static_cast<std::size_t>(r)].liquid);
      }
    }
  }
}
