// The smoothing kernels are normalised and the spiky gradient is the gradient of spiky.
#include "Kernels.h"

#include <gtest/gtest.h>

#include <random>

using pbf::Kernels;
using pbf::Vec3d;

namespace
{

// Integral of a radial function over the ball of radius h, by composite Simpson in r.
template <class F>
double integrateOverSupport(double h, F&& w)
{
  const int n = 20000;
  const double pi = 3.14159265358979323846;
  const double dr = h / n;
  double sum = 0;
  for (int k = 0; k <= n; ++k)
  {
    const double r = k * dr;
    const double weight = (k == 0 || k == n) ? 1 : (k % 2 ? 4 : 2);
    sum += weight * w(r) * 4 * pi * r * r;
  }
  return sum * dr / 3;
}

} // namespace

TEST(Kernels, Poly6AndSpikyIntegrateToOneOverTheirSupport)
{
  for (double h : { 0.01, 0.04, 1.0 })
  {
    const auto k = Kernels<double>::make(h);
    // Simpson with 20000 intervals on degree-8 polynomials: error far below 1e-9.
    EXPECT_NEAR(integrateOverSupport(h, [&](double r) { return k.poly6(r * r); }), 1.0, 1e-9)
      << "h = " << h;
    EXPECT_NEAR(integrateOverSupport(h, [&](double r) { return k.spiky(r); }), 1.0, 1e-9)
      << "h = " << h;
  }
}

TEST(Kernels, KernelsVanishAtAndBeyondTheSupportRadius)
{
  const auto k = Kernels<double>::make(0.04);
  EXPECT_EQ(k.poly6(0.04 * 0.04), 0.0);
  EXPECT_EQ(k.spiky(0.04), 0.0);
  const Vec3d r{ 0.05, 0, 0 };
  const Vec3d g = k.spikyGradient(r, dot(r, r));
  EXPECT_EQ(g.x, 0.0);
}

TEST(Kernels, SpikyGradientMatchesFiniteDifferences)
{
  const double h = 0.04;
  const auto k = Kernels<double>::make(h);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-h, h);
  int checked = 0;
  while (checked < 200)
  {
    const Vec3d r{ coordinate(random), coordinate(random), coordinate(random) };
    const double len = pbf::length(r);
    if (len < 0.05 * h || len > 0.95 * h)
    {
      continue; // the kink at 0 and the cut at h are not smooth: central differences fail there
    }
    const Vec3d g = k.spikyGradient(r, dot(r, r));
    const double step = 1e-7 * h;
    const double scale = pbf::length(g);
    const Vec3d axes[3] = { { step, 0, 0 }, { 0, step, 0 }, { 0, 0, step } };
    const double analytic[3] = { g.x, g.y, g.z };
    for (int a = 0; a < 3; ++a)
    {
      const double numeric =
        (k.spiky(pbf::length(r + axes[a])) - k.spiky(pbf::length(r - axes[a]))) / (2 * step);
      // Central differences have O(step^2) truncation and ~1e-16 / step rounding: 1e-6 of the
      // gradient's magnitude is well above both.
      EXPECT_NEAR(numeric, analytic[a], 1e-6 * scale);
    }
    ++checked;
  }
}
