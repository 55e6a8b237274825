// Probes (Surface/Probes.h): what the particles read at points, on the initial lattice, where the
// answers are known.
#include "Probes.h"
#include "Scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace pbf;

namespace
{

constexpr double kSpacing = 0.05;
constexpr double kHeight = 0.4; // the block's height: 8 layers

struct Block
{
  Parameters parameters;
  std::vector<Vec3d> x, v;
  std::vector<double> pressure;
};

// A block of water filling the domain's bottom, every particle moving at (1, 2, 3) m/s with a
// pressure of 1000 Pa + its height in mm (a field whose mean a probe must find).
Block block()
{
  Block b;
  b.parameters.particleSpacing = kSpacing;
  b.parameters.domain = { { 0, 0, 0 }, { 1, 1, 1 } };
  Scene scene;
  scene.domain = b.parameters.domain;
  scene.boxes.push_back({ { 0, 0, 0 }, { 1, kHeight, 1 }, { 0, 0, 0 } });
  const ParticleBatch water = fillScene(scene, b.parameters);
  b.x = water.position;
  b.v.assign(b.x.size(), Vec3d{ 1, 2, 3 });
  for (const Vec3d& x : b.x)
  {
    b.pressure.push_back(1000.0 + 1000.0 * x.y);
  }
  return b;
}

ProbeReading read(const Block& b, const ParticleSums& sums, const Vec3d& probe)
{
  std::vector<Vec3d> points = gaugeColumn(b.parameters, probe);
  points.insert(points.begin(), probe);
  std::vector<double> values;
  sums.at(points, values);
  return readProbe(b.parameters, probe, values.data(), values.data() + kProbeSums, points.size() - 1);
}

} // namespace

// At a site inside the lattice the fraction is 1 (the mass is calibrated so that a site reads
// rho_0 with poly6: 1e-12, rounding; between sites it reads 2.6 % less), a uniform velocity reads
// as itself, and a field linear in y reads its value at the probe (poly6 is symmetric about the
// site: the lattice's mean of a linear field is exact).
TEST(Probes, InsideTheLatticeAProbeReadsTheParticlesFields)
{
  const Block b = block();
  const ParticleSums sums(b.parameters, b.x.data(), b.v.data(), b.pressure.data(), b.x.size());
  const Vec3d probe{ 0.525, 0.225, 0.525 }; // a site: (k + 1/2) s
  const ProbeReading r = read(b, sums, probe);
  ASSERT_TRUE(r.inside);
  EXPECT_NEAR(r.fraction, 1.0, 1e-12);
  EXPECT_NEAR(r.velocity.x, 1.0, 1e-12);
  EXPECT_NEAR(r.velocity.y, 2.0, 1e-12);
  EXPECT_NEAR(r.velocity.z, 3.0, 1e-12);
  EXPECT_NEAR(r.pressure, 1000.0 + 1000.0 * probe.y, 1e-9);
}

// A probe on the floor reads the block's height, and one at 0.1 m the height above it: within a
// sample (s / 4) and the half spacing the kernel blurs the surface by at most (measured: exact to
// the sample at both). In the air above, nothing: a fraction of 0 and no water.
TEST(Probes, TheWaterHeightIsTheLatticesHeightAboveTheProbe)
{
  const Block b = block();
  const ParticleSums sums(b.parameters, b.x.data(), b.v.data(), b.pressure.data(), b.x.size());
  EXPECT_NEAR(read(b, sums, { 0.5, 0.0, 0.5 }).waterHeight, kHeight, 0.25 * kSpacing);
  EXPECT_NEAR(read(b, sums, { 0.5, 0.1, 0.5 }).waterHeight, kHeight - 0.1, 0.25 * kSpacing);
  const ProbeReading air = read(b, sums, { 0.5, 0.8, 0.5 });
  EXPECT_EQ(air.fraction, 0.0);
  EXPECT_EQ(air.waterHeight, 0.0);
  EXPECT_EQ(air.pressure, 0.0);
}

