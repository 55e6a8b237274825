// Open boundaries: particles leave through the scene's outflows, inflows release their rate, ids
// are never given twice, and every CPU backend, a decomposed run and a checkpoint agree.
#include "Distributed/ThreadCluster.h"
#include "Outflow.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <string>

using namespace pbf;

namespace
{

// The shipped channel at twice the default spacing: 13 sites a layer, a few hundred particles.
Parameters coarse()
{
  Parameters p;
  p.particleSpacing = 0.04;
  return p;
}

template <class Real>
Snapshot<Real> stateOf(const Simulation& s)
{
  Snapshot<Real> out;
  s.stepper().read(out);
  return out;
}

std::string errorOf(const std::string& json, const Parameters& p = coarse())
{
  try
  {
    Simulation s(parseScene(json), p, Backend::Serial, Precision::Single);
  }
  catch (const InvalidInput& error)
  {
    return error.what();
  }
  return "";
}

const char* const kTank = R"("domain": {"min": [0,0,0], "max": [1,0.5,0.5]},
  "fluid": [{"type": "box", "min": [0,0,0], "max": [0.3,0.3,0.5]}])";

std::string tankWith(const std::string& more)
{
  return std::string("{") + kTank + ", " + more + "}";
}

} // namespace

TEST(Outflow, ParticlesLeaveThroughTheOutflowAndNoIdIsGivenTwice)
{
  Simulation channel(presetScene("channel"), coarse(), Backend::Serial, Precision::Single);
  ASSERT_EQ(channel.outflowZones().size(), 1u);
  const OutflowZones<float> zones = OutflowZones<float>::make(channel.outflowZones());
  std::set<std::int64_t> seen; // every id ever output
  for (int frame = 1; frame <= 16; ++frame)
  {
    channel.advanceTo(0.25 * frame);
    const Snapshot<float> s = stateOf<float>(channel);
    const std::set<std::int64_t> ids(s.id.begin(), s.id.end());
    ASSERT_EQ(ids.size(), s.id.size()) << "an id twice at frame " << frame;
    // Every id below idCount, and the count is what came in less what left.
    EXPECT_LT(*ids.rbegin(), channel.idCount());
    EXPECT_EQ(static_cast<std::uint64_t>(s.id.size()) + channel.removedCount(),
      static_cast<std::uint64_t>(channel.idCount()));
    for (const Vec3<float>& x : s.position)
    {
      ASSERT_FALSE(zones.contains(x)) << "a particle stayed in the outflow at frame " << frame;
    }
    seen.insert(ids.begin(), ids.end());
  }
  // The stream reached the end within 4 s, and what left never came back: every id output is
  // one of idCount, and those gone are not among the particles now.
  EXPECT_GT(channel.removedCount(), 100u);
  EXPECT_EQ(seen.size(), static_cast<std::size_t>(channel.idCount()));
}

TEST(Outflow, AnInflowReleasesItsRateAsWholeLayers)
{
  // 0.01 m^3/s through 13 sites of 0.04 m: 0.4808 m/s, a layer every 83 ms. After 2 s the
  // released volume is the rate's to within the one layer released at t = 0.
  Simulation channel(presetScene("channel"), coarse(), Backend::Serial, Precision::Single);
  const Emitter& inflow = channel.scene().emitters.at(0);
  const double s = 0.04;
  EXPECT_EQ(emitterSites(inflow, s), 13);
  EXPECT_NEAR(inflow.speed, 0.01 / (13 * s * s), 1e-12); // the same formula, evaluated twice
  channel.advanceTo(2.0);
  const double released = static_cast<double>(channel.idCount()) * s * s * s;
  EXPECT_NEAR(released, 0.01 * 2.0, 13 * s * s * s) << channel.idCount() << " particles";
}

TEST(Outflow, OpenMPIsBitIdenticalToSerial)
{
  Simulation serial(presetScene("channel"), coarse(), Backend::Serial, Precision::Single);
  Simulation openmp(presetScene("channel"), coarse(), Backend::OpenMP, Precision::Single);
  serial.advanceTo(3.0);
  openmp.advanceTo(3.0);
  EXPECT_GT(serial.removedCount(), 0u);
  EXPECT_EQ(serial.removedCount(), openmp.removedCount());
  test::expectBitIdentical(stateOf<float>(serial), stateOf<float>(openmp));
}

TEST(Outflow, ACheckpointResumesBitForBitWithTheRemovedCount)
{
  // Both land on the frames at 3 and 3.5 s: a frame's pressure is the mean over its steps.
  Simulation straight(presetScene("channel"), coarse(), Backend::Serial, Precision::Single);
  straight.advanceTo(3.0);
  straight.advanceTo(3.5);
  Simulation resumed(presetScene("channel"), coarse(), Backend::Serial, Precision::Single);
  resumed.advanceTo(3.0);
  const SimulationCheckpoint at3 = resumed.checkpoint();
  resumed.advanceTo(3.25); // wander on, then come back
  resumed.restore(at3);
  EXPECT_EQ(resumed.removedCount(), at3.removed);
  resumed.advanceTo(3.5);
  EXPECT_GT(straight.removedCount(), at3.removed); // particles left after the checkpoint too
  EXPECT_EQ(straight.removedCount(), resumed.removedCount());
  test::expectBitIdentical(stateOf<float>(straight), stateOf<float>(resumed));
}

