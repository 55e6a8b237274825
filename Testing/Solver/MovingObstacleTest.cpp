// Moving solid obstacles (Scene/SolidMotion.h): the keyframes' poses and velocities, a paddle
// that pushes water without letting a particle into it, a moving floor that drags the fluid only
// with friction, the same bits on Serial, OpenMP and one decomposed rank (and rounding on two),
// resumed from a checkpoint or split into other frames, and scene errors naming the key.
#include "Backends.h"
#include "Distributed/ThreadCluster.h"
#include "Scene.h"
#include "Simulation.h"
#include "SolidMotion.h"
#include "Solids.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace pbf;

namespace
{

constexpr double kPi = 3.14159265358979323846;

// Exact in double up to rounding of a few operations.
constexpr double kRounding = 1e-12;

void expectNear(const Vec3d& a, const Vec3d& b, double tolerance)
{
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

// A quarter turn about z through (1, 0, 0) and 2 m along x, over the second from t = 1 to 2.
SolidMotion quarterTurn()
{
  SolidMotion m;
  m.pivot = { 1, 0, 0 };
  m.keyframes.push_back({ 1.0, { 0, 0, 0 }, Rotation{} });
  m.keyframes.push_back({ 2.0, { 2, 0, 0 }, Rotation::fromDegrees({ 0, 0, 90 }) });
  return m;
}

// Water 0.2 m deep in a 1 x 0.5 x 0.12 m tank at s = 0.04 m, and a paddle (a box through the
// whole depth) at x = 0.1-0.18 m that moves 0.3 m along +x in 0.5 s, then stops.
const char* const kPaddle = R"({
  "name": "paddle",
  "domain": { "min": [0, 0, 0], "max": [1.0, 0.5, 0.12] },
  "fluid": [ { "type": "box", "min": [0, 0, 0], "max": [1.0, 0.2, 0.12] } ],
  "obstacles": [ { "type": "box", "min": [0.1, -0.2, -0.2], "max": [0.18, 0.45, 0.32],
    "motion": { "keyframes": [ { "time": 0 }, { "time": 0.5, "translation": [0.3, 0, 0] } ] } } ]
})";

Parameters paddleParameters()
{
  Parameters p;
  p.particleSpacing = 0.04;
  return p;
}

// The smallest signed distance of any particle centre to the scene's solids at `time`.
double closestToSolids(const Simulation& simulation, double time)
{
  const Parameters& p = simulation.parameters();
  const std::vector<DistanceGrid> fields = solidFields(simulation.scene().solids, p);
  const std::vector<SolidPose> poses = posesAt(solidMotions(simulation.scene().solids), time);
  Snapshot<double> state;
  simulation.stepper().read(state);
  double closest = HUGE_VAL;
  for (const Vec3d& x : state.position)
  {
    for (std::size_t k = 0; k < fields.size(); ++k)
    {
      closest = std::min(closest, fields[k].at(poses.empty() ? x : poses[k].toLocal(x)));
    }
  }
  return closest;
}

Snapshot<double> stateOf(const Simulation& simulation)
{
  Snapshot<double> state;
  simulation.stepper().read(state);
  return state;
}

} // namespace

TEST(SolidMotion, InterpolatesBetweenKeyframesAndHoldsBeforeAndAfter)
{
  const SolidMotion m = quarterTurn();
  const Vec3d corner{ 2, 0, 0 }; // 1 m from the pivot along x
  // Held at the first keyframe before it, at rest.
  const SolidPose before = m.at(0.25);
  EXPECT_TRUE(before.moving);
  expectNear(before.toWorld(corner), corner, kRounding);
  expectNear(before.velocityAt(corner), { 0, 0, 0 }, 0);
  // Half way: the pivot 1 m along, an eighth of a turn about it.
  const SolidPose half = m.at(1.5);
  expectNear(half.pivot, { 2, 0, 0 }, kRounding);
  const double r = std::sqrt(0.5);
  expectNear(half.toWorld(corner), { 2 + r, r, 0 }, kRounding);
  expectNear(half.toLocal(half.toWorld(corner)), corner, kRounding);
  // Constant rates over the segment: 2 m/s, pi/2 rad/s about +z.
  expectNear(half.pivotVelocity, { 2, 0, 0 }, kRounding);
  expectNear(half.angularVelocity, { 0, 0, kPi / 2 }, kRounding);
  // Held at the last keyframe after it.
  const SolidPose after = m.at(7.0);
  expectNear(after.toWorld(corner), { 3, 1, 0 }, kRounding);
  expectNear(after.velocityAt(corner), { 0, 0, 0 }, 0);
  // Without keyframes: the identity, not moving (the solid's bits as sampled).
  EXPECT_FALSE(SolidMotion{}.at(1.0).moving);
}

