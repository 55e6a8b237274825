// Given particles that come in pieces, one a rank (Distributed/FluidPieces.h, the filter's input
// under a parallel pipeline): ranks that each hold only their piece run bit for bit as ranks that
// are each handed the whole batch, whatever the pieces (uneven, empty, cut across the slabs), and
// a bad point in one piece stops every rank with the message a single process gives.
#include "Distributed/FluidPieces.h"

#include "Distributed/ThreadCluster.h"
#include "Simulation.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

// The particles [from, to) of the batch, with the batch's arrays.
ParticleBatch slice(const ParticleBatch& batch, std::size_t from, std::size_t to)
{
  ParticleBatch piece;
  piece.position.assign(batch.position.begin() + from, batch.position.begin() + to);
  piece.velocity.assign(batch.velocity.begin() + from, batch.velocity.begin() + to);
  piece.id.assign(batch.id.begin() + from, batch.id.begin() + to);
  if (!batch.liquid.empty())
  {
    piece.liquid.assign(batch.liquid.begin() + from, batch.liquid.begin() + to);
  }
  return piece;
}

// Cuts the batch in rank order at the given fractions of its length (an empty piece where two
// fractions are equal).
std::vector<ParticleBatch> pieces(const ParticleBatch& batch, const std::vector<double>& cuts)
{
  std::vector<ParticleBatch> out;
  std::size_t from = 0;
  for (std::size_t r = 0; r <= cuts.size(); ++r)
  {
    const std::size_t to = r < cuts.size()
      ? static_cast<std::size_t>(cuts[r] * static_cast<double>(batch.position.size()))
      : batch.position.size();
    out.push_back(slice(batch, from, to));
    from = to;
  }
  return out;
}

// What each rank threw (empty: nothing) when constructing from its piece.
std::vector<std::string> failures(const Scene& scene, const Parameters& p,
  const std::vector<ParticleBatch>& given)
{
  std::vector<std::string> what(given.size());
  distributed::runThreadCluster(static_cast<int>(given.size()), [&](distributed::Communicator& c) {
    const auto r = static_cast<std::size_t>(c.rank());
    try
    {
      Simulation s(scene, p, Backend::Serial, Precision::Double, given[r], c, Simulation::InPieces{});
    }
    catch (const InvalidInput& e)
    {
      what[r] = e.what();
    }
  });
  return what;
}

} // namespace

TEST(FluidPieces, RanksGivenPiecesRunAsRanksHandedTheWholeBatch)
{
  for (const Scene& scene : { test::damBreakWithSolids(), test::sideBySideLiquids() })
  {
    Parameters p;
    p.particleSpacing = 0.05;
    const ParticleBatch whole = fillScene(scene, withSceneDomain(p, scene));
    // Pieces cut in the batch's order, not along the slabs: most particles change rank. The
    // three-rank cut leaves rank 1 an empty piece.
    for (const std::vector<double>& cuts : { std::vector<double>{ 0.3 }, { 0.6, 0.6 } })
    {
      const std::vector<ParticleBatch> given = pieces(whole, cuts);
      const int ranks = static_cast<int>(given.size());
      std::vector<Snapshot<double>> fromPieces(given.size()), handed(given.size());
      std::vector<std::size_t> removed(given.size()), removedHanded(given.size());
      distributed::runThreadCluster(ranks, [&](distributed::Communicator& communicator) {
        const auto r = static_cast<std::size_t>(communicator.rank());
        Simulation a(scene, p, Backend::Serial, Precision::Double, given[r], communicator,
          Simulation::InPieces{});
        Simulation b(scene, p, Backend::Serial, Precision::Double, whole, &communicator);
        removed[r] = a.seededInsideSolids();
        removedHanded[r] = b.seededInsideSolids();
        a.advance(8);
        b.advance(8);
        a.stepper().read(fromPieces[r]);
        b.stepper().read(handed[r]);
      });
      for (std::size_t r = 0; r < given.size(); ++r)
      {
        SCOPED_TRACE(scene.name + ", rank " + std::to_string(r) + " of " + std::to_string(ranks));
        EXPECT_GT(fromPieces[r].id.size(), 0u);
        test::expectBitIdentical(fromPieces[r], handed[r]);
        EXPECT_EQ(fromPieces[r].liquid, handed[r].liquid);
        EXPECT_EQ(removed[r], removedHanded[r]);
      }
    }
  }
}

// What one process given the pieces joined throws.
std::string singleFailure(const Scene& scene, const Parameters& p, const std::vector<ParticleBatch>& given)
{
  ParticleBatch whole;
  for (const ParticleBatch& piece : given)
  {
    whole.position.insert(whole.position.end(), piece.position.begin(), piece.position.end());
    whole.velocity.insert(whole.velocity.end(), piece.velocity.begin(), piece.velocity.end());
    whole.id.insert(whole.id.end(), piece.id.begin(), piece.id.end());
  }
  try
  {
    Simulation s(scene, p, Backend::Serial, Precision::Double, whole);
  }
  catch (const InvalidInput& e)
  {
    return e.what();
  }
  return "nothing thrown";
}

