// The diffuse particles' model (Solver/Physics/Diffuse.h): the potentials' clamp, the trapped-air
// term, the births' random rounding (its mean at any dt), the hash's draws, the cap's thinning,
// the classification and the three kinds' motion, the same at any time step.
#include "Diffuse.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

using namespace pbf;

TEST(Diffuse, APotentialIsClampedBetweenItsThresholds)
{
  // Eq. 1: 0 at or below the lower threshold, 1 at or above the upper, linear between (exact in
  // binary fractions here).
  EXPECT_EQ(potential(1.0, 2.0, 6.0), 0.0);
  EXPECT_EQ(potential(2.0, 2.0, 6.0), 0.0);
  EXPECT_EQ(potential(3.0, 2.0, 6.0), 0.25);
  EXPECT_EQ(potential(6.0, 2.0, 6.0), 1.0);
  EXPECT_EQ(potential(60.0, 2.0, 6.0), 1.0);
}

TEST(Diffuse, TrappedAirCountsApproachingNeighboursTwice)
{
  // v_ij along -x_ij (approaching): 2 |v_ij|; perpendicular: |v_ij|; receding: 0 (1e-15:
  // rounding of a unit vector's length).
  const Vec3d x{ 1, 0, 0 };
  EXPECT_NEAR(trappedAirTerm(Vec3d{ -3, 0, 0 }, x), 6.0, 1e-15);
  EXPECT_NEAR(trappedAirTerm(Vec3d{ 0, 3, 0 }, x), 3.0, 1e-15);
  EXPECT_NEAR(trappedAirTerm(Vec3d{ 3, 0, 0 }, x), 0.0, 1e-15);
  EXPECT_EQ(trappedAirTerm(Vec3d{ 0, 0, 0 }, x), 0.0);
  EXPECT_EQ(trappedAirTerm(Vec3d{ 1, 0, 0 }, Vec3d{ 0, 0, 0 }), 0.0);
}

TEST(Diffuse, DrawsAreUniformAndTheSameForTheSameParticleAndStep)
{
  // The same (id, step, draw) gives the same bits; 100,000 draws fill 10 bins evenly (each within
  // 5 standard deviations, sqrt(10,000 * 0.9) = 95, of 10,000) and their mean is 1/2 within 5
  // standard deviations (0.29 / sqrt(100,000) = 9.1e-4).
  EXPECT_EQ(uniformDraw(7, 11, 2), uniformDraw(7, 11, 2));
  EXPECT_NE(uniformDraw(7, 11, 2), uniformDraw(7, 12, 2));
  EXPECT_NE(uniformDraw(7, 11, 2), uniformDraw(8, 11, 2));
  EXPECT_NE(uniformDraw(7, 11, 2), uniformDraw(7, 11, 3));
  std::vector<int> bins(10, 0);
  double sum = 0;
  for (std::uint64_t id = 0; id < 1000; ++id)
  {
    for (std::uint64_t step = 0; step < 100; ++step)
    {
      const double u = uniformDraw(id, step, 0);
      ASSERT_GE(u, 0.0);
      ASSERT_LT(u, 1.0);
      ++bins[static_cast<std::size_t>(u * 10)];
      sum += u;
    }
  }
  for (int b : bins)
  {
    EXPECT_NEAR(b, 10000, 5 * 95);
  }
  EXPECT_NEAR(sum / 100000, 0.5, 5 * 9.1e-4);
}

TEST(Diffuse, TheBirthsOfASecondDoNotDependOnTheTimeStep)
{
  // A particle expected to emit 3.7 a second, over one second in 1,000 steps or in 100: the mean
  // count of 2,000 particles is 3.7 either way, within 5 standard errors (a second's count has a
  // variance of at most 3.7 (1 - dt share), so the mean's standard error is below
  // sqrt(3.7 / 2,000) = 0.043). Rounding to the nearest count instead (the paper's) gives 0 at
  // both.
  const double rate = 3.7;
  for (int steps : { 1000, 100 })
  {
    const double dt = 1.0 / steps;
    double total = 0;
    for (std::uint64_t id = 0; id < 2000; ++id)
    {
      for (int step = 0; step < steps; ++step)
      {
        total += birthCount(rate * dt, uniformDraw(id, static_cast<std::uint64_t>(step), 0), 8);
      }
    }
    EXPECT_NEAR(total / 2000, rate, 5 * 0.043) << steps << " steps";
  }
  // The cap and the edges: never above it, 0 for nothing or NaN.
  EXPECT_EQ(birthCount(20.5, 0.0, 8), 8);
  EXPECT_EQ(birthCount(7.9, 0.0, 8), 8);
  EXPECT_EQ(birthCount(7.9, 0.95, 8), 7);
  EXPECT_EQ(birthCount(0.0, 0.0, 8), 0);
  EXPECT_EQ(birthCount(std::nan(""), 0.0, 8), 0);
}