TEST(SolidMotion, TheVelocityIsTheRateOfChangeOfThePose)
{
  SolidMotion m = quarterTurn();
  m.keyframes.push_back({ 3.0, { 2, 1, -1 }, Rotation::fromDegrees({ 30, 20, 100 }) });
  const Vec3d point{ 0.3, -0.4, 0.7 };
  for (double t : { 1.3, 1.8, 2.2, 2.9 })
  {
    // A central difference of the point's path: its error is O(delta^2) times the path's
    // curvature (~10 m/s^2 here), 1e-9 at delta = 1e-5, plus rounding of 1e-16 / 1e-5.
    const double delta = 1e-5;
    const Vec3d ahead = m.at(t + delta).toWorld(point), behind = m.at(t - delta).toWorld(point);
    const Vec3d rate = (ahead - behind) * (0.5 / delta);
    const SolidPose pose = m.at(t);
    expectNear(pose.velocityAt(pose.toWorld(point)), rate, 1e-7);
  }
}

TEST(SolidMotion, RotationsComposeAsParaViewsTransform)
{
  // ParaView's Transform turns about y, then x, then z (vtkTransform: RotateZ, RotateX, RotateY).
  expectNear(Rotation::fromDegrees({ 0, 90, 0 }).apply({ 1, 0, 0 }), { 0, 0, -1 }, kRounding);
  expectNear(Rotation::fromDegrees({ 90, 0, 0 }).apply({ 0, 1, 0 }), { 0, 0, 1 }, kRounding);
  // y first: (1, 0, 0) -> (0, 0, -1), then x: -> (0, 1, 0), then z: -> (-1, 0, 0).
  expectNear(Rotation::fromDegrees({ 90, 90, 90 }).apply({ 1, 0, 0 }), { -1, 0, 0 }, kRounding);
  // A matrix and its quaternion agree both ways.
  const Rotation q = Rotation::fromDegrees({ 10, -70, 200 });
  const Rotation back = Rotation::fromMatrix(q.matrix());
  const double sign = q.w * back.w + q.x * back.x + q.y * back.y + q.z * back.z > 0 ? 1 : -1;
  EXPECT_NEAR(back.w * sign, q.w, kRounding);
  EXPECT_NEAR(back.x * sign, q.x, kRounding);
  EXPECT_NEAR(back.y * sign, q.y, kRounding);
  EXPECT_NEAR(back.z * sign, q.z, kRounding);
}

TEST(MovingObstacle, APaddlePushesTheWaterAndNoParticleEntersIt)
{
  Simulation simulation(parseScene(kPaddle), paddleParameters(), Backend::Serial, Precision::Double);
  // The fluid where the paddle stands at t = 0 was removed.
  EXPECT_GT(simulation.seededInsideSolids(), 0u);
  double closest = HUGE_VAL, highestAhead = 0;
  for (int frame = 1; frame <= 36; ++frame)
  {
    const double t = frame / 60.0;
    simulation.advanceTo(t);
    closest = std::min(closest, closestToSolids(simulation, t));
    if (frame == 30)
    {
      // The paddle (now at x = 0.4-0.48 m) has pushed a bore ahead of it: the water just ahead
      // of it stands higher than the 0.2 m it started at, and flows along +x.
      const Snapshot<double> state = stateOf(simulation);
      double momentum = 0;
      for (std::size_t i = 0; i < state.position.size(); ++i)
      {
        momentum += state.velocity[i].x;
        if (state.position[i].x > 0.48 && state.position[i].x < 0.6)
        {
          highestAhead = std::max(highestAhead, state.position[i].y);
        }
      }
      // Mean x velocity, measured 0.37 m/s (the paddle moves at 0.6 m/s).
      EXPECT_GT(momentum / static_cast<double>(state.position.size()), 0.1);
    }
  }
  // Particle centres stay out: the solid's share of the density keeps them off it (closest
  // measured 7.6 mm); the collision would leave one on the surface (distance 0 to the trilinear
  // field's rounding), so anything below -1e-9 m is a particle inside.
  EXPECT_GE(closest, -1e-9);
  EXPECT_GT(highestAhead, 0.2 + 0.04); // measured 0.30 m
}