// A probe outside the domain reads NaN and says so; it is not an error.
TEST(Probes, AProbeOutsideTheDomainReadsNaN)
{
  const Block b = block();
  const ParticleSums sums(b.parameters, b.x.data(), b.v.data(), b.pressure.data(), b.x.size());
  const ProbeReading r = read(b, sums, { 1.5, 0.2, 0.5 });
  EXPECT_FALSE(r.inside);
  EXPECT_TRUE(std::isnan(r.pressure));
  EXPECT_TRUE(std::isnan(r.waterHeight));
  EXPECT_TRUE(std::isnan(r.velocity.x));
}

// The sums are linear in the particles: two halves' sums add up to the whole's (what a decomposed
// run adds over its ranks), to rounding (1e-12 of the largest sum).
TEST(Probes, TheSumsOfTwoHalvesAreTheSumsOfTheWhole)
{
  const Block b = block();
  const std::size_t half = b.x.size() / 2;
  const ParticleSums whole(b.parameters, b.x.data(), b.v.data(), b.pressure.data(), b.x.size());
  const ParticleSums first(b.parameters, b.x.data(), b.v.data(), b.pressure.data(), half);
  const ParticleSums second(b.parameters, b.x.data() + half, b.v.data() + half,
    b.pressure.data() + half, b.x.size() - half);
  const std::vector<Vec3d> points = gaugeColumn(b.parameters, { 0.5, 0.0, 0.5 });
  std::vector<double> all, a, c;
  whole.at(points, all);
  first.at(points, a);
  second.at(points, c);
  ASSERT_EQ(all.size(), a.size());
  double scale = 0;
  for (double value : all)
  {
    scale = std::max(scale, std::abs(value));
  }
  for (std::size_t k = 0; k < all.size(); ++k)
  {
    ASSERT_NEAR(a[k] + c[k], all[k], 1e-12 * scale) << k;
  }
}

// The wet threshold itself: readProbe given the sums directly, a column of 8 samples (2 spacings)
// all at one fluid fraction F. Above the floor's band, F just above 1/2 (the documented
// threshold, Probes.h) is wet along the whole column and F = 1/2 or just below is dry, as is any
// 0 < F < 1/2 (1/3 + 0.01 among them); within s/2 of the floor the threshold is 1/4. "Just": 1e-9
// of F, which places the threshold to a billionth of the fraction rather than to a sample of the
// height (the lattice test above). The probe reads its own F and pressure as max(F, 1/2) weighs it.
TEST(Probes, TheWetThresholdIsAHalfAndAQuarterOnTheFloor)
{
  Parameters p;
  p.particleSpacing = kSpacing;
  p.domain = { { 0, 0, 0 }, { 1, 1, 1 } };
  const std::size_t samples = 8;
  const double dy = 0.25 * kSpacing;
  const auto height = [&](double y, double fraction, bool defaulted) {
    std::vector<double> sums((samples + 1) * kProbeSums, 0.0);
    for (std::size_t k = 0; k <= samples; ++k)
    {
      sums[k * kProbeSums] = fraction;
      sums[k * kProbeSums + 1] = 100 * fraction; // a pressure of 100 Pa
    }
    const Vec3d probe{ 0.5, y, 0.5 };
    const ProbeReading r = defaulted
      ? readProbe(p, probe, sums.data(), sums.data() + kProbeSums, samples)
      : readProbe(p, probe, sums.data(), sums.data() + kProbeSums, samples, 0.5);
    EXPECT_EQ(r.fraction, fraction);
    EXPECT_NEAR(r.pressure, 100 * fraction / std::max(fraction, 0.5), 1e-12);
    return r.waterHeight;
  };
  const double eps = 1e-9;
  for (bool defaulted : { true, false })
  {
    const double y = 0.5; // far above the floor's band
    // Wet: dy added 8 times, to rounding (1e-15 m).
    EXPECT_NEAR(height(y, 0.5 + eps, defaulted), samples * dy, 1e-15) << "just above 1/2: wet";
    for (double dry : { 0.5, 0.5 - eps, 1.0 / 3.0 + 0.01, 0.1, 1e-6 })
    {
      EXPECT_EQ(height(y, dry, defaulted), 0.0) << "F = " << dry << ": dry";
    }
    // On the floor: the two samples below s/2 (at s/8 and 3 s/8) count from F > 1/4.
    EXPECT_EQ(height(0.0, 0.25 + eps, defaulted), 2 * dy);
    EXPECT_EQ(height(0.0, 0.25 - eps, defaulted), 0.0);
  }
}
