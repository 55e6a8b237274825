#include "ShapeIntegrals.h"

#include "Kernels.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace pbf
{
namespace
{

constexpr double kPi = 3.14159265358979323846;
// Radial nodes: exact for polynomials up to degree 31; the kernels times r^2 are at most 28
// (s_corr's W^n times the spiky gradient with n = 4).
constexpr int kRadialNodes = 16;

// Gauss-Legendre nodes and weights on [-1, 1], by Newton's iteration on P_n.
std::vector<std::pair<double, double>> gaussLegendre(int n)
{
  std::vector<std::pair<double, double>> rule(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
  {
    double x = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double derivative = 1;
    for (int iteration = 0; iteration < 100; ++iteration)
    {
      double p0 = 1, p1 = x;
      for (int k = 2; k <= n; ++k)
      {
        const double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      derivative = n * (x * p1 - p0) / (x * x - 1);
      const double step = p1 / derivative;
      x -= step;
      if (std::abs(step) < 1e-16)
      {
        break;
      }
    }
    rule[static_cast<std::size_t>(i)] = { x, 2 / ((1 - x * x) * derivative * derivative) };
  }
  return rule;
}

// The radial integrals of one ray over [a, b] (0 <= a < b <= h), each kernel times r^2.
struct Radial
{
  double poly6 = 0, spiky = 0, spiky2 = 0, tensile = 0;
};

// x^n: by multiplication where n is a small whole number (s_corr's n is 4 by default), which is
// most of the integration's time through std::pow otherwise.
double power(double x, double n)
{
  if (n >= 0 && n <= 16 && n == std::floor(n))
  {
    double result = 1;
    for (int e = static_cast<int>(n); e > 0; --e)
    {
      result *= x;
    }
    return result;
  }
  return std::pow(x, n);
}

// The four integrands at r (each kernel times r^2). The spiky gradient at r: grad_x W(x - y) is
// g(r) times the unit vector from y to x, with g < 0, so it points towards y.
Radial integrands(double r, const Kernels<double>& kernels, const ShapeKernels& k)
{
  const double w = kernels.poly6(r * r);
  const double g = r < k.h ? kernels.spikyGradScale * (k.h - r) * (k.h - r) : 0.0;
  const double r2 = r * r;
  return { w * r2, g * r2, g * g * r2, g * -power(w / k.wDeltaQ, k.sCorrN) * r2 };
}

// Gauss-Legendre over [a, b]: exact for the kernels, polynomials in r.
Radial exactRadial(double a, double b, const ShapeKernels& k)
{
  static const std::vector<std::pair<double, double>> nodes = gaussLegendre(kRadialNodes);
  const Kernels<double> kernels = Kernels<double>::make(k.h);
  Radial sum;
  const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
  for (const auto& [t, weight] : nodes)
  {
    const Radial f = integrands(mid + half * t, kernels, k);
    sum.poly6 += weight * half * f.poly6;
    sum.spiky += weight * half * f.spiky;
    sum.spiky2 += weight * half * f.spiky2;
    sum.tensile += weight * half * f.tensile;
  }
  return sum;
}

// The integrals from 0 to r, tabulated exactly at kSteps + 1 radii with the integrands there and
// read by cubic Hermite between them: a relative error below 1e-12 (the step is h / 4096 and the
// fourth derivative of a kernel's antiderivative is of order its value over h^4), for four
// evaluations of each kernel where Gauss-Legendre takes sixteen per ray's interval. One table per
// thread and set of kernels.
class RadialTable
{
public:
  static const RadialTable& of(const ShapeKernels& k)
  {
    static thread_local RadialTable table;
    if (!(table.k_.h == k.h && table.k_.sCorrN == k.sCorrN && table.k_.wDeltaQ == k.wDeltaQ))
    {
      table = RadialTable(k);
    }
    return table;
  }

  Radial upTo(double r) const
  {
    const double u = std::clamp(r / k_.h, 0.0, 1.0) * kSteps;
    const int i = std::min(static_cast<int>(u), kSteps - 1);
    const double t = u - i, step = k_.h / kSteps;
    const double h00 = (1 + 2 * t) * (1 - t) * (1 - t), h10 = t * (1 - t) * (1 - t);
    const double h01 = t * t * (3 - 2 * t), h11 = t * t * (t - 1);
    const auto at = [&](double Radial::*field) {
      return h00 * total_[i].*field + h10 * step * rate_[i].*field +
        h01 * total_[i + 1].*field + h11 * step * rate_[i + 1].*field;
    };
    return { at(&Radial::poly6), at(&Radial::spiky), at(&Radial::spiky2), at(&Radial::tensile) };
  }

private:
  static constexpr int kSteps = 4096;
  RadialTable() : k_{ 0, 0, 0 } {}
  explicit RadialTable(const ShapeKernels& k)
    : k_(k)
    , total_(kSteps + 1)
    , rate_(kSteps + 1)
  {
    const Kernels<double> kernels = Kernels<double>::make(k.h);
    for (int i = 0; i <= kSteps; ++i)
    {
      const double r = k.h * i / kSteps;
      rate_[i] = integrands(r, kernels, k);
      if (i > 0)
      {
        const Radial piece = exactRadial(k.h * (i - 1) / kSteps, r, k);
        total_[i] = { total_[i - 1].poly6 + piece.poly6, total_[i - 1].spiky + piece.spiky,
          total_[i - 1].spiky2 + piece.spiky2, total_[i - 1].tensile + piece.tensile };
      }
    }
  }
  ShapeKernels k_;
  std::vector<Radial> total_, rate_;
};

Radial radial(double a, double b, const ShapeKernels& k)
{
  const RadialTable& table = RadialTable::of(k);
  const Radial from = table.upTo(a), to = table.upTo(b);
  return { to.poly6 - from.poly6, to.spiky - from.spiky, to.spiky2 - from.spiky2,
    to.tensile - from.tensile };
}

// Adds a ray's radial integrals, weighted by its solid angle, to the totals. The gradient with
// respect to x of W(x - y) is g times the unit vector from y to x, minus the ray's direction.
void accumulate(ShapeIntegrals& total, const Radial& r, const Vec3d& direction, double weight)
{
  total.poly6 += weight * r.poly6;
  total.spiky = total.spiky - direction * (weight * r.spiky);
  total.spiky2 += weight * r.spiky2;
  total.tensile = total.tensile - direction * (weight * r.tensile);
}

// The rays of the rule about a pole: direction and solid angle. mu = cos(theta) is split at
// split (a half-space at distance split h starts there), Gauss-Legendre on each side.
template <class Visit>
void forEachRay(const Vec3d& pole, double split, const ShapeRule& rule, Visit&& visit)
{
  static thread_local std::vector<std::pair<double, double>> nodes;
  if (static_cast<int>(nodes.size()) != rule.polar)
  {
    nodes = gaussLegendre(rule.polar);
  }
  // Two unit vectors across the pole.
  const Vec3d helper = std::abs(pole.x) < 0.9 ? Vec3d{ 1, 0, 0 } : Vec3d{ 0, 1, 0 };
  const Vec3d across = cross(pole, helper);
  const Vec3d e1 = across * (1 / length(across));
  const Vec3d e2 = cross(pole, e1);
  const int azimuths = 2 * rule.polar;
  const double turn = 2 * kPi / azimuths;
  const double cut = std::clamp(split, -1.0, 1.0);
  for (const auto& [lo, hi] : { std::pair<double, double>{ -1.0, cut }, { cut, 1.0 } })
  {
    if (hi <= lo)
    {
      continue;
    }
    for (const auto& [t, weight] : nodes)
    {
      const double mu = 0.5 * (lo + hi) + 0.5 * (hi - lo) * t;
      const double sine = std::sqrt(std::max(0.0, 1 - mu * mu));
      for (int a = 0; a < azimuths; ++a)
      {
        const double angle = (a + 0.5) * turn;
        const Vec3d direction =
          e1 * (sine * std::cos(angle)) + e2 * (sine * std::sin(angle)) + pole * mu;
        visit(direction, mu, weight * 0.5 * (hi - lo) * turn);
      }
    }
  }
}

// Where phi changes sign between r0 (value f0) and r1 (value f1): the Illinois variant of
// regula falsi, to 1e-9 of h. phi is close to linear along a ray between two nodes, so a few
// steps reach it where bisection takes fifty.
double crossing(const Vec3d& x, const Vec3d& direction,
  const std::function<double(const Vec3d&)>& phi, double r0, double f0, double r1, double f1,
  double tolerance)
{
  int side = 0;
  for (int iteration = 0; iteration < 100 && r1 - r0 > tolerance; ++iteration)
  {
    double r = (r0 * f1 - r1 * f0) / (f1 - f0);
    if (!(r > r0 && r < r1))
    {
      r = 0.5 * (r0 + r1);
    }
    const double f = phi(x + direction * r);
    if (f == 0)
    {
      return r;
    }
    if ((f < 0) == (f0 < 0))
    {
      r0 = r;
      f0 = f;
      f1 = side == -1 ? 0.5 * f1 : f1;
      side = -1;
    }
    else
    {
      r1 = r;
      f1 = f;
      f0 = side == 1 ? 0.5 * f0 : f0;
      side = 1;
    }
    if (std::abs(r1 - r0) <= tolerance)
    {
      break;
    }
  }
  return 0.5 * (r0 + r1);
}

} // namespace

ShapeIntegrals integrateOverSolid(const Vec3d& x, const Vec3d& pole,
  const std::function<double(const Vec3d&)>& phi, const ShapeKernels& k, const ShapeRule& rule)
{
  ShapeIntegrals total;
  const double here = phi(x);
  if (here >= k.h)
  {
    return total;
  }
  forEachRay(pole, here / k.h, rule, [&](const Vec3d& direction, double, double weight) {
    double r0 = 0, f0 = here;
    double start = f0 < 0 ? 0.0 : -1.0; // the open interval's start, -1 when outside
    // phi is a distance: no surface lies within |phi| of a point, so the march strides that far
    // (nine tenths of it, for the interpolated field), and never less than h / marchSteps.
    const double least = k.h / rule.marchSteps;
    while (r0 < k.h)
    {
      const double r1 = std::min(k.h, r0 + std::max(least, 0.9 * std::abs(f0)));
      const double f1 = phi(x + direction * r1);
      if ((f1 < 0) != (f0 < 0))
      {
        const double r = crossing(x, direction, phi, r0, f0, r1, f1, 1e-9 * k.h);
        if (start >= 0)
        {
          accumulate(total, radial(start, r, k), direction, weight);
          start = -1;
        }
        else
        {
          start = r;
        }
      }
      r0 = r1;
      f0 = f1;
    }
    if (start >= 0)
    {
      accumulate(total, radial(start, k.h, k), direction, weight);
    }
  });
  return total;
}

ShapeIntegrals integrateOverHalfSpace(double d, const ShapeKernels& k, const ShapeRule& rule)
{
  ShapeIntegrals total;
  if (d >= k.h)
  {
    return total;
  }
  const Vec3d pole{ 0, 0, 1 };
  forEachRay(pole, d / k.h, rule, [&](const Vec3d& direction, double mu, double weight) {
    // Inside where d - r mu < 0, within [0, h].
    double a = 0, b = k.h;
    if (mu > 0)
    {
      a = std::max(0.0, d / mu);
    }
    else if (mu < 0)
    {
      b = std::min(k.h, d / mu);
    }
    else if (d >= 0)
    {
      return;
    }
    if (b > a)
    {
      accumulate(total, radial(a, b, k), direction, weight);
    }
  });
  return total;
}

} // namespace pbf