TEST(Diffuse, TheCapKeepsExactlyItsRoomSpreadOverTheCandidates)
{
  // 1,000 candidates, room for 1 to 1,000: exactly `room` kept, into slots 0..room-1 in order, and
  // no gap between kept candidates longer than ceil(total / room).
  const std::uint64_t total = 1000;
  for (std::uint64_t room : { 1ull, 7ull, 333ull, 999ull, 1000ull, 5000ull })
  {
    std::uint64_t kept = 0, last = 0, longest = 0;
    bool any = false;
    for (std::uint64_t g = 0; g < total; ++g)
    {
      std::uint64_t slot = 0;
      if (keptUnderCap(g, total, room, &slot))
      {
        EXPECT_EQ(slot, kept) << "room " << room;
        longest = any ? std::max(longest, g - last) : longest;
        last = g;
        any = true;
        ++kept;
      }
    }
    EXPECT_EQ(kept, std::min(room, total)) << "room " << room;
    if (room < total && room > 1)
    {
      EXPECT_LE(longest, (total + room - 1) / room) << "room " << room;
    }
  }
}

TEST(Diffuse, AParticleIsSprayFoamOrBubbleByTheFluidAroundIt)
{
  DiffuseCoefficients<double> c{};
  c.sprayBelow = 0.2;
  c.bubbleAbove = 0.6;
  EXPECT_EQ(classifyDiffuse(0.0, c), DiffuseKind::Spray);
  EXPECT_EQ(classifyDiffuse(0.19, c), DiffuseKind::Spray);
  EXPECT_EQ(classifyDiffuse(0.5, c), DiffuseKind::Foam); // on a flat free surface
  EXPECT_EQ(classifyDiffuse(0.6, c), DiffuseKind::Foam);
  EXPECT_EQ(classifyDiffuse(1.0, c), DiffuseKind::Bubble);
}

namespace
{

// A diffuse particle of `kind` from rest at the origin, in fluid moving at `fluid`, after `time`
// seconds in steps of dt.
Vec3d advanced(DiffuseKind kind, const Vec3d& fluid, double time, double dt, Vec3d* velocity)
{
  const DiffuseStep<double> s = makeDiffuseStep<double>(dt, 0.012, 0.5, 2.0);
  Vec3d x{ 0, 0, 0 }, v{ 0, 0, 0 };
  const int steps = static_cast<int>(std::lround(time / dt));
  for (int k = 0; k < steps; ++k)
  {
    advanceDiffuse(kind, x, v, fluid, Vec3d{ 0, -9.81, 0 }, s);
  }
  *velocity = v;
  return x;
}

} // namespace

TEST(Diffuse, EachKindMovesTheSameAtAnyTimeStep)
{
  const Vec3d fluid{ 0.3, 0, 0 };
  Vec3d v1, v2;
  // A bubble's slip tends to k_b tau_b |g| = 2 x 0.012 x 9.81 = 0.2354 m/s upward, whatever dt: the
  // velocity's update is exact for a steady fluid (1e-12: rounding over 4,000 steps).
  advanced(DiffuseKind::Bubble, fluid, 0.5, 1e-3, &v1);
  advanced(DiffuseKind::Bubble, fluid, 0.5, 1.25e-4, &v2);
  EXPECT_NEAR(v1.y, 2 * 0.012 * 9.81, 1e-12);
  EXPECT_NEAR(v2.y, 2 * 0.012 * 9.81, 1e-12);
  EXPECT_NEAR(v1.x, 0.3, 1e-12);
  // Spray with air drag of 0.5 s: its velocity after 0.4 s is g tau (1 - e^(-t/tau)) at any dt
  // (1e-12, as above); foam moves with the fluid, 0.3 m/s x 0.4 s.
  advanced(DiffuseKind::Spray, fluid, 0.4, 1e-3, &v1);
  advanced(DiffuseKind::Spray, fluid, 0.4, 2e-4, &v2);
  const double exact = -9.81 * 0.5 * -std::expm1(-0.4 / 0.5);
  EXPECT_NEAR(v1.y, exact, 1e-12);
  EXPECT_NEAR(v2.y, exact, 1e-12);
  EXPECT_NEAR(advanced(DiffuseKind::Foam, fluid, 0.4, 1e-3, &v1).x, 0.12, 1e-12);
  // Without air drag spray falls as a stone: v = g t exactly.
  const DiffuseStep<double> free = makeDiffuseStep<double>(
    1e-3, 0.012, std::numeric_limits<double>::infinity(), 2.0);
  EXPECT_EQ(free.sprayKeep, 1.0);
  EXPECT_EQ(free.sprayFall, 1e-3);
}