TEST(Outflow, OneRankIsBitIdenticalToSerialAndTwoRanksRemoveAlike)
{
  const Scene scene = presetScene("channel");
  Parameters p = coarse();
  Simulation serial(scene, p, Backend::Serial, Precision::Double);
  serial.advanceTo(3.0);
  const Snapshot<double> reference = stateOf<double>(serial);
  for (int ranks : { 1, 2 })
  {
    std::vector<std::uint64_t> removed(static_cast<std::size_t>(ranks));
    std::vector<std::size_t> held(static_cast<std::size_t>(ranks));
    std::vector<Snapshot<double>> parts(static_cast<std::size_t>(ranks));
    distributed::runThreadCluster(ranks, [&](distributed::Communicator& c) {
      Simulation part(scene, p, Backend::Serial, Precision::Double, &c);
      part.advanceTo(3.0);
      const auto r = static_cast<std::size_t>(c.rank());
      removed[r] = part.removedCount();
      part.stepper().read(parts[r]);
    });
    for (int r = 1; r < ranks; ++r)
    {
      EXPECT_EQ(removed[static_cast<std::size_t>(r)], removed[0]) << "the count is every rank's";
    }
    std::size_t total = 0;
    for (const Snapshot<double>& part : parts)
    {
      total += part.id.size();
    }
    if (ranks == 1)
    {
      EXPECT_EQ(removed[0], serial.removedCount());
      test::expectBitIdentical(parts[0], reference);
      continue;
    }
    // Two ranks sum neighbours in another order, so after 3 s of a free stream the particles
    // differ; the stream does not: the count within 2 % (the channel's own unsteadiness).
    EXPECT_GT(removed[0], 0u);
    EXPECT_NEAR(static_cast<double>(total), static_cast<double>(reference.id.size()),
      0.02 * static_cast<double>(reference.id.size()));
  }
}

TEST(Outflow, BadOutflowsAndInflowsAreNamed)
{
  const auto expectError = [](const std::string& json, const std::string& part) {
    const std::string error = errorOf(json);
    EXPECT_NE(error.find(part), std::string::npos) << "error: " << error << "\nexpected: " << part;
  };
  expectError(tankWith(R"("outflows": [{"face": "x"}])"),
    R"(.outflows[0].face = "x": must be one of)");
  expectError(tankWith(R"("outflows": [{"face": "+x", "depth": 1.5}])"),
    ".outflows[0].depth = 1.5: the slab would cover the whole domain");
  expectError(tankWith(R"("outflows": [{"face": "+x", "min": [0,0,0], "max": [1,1,1]}])"),
    "give a face or a box (min and max), not both");
  expectError(tankWith(R"("outflows": [{"min": [2,0,0], "max": [3,1,1]}])"),
    "the box lies outside the domain");
  expectError(tankWith(R"("outflows": [{"min": [-1,-1,-1], "max": [2,2,2]}])"),
    "the box covers the whole domain");
  expectError(tankWith(R"("outflows": [{"min": [0,0,0], "max": [0.5,0.5,0.5]}])"),
    "scene .outflows[0] (box) covers all");
  expectError(tankWith(R"("outflows": [{"face": "-x", "depth": 0.2}, {"min": [0.15,0,0], "max": [0.5,0.5,0.5]}])"),
    "scene .outflows covers all");
  expectError(tankWith(R"("outflows": [{"face": "+x"}], "emitters": [{"center": [0.95,0.2,0.2],
    "direction": [1,0,0], "radius": 0.04, "rate": 0.001, "stop": 1}])"),
    "scene .outflows[0] (face +x) holds the nozzle of .emitters[0]");
  expectError(tankWith(R"("emitters": [{"center": [0.5,0.2,0.2], "direction": [1,0,0],
    "radius": 0.04, "speed": 1, "rate": 0.001, "stop": 1}])"),
    ".emitters[0].rate = 0.001: give speed or rate, not both");
  expectError(tankWith(R"("emitters": [{"center": [0.5,0.2,0.2], "direction": [1,0,0],
    "radius": 0.04, "rate": -1, "stop": 1}])"),
    ".emitters[0].rate = -1: must be > 0");
  expectError(tankWith(R"("emitters": [{"center": [0.5,0.2,0.2], "direction": [1,0,0],
    "radius": 0.04, "stop": 1}])"),
    ".emitters[0].speed is missing (or give rate");
  // A face and a box that leave some of the fluid are fine.
  EXPECT_EQ(errorOf(tankWith(R"("outflows": [{"face": "+x"}, {"min": [0,0,0], "max": [0.1,0.1,0.1]}])")), "");
}