TEST(MovingObstacle, AnIdentityPoseGivesTheBitsOfAStaticSolid)
{
  // The pose path (into the solid's frame, the gradient back out) with the identity must change
  // nothing: the same field, placed or not, gives the same bits.
  const Scene scene = parseScene(kPaddle);
  const Parameters p = withSceneDomain(paddleParameters(), scene);
  const ParticleBatch fluid = fillScene(scene, p);
  std::size_t removed = 0;
  const std::vector<DistanceGrid> fields = solidFields(scene.solids, p);
  const ParticleBatch outside = outsideSolids(fluid, fields, {}, removed);
  SolidPose identity;
  identity.moving = true;
  auto a = makeStepper(Backend::Serial, Precision::Double, p, outside);
  auto b = makeStepper(Backend::Serial, Precision::Double, p, outside);
  a->setObstacles(fields, { identity });
  b->setObstacles(fields);
  for (int s = 0; s < 30; ++s)
  {
    a->setObstaclePoses({ identity });
    a->step();
    b->step();
  }
  Snapshot<double> sa, sb;
  a->read(sa);
  b->read(sb);
  test::expectBitIdentical(sa, sb);
}

TEST(MovingObstacle, SerialOpenMPAndDecomposedRanksAgree)
{
  const Scene scene = parseScene(kPaddle);
  const double until = 0.15;
  Simulation serial(scene, paddleParameters(), Backend::Serial, Precision::Double);
  Simulation openmp(scene, paddleParameters(), Backend::OpenMP, Precision::Double);
  serial.advanceTo(until);
  openmp.advanceTo(until);
  const Snapshot<double> reference = stateOf(serial);
  test::expectBitIdentical(stateOf(openmp), reference);
  // One rank runs the serial stages in the serial order: the same bits. Two sum a particle's
  // neighbours in another order: rounding (1e-16 a sum), well under 1e-9 after 0.15 s, where a
  // paddle left where it started would move particles by centimetres.
  for (int ranks : { 1, 2 })
  {
    std::vector<Snapshot<double>> parts(static_cast<std::size_t>(ranks));
    distributed::runThreadCluster(ranks, [&](distributed::Communicator& communicator) {
      Simulation part(scene, paddleParameters(), Backend::Serial, Precision::Double, &communicator);
      part.advanceTo(until);
      part.stepper().read(parts[static_cast<std::size_t>(communicator.rank())]);
    });
    const Snapshot<double> all = test::joined(parts);
    if (ranks == 1)
    {
      test::expectBitIdentical(all, reference);
    }
    EXPECT_LE(test::maxRelativePositionError(all, reference), 1e-9) << ranks << " ranks";
  }
  // The paddle moved the fluid (else the comparisons say nothing about the motion).
  Scene still = scene;
  still.solids[0].motion = SolidMotion{};
  Simulation unmoved(still, paddleParameters(), Backend::Serial, Precision::Double);
  unmoved.advanceTo(until);
  EXPECT_GT(test::maxRelativePositionError(stateOf(unmoved), reference), 1e-3);
}

TEST(MovingObstacle, ACheckpointAndOtherFramesGiveTheSameBits)
{
  const Scene scene = parseScene(kPaddle);
  // Frames of 1/60 s, a checkpoint at 0.1 s resumed in a fresh run.
  Simulation framed(scene, paddleParameters(), Backend::Serial, Precision::Double);
  for (int frame = 1; frame <= 6; ++frame)
  {
    framed.advanceTo(frame / 60.0);
  }
  const SimulationCheckpoint at = framed.checkpoint();
  Simulation resumed(scene, paddleParameters(), Backend::Serial, Precision::Double);
  resumed.restore(at);
  for (int frame = 7; frame <= 18; ++frame)
  {
    framed.advanceTo(frame / 60.0);
    resumed.advanceTo(frame / 60.0);
  }
  test::expectBitIdentical(stateOf(resumed), stateOf(framed));
  // The same frames again from the start: the same bits (the poses are a function of time).
  Simulation again(scene, paddleParameters(), Backend::Serial, Precision::Double);
  for (int frame = 1; frame <= 18; ++frame)
  {
    again.advanceTo(frame / 60.0);
  }
  test::expectBitIdentical(stateOf(again), stateOf(framed));
}