TEST(FluidPieces, ABadPointInOnePieceStopsEveryRankWithTheWholesMessage)
{
  const Scene scene = test::damBreakWithSolids();
  Parameters p;
  p.particleSpacing = 0.05;
  const Parameters run = withSceneDomain(p, scene);
  const std::vector<ParticleBatch> given = pieces(fillScene(scene, run), { 0.4, 0.7 });
  auto expectEveryRankSays = [&](const std::vector<ParticleBatch>& bad, const std::string& what) {
    const std::string single = singleFailure(scene, p, bad);
    EXPECT_NE(single.find(what), std::string::npos) << single;
    for (const std::string& theirs : failures(scene, p, bad))
    {
      EXPECT_NE(theirs.find(single), std::string::npos) << theirs << "\n" << single;
    }
  };

  // On a mirror wall, in rank 1's piece: checkPacking over the pieces names the point as the
  // whole numbers it (past the particles the solids removed from rank 0's piece).
  std::vector<ParticleBatch> onWall = given;
  onWall[1].position[0].x = run.domain.min.x;
  expectEveryRankSays(onWall, "of a wall of the domain");

  // Not finite: the rank that receives it names it by its id in the whole.
  std::vector<ParticleBatch> notFinite = given;
  notFinite[1].position[0].y = std::numeric_limits<double>::quiet_NaN();
  expectEveryRankSays(notFinite, "position of particle ");

  // Packed twice closer, 8 points a cell: no piece sees the whole, and the counts added over the
  // pieces refuse it as one process does. A cell that two pieces share counts in both (these
  // pieces, cut in the lattice's order, share many: 175 cells against the whole's 144), so the
  // ratio may read lower than one process's, never higher.
  std::vector<ParticleBatch> packed = given;
  std::size_t points = 0;
  for (ParticleBatch& piece : packed)
  {
    points += piece.position.size();
    for (Vec3d& x : piece.position)
    {
      x = run.domain.min + (x - run.domain.min) * 0.5 + Vec3d{ 0.01, 0.01, 0.01 };
    }
  }
  EXPECT_NE(singleFailure(scene, p, packed).find("times closer than the spacing"), std::string::npos);
  for (const std::string& theirs : failures(scene, p, packed))
  {
    EXPECT_NE(theirs.find("initial particles: " + std::to_string(points) + " points in "),
      std::string::npos) << theirs;
    EXPECT_NE(theirs.find("times closer than the spacing"), std::string::npos) << theirs;
  }
}

// Messages of a few particles (MPI's int counts bound a message at 2 GiB, 37M particles): the
// pieces go in rounds, and each rank still receives its whole slab in the fluid's order.
TEST(FluidPieces, RoundsOfSmallMessagesDeliverEachSlabInTheFluidsOrder)
{
  const Scene scene = test::sideBySideLiquids();
  Parameters p;
  p.particleSpacing = 0.05;
  const ParticleBatch whole = fillScene(scene, withSceneDomain(p, scene));
  const std::vector<ParticleBatch> given = pieces(whole, { 0.2, 0.9 });
  using Visited = std::vector<std::pair<std::int64_t, std::uint8_t>>;
  auto receive = [&](std::size_t perMessage) {
    std::vector<Visited> got(given.size());
    distributed::runThreadCluster(3, [&](distributed::Communicator& c) {
      const auto r = static_cast<std::size_t>(c.rank());
      const distributed::FluidPieces fluid(given[r], c, perMessage);
      EXPECT_TRUE(fluid.hasLiquids());
      // Owners across the pieces: stripes of x.
      fluid.forEachOwned([](const Vec3d& x) { return static_cast<int>(x.x * 20.0) % 3; }, c.rank(),
        [&](const Vec3d& x, const Vec3d&, std::int64_t id, std::uint8_t liquid) {
          EXPECT_EQ(static_cast<int>(x.x * 20.0) % 3, c.rank());
          got[r].emplace_back(id, liquid);
        });
    });
    return got;
  };
  const std::vector<Visited> once = receive(std::size_t(1) << 24);
  const std::vector<Visited> rounds = receive(7);
  std::size_t total = 0;
  for (std::size_t r = 0; r < given.size(); ++r)
  {
    EXPECT_EQ(rounds[r], once[r]) << "rank " << r;
    EXPECT_TRUE(std::is_sorted(once[r].begin(), once[r].end())) << "rank " << r; // the fluid's order
    total += once[r].size();
  }
  EXPECT_EQ(total, whole.position.size());
}