namespace
{

// Points on the faces, edges and corners of zone 0 (its own rounded bounds, so exactly on them),
// each in turn: every one lies in the zone.
template <class Real>
void expectFacesInside(const Box& box)
{
  const OutflowZones<Real> zones = OutflowZones<Real>::make({ box });
  const Vec3<Real> lo = zones.min[0], hi = zones.max[0];
  const Vec3<Real> mid{ (lo.x + hi.x) / 2, (lo.y + hi.y) / 2, (lo.z + hi.z) / 2 };
  const Real xs[3] = { lo.x, mid.x, hi.x }, ys[3] = { lo.y, mid.y, hi.y }, zs[3] = { lo.z, mid.z, hi.z };
  int onFaces = 0;
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      for (int k = 0; k < 3; ++k)
      {
        const Vec3<Real> x{ xs[i], ys[j], zs[k] };
        EXPECT_TRUE(zones.contains(x)) << "(" << x.x << ", " << x.y << ", " << x.z << ")";
        onFaces += i != 1 || j != 1 || k != 1;
      }
    }
  }
  EXPECT_EQ(onFaces, 26);
  // Just outside each face (one rounding step beyond): out.
  const Real big = std::numeric_limits<Real>::max();
  EXPECT_FALSE(zones.contains({ std::nextafter(lo.x, -big), mid.y, mid.z }));
  EXPECT_FALSE(zones.contains({ std::nextafter(hi.x, big), mid.y, mid.z }));
  EXPECT_FALSE(zones.contains({ mid.x, std::nextafter(lo.y, -big), mid.z }));
  EXPECT_FALSE(zones.contains({ mid.x, std::nextafter(hi.y, big), mid.z }));
  EXPECT_FALSE(zones.contains({ mid.x, mid.y, std::nextafter(lo.z, -big) }));
  EXPECT_FALSE(zones.contains({ mid.x, mid.y, std::nextafter(hi.z, big) }));
}

double component(const Vec3d& v, int axis)
{
  return axis == 0 ? v.x : (axis == 1 ? v.y : v.z);
}

const char* const kFaceNames[6] = { "-x", "+x", "-y", "+y", "-z", "+z" };

} // namespace

// Closed zones (Outflow.h): a particle clamped onto a face of an outflow, or on its edges and
// corners, is in it and leaves, in both precisions; a rounding step beyond a face, it stays.
TEST(Outflow, PointsExactlyOnAZonesFacesAreInside)
{
  const Box box{ { 0.1, -0.25, 0.3 }, { 0.7, 0.35, 0.45 } };
  expectFacesInside<float>(box);
  expectFacesInside<double>(box);
}

// A face's outflow (depth 0) is the slab one smoothing length h deep inside that wall, reaching a
// spacing beyond the domain on its other sides. The inner face is wall -+ h computed once in
// double, so it is h from the wall to the rounding of that sum: 2 ulps of the largest coordinate
// (|x| <= 2: 4.4e-16 each; bound 1e-15), where a depth of h + s would be 4 cm off.
TEST(Outflow, AFacesOutflowStartsOneSmoothingLengthInsideTheWall)
{
  Scene scene;
  scene.domain = { { -0.3, 0.1, 0.2 }, { 1.7, 0.9, 0.65 } };
  for (int face = 0; face < 6; ++face)
  {
    Outflow outflow;
    outflow.face = face;
    scene.outflows.push_back(outflow);
  }
  const Parameters p = coarse();
  const double h = p.smoothingLength(), s = p.particleSpacing;
  ASSERT_GT(h, s);
  const std::vector<Box> zones = outflowZones(scene, p);
  ASSERT_EQ(zones.size(), 6u);
  const double tolerance = 1e-15;
  for (int face = 0; face < 6; ++face)
  {
    const int axis = face / 2;
    const Box& zone = zones[static_cast<std::size_t>(face)];
    const double low = component(scene.domain.min, axis), high = component(scene.domain.max, axis);
    if (face % 2 == 0)
    {
      EXPECT_NEAR(component(zone.max, axis) - low, h, tolerance) << kFaceNames[face];
      EXPECT_NEAR(component(zone.min, axis), low - s, tolerance) << kFaceNames[face];
    }
    else
    {
      EXPECT_NEAR(high - component(zone.min, axis), h, tolerance) << kFaceNames[face];
      EXPECT_NEAR(component(zone.max, axis), high + s, tolerance) << kFaceNames[face];
    }
    const int other = (axis + 1) % 3;
    EXPECT_NEAR(component(zone.min, other), component(scene.domain.min, other) - s, tolerance);
    EXPECT_NEAR(component(zone.max, other), component(scene.domain.max, other) + s, tolerance);
  }
}