TEST(MovingObstacle, AMovingFloorDragsTheFluidOnlyWithFriction)
{
  // A layer at rest on a solid floor that slides along +x at 1 m/s: free-slip leaves the layer
  // (almost) where it is; no-slip drags it along.
  const char* const slidingFloor = R"({
    "domain": { "min": [0, 0, 0], "max": [1.8, 0.5, 0.1] },
    "fluid": [ { "type": "box", "min": [0.5, 0.1, 0], "max": [1.0, 0.2, 0.1] } ],
    "obstacles": [ { "type": "box", "min": [-1, -1, -1], "max": [3, 0.1, 1],
      "motion": { "keyframes": [ { "time": 0 }, { "time": 1, "translation": [1, 0, 0] } ] } } ]
  })";
  auto meanSpeed = [&](double friction) {
    Parameters p;
    p.particleSpacing = 0.025;
    p.wallFriction = friction;
    Simulation simulation(parseScene(slidingFloor), p, Backend::OpenMP, Precision::Double);
    simulation.advanceTo(0.25);
    double sum = 0;
    const Snapshot<double> state = stateOf(simulation);
    for (const Vec3d& v : state.velocity)
    {
      sum += v.x;
    }
    return sum / static_cast<double>(state.velocity.size());
  };
  const double free = meanSpeed(0.0), sticky = meanSpeed(1.0);
  // Measured 0.000 and 0.34 m/s; the bounds leave a factor of 2 or more.
  EXPECT_LT(std::abs(free), 0.05);
  EXPECT_GT(sticky, 0.15);
}

TEST(MovingObstacle, SceneErrorsNameTheKeyAndAnObstacleThatNeverEntersTheDomain)
{
  auto error = [](const std::string& motion) {
    try
    {
      parseScene(R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
        "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}],
        "obstacles": [{"type": "sphere", "center": [0.7, 0.7, 0.7], "radius": 0.1,
        "motion": )" + motion + "}]}");
    }
    catch (const InvalidInput& e)
    {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error(R"({"keyframes": [{"time": 1}, {"time": 0.5}]})")
              .find(".obstacles[0].motion.keyframes[1].time = 0.5: keyframe times must increase"),
    std::string::npos);
  EXPECT_NE(error(R"({"keyframes": []})").find(".obstacles[0].motion.keyframes"),
    std::string::npos);
  EXPECT_NE(error(R"({"keyframes": [{"time": 0, "spin": 3}]})")
              .find(".obstacles[0].motion.keyframes[0].spin"),
    std::string::npos);
  EXPECT_NE(error(R"({"keyframes": [{"time": 0, "translation": [1, "a", 0]}]})")
              .find(".obstacles[0].motion.keyframes[0].translation"),
    std::string::npos);
  // Out of the domain at every keyframe: refused when the run is built, naming the solid.
  Scene away = parseScene(R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
    "fluid": [{"type": "box", "min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}],
    "obstacles": [{"type": "sphere", "center": [0.7, 0.7, 0.7], "radius": 0.1,
      "motion": {"keyframes": [{"time": 0, "translation": [5, 0, 0]},
                               {"time": 1, "translation": [6, 0, 0]}]}}]})");
  Parameters p;
  p.particleSpacing = 0.05;
  try
  {
    Simulation s(away, p, Backend::Serial, Precision::Double);
    FAIL() << "a solid outside the domain at every keyframe was accepted";
  }
  catch (const InvalidInput& e)
  {
    EXPECT_NE(std::string(e.what()).find("obstacles[0]: lies outside the domain"),
      std::string::npos)
      << e.what();
  }
  // Brought into the domain by a keyframe: accepted.
  away.solids[0].motion.keyframes[1].translation = { 0, 0, 0 };
  EXPECT_NO_THROW(Simulation(away, p, Backend::Serial, Precision::Double));
}
