#include "Parameters.h"

#include "Kernels.h"
#include "SurfaceTension.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pbf
{
namespace
{

// max_k |G(k)|^2 / D on the lattice (LatticeCalibration::jacobiGain). |G|^2 is even in k and the
// lattice is cubic, so k_x >= k_y >= k_z >= 0 in [0, pi / s] covers every case: a coarse grid,
// then a finer one around its best point.
double jacobiGain(double s, double h)
{
  const auto kernels = Kernels<double>::make(h);
  const int reach = static_cast<int>(std::ceil(h / s));
  std::vector<Vec3d> r, g;
  double D = 0.0;
  for (int i = -reach; i <= reach; ++i)
  {
    for (int j = -reach; j <= reach; ++j)
    {
      for (int k = -reach; k <= reach; ++k)
      {
        const Vec3d q{ i * s, j * s, k * s };
        const double q2 = dot(q, q);
        if (q2 > 0.0 && q2 < kernels.h2)
        {
          r.push_back(q);
          g.push_back(kernels.spikyGradient(q, q2));
          D += dot(g.back(), g.back());
        }
      }
    }
  }
  const auto gain = [&](const Vec3d& k) {
    Vec3d G{ 0, 0, 0 };
    for (std::size_t m = 0; m < r.size(); ++m)
    {
      G += g[m] * std::sin(dot(k, r[m]));
    }
    return dot(G, G) / D;
  };
  const double pi = 3.14159265358979323846;
  const int coarse = 12;
  const double step = pi / s / coarse;
  double best = 0.0;
  Vec3d at{ 0, 0, 0 };
  for (int a = 0; a <= coarse; ++a)
  {
    for (int b = 0; b <= a; ++b)
    {
      for (int c = 0; c <= b; ++c)
      {
        const Vec3d k{ a * step, b * step, c * step };
        const double value = gain(k);
        if (value > best)
        {
          best = value;
          at = k;
        }
      }
    }
  }
  const Vec3d centre = at;
  for (int a = -4; a <= 4; ++a)
  {
    for (int b = -4; b <= 4; ++b)
    {
      for (int c = -4; c <= 4; ++c)
      {
        const Vec3d k = centre + Vec3d{ a * step / 8, b * step / 8, c * step / 8 };
        best = std::max(best, gain(k));
      }
    }
  }
  return best;
}

} // namespace

double Parameters::liquidRestDensity(int l) const
{
  return liquids.empty() ? restDensity : liquids[static_cast<std::size_t>(l)].restDensity;
}

double Parameters::liquidXsphNu(int l) const
{
  const double alpha = liquids.empty() ? xsphViscosity : liquids[static_cast<std::size_t>(l)].xsphViscosity;
  return std::isnan(alpha) ? xsphNu() : alpha * smoothingLength() * sceneSpeed();
}

double Parameters::largestXsphNu() const
{
  double largest = 0.0;
  for (int l = 0; l < liquidCount(); ++l)
  {
    largest = std::max(largest, liquidXsphNu(l));
  }
  return largest;
}

double Parameters::liquidSurfaceTension(int l) const
{
  const double sigma =
    liquids.empty() ? surfaceTension : liquids[static_cast<std::size_t>(l)].surfaceTension;
  return std::isnan(sigma) ? surfaceTension : sigma;
}

double Parameters::liquidWallContactAngle(int l) const
{
  const double theta =
    liquids.empty() ? contactAngle : liquids[static_cast<std::size_t>(l)].wallContactAngle;
  return std::isnan(theta) ? contactAngle : theta;
}

bool Parameters::wallAdhesion() const
{
  for (int l = 0; l < liquidCount(); ++l)
  {
    if (liquidWallContactAngle(l) != 90.0 && liquidSurfaceTension(l) > 0)
    {
      return true;
    }
  }
  return false;
}

double Parameters::largestSurfaceTension() const
{
  double largest = 0.0;
  for (int l = 0; l < liquidCount(); ++l)
  {
    largest = std::max(largest, liquidSurfaceTension(l));
  }
  return largest;
}

double Parameters::sceneSpeed() const
{
  if (sceneSpeedHint > 0)
  {
    return sceneSpeedHint;
  }
  const double g = length(gravity);
  if (!(g > 0))
  {
    return 0.0;
  }
  const Vec3d u = gravity * (1.0 / g);
  const double extent = std::abs(u.x) * (domain.max.x - domain.min.x) +
    std::abs(u.y) * (domain.max.y - domain.min.y) + std::abs(u.z) * (domain.max.z - domain.min.z);
  return std::sqrt(2.0 * g * extent);
}

namespace
{

// LatticeCalibration::surfaceColour: the particle k layers below a flat surface (along y) sees
// the sites at offsets (i, j, l) s with j <= k.
double surfaceColourShare(double s, double h, double volume)
{
  const auto kernels = Kernels<double>::make(h);
  const int reach = static_cast<int>(std::ceil(h / s));
  double share = 0.0;
  for (int layer = 0; layer <= reach; ++layer)
  {
    Vec3d gradient{ 0, 0, 0 };
    for (int i = -reach; i <= reach; ++i)
    {
      for (int j = -reach; j <= layer; ++j)
      {
        for (int k = -reach; k <= reach; ++k)
        {
          const Vec3d r{ -i * s, -j * s, -k * s };
          const double r2 = dot(r, r);
          if (r2 < kernels.h2)
          {
            gradient += colourGradientTerm(r, kernels.h2 - r2, 6.0 * kernels.poly6Scale * volume);
          }
        }
      }
    }
    const double g = length(gradient);
    share += volume / (s * s) * g * surfaceWeight(g * h);
  }
  return share;
}

} // namespace

LatticeCalibration calibrateLattice(const Parameters& p)
{
  // Sums over every lattice site within h of a site at the origin.
  const double s = p.particleSpacing;
  const double h = p.smoothingLength();
  const auto kernels = Kernels<double>::make(h);
  const int reach = static_cast<int>(std::ceil(h / s));
  const double dq = p.sCorrDeltaQ * h;
  const double wDeltaQ = kernels.poly6(dq * dq);
  double sum = 0.0;
  double gradient2 = 0.0;
  double tensile = 0.0;     // below a surface site: sites with j <= 0, pushing along +y
  double secondMoment = 0.0;
  double firstMoment = 0.0;
  for (int i = -reach; i <= reach; ++i)
  {
    for (int j = -reach; j <= reach; ++j)
    {
      for (int k = -reach; k <= reach; ++k)
      {
        // r = p_origin - p_site
        const Vec3d r{ -i * s, -j * s, -k * s };
        const double r2 = dot(r, r);
        const double w = kernels.poly6(r2);
        sum += w;
        const Vec3d g = kernels.spikyGradient(r, r2);
        gradient2 += dot(g, g);
        secondMoment += w * r2;
        firstMoment += dot(r, g);
        if (j <= 0 && r2 < kernels.h2 && r2 > 0.0)
        {
          tensile += std::pow(w / wDeltaQ, p.sCorrN) * -g.y;
        }
      }
    }
  }
  LatticeCalibration c;
  c.jacobiGain = jacobiGain(s, h);
  c.jacobiRelaxation = std::min(1.0, kJacobiGainTarget / c.jacobiGain);
  c.mass = p.restDensity / sum;
  const double massOverRho0 = c.mass / p.restDensity;
  c.gradientSum = massOverRho0 * massOverRho0 * gradient2;
  c.tensileSurfacePush = massOverRho0 * tensile;
  c.xsphSecondMoment = massOverRho0 * secondMoment / 6.0;
  c.gradientMoment = -massOverRho0 * firstMoment / 3.0;
  c.surfaceColour = surfaceColourShare(s, h, massOverRho0);
  return c;
}

} // namespace pbf
