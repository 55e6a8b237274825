#include "Parameters.h"

#include "Kernels.h"
#include "ParameterTable.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace pbf
{
namespace
{

[[noreturn]] void reject(const std::string& field, double value, const std::string& rule)
{
  std::ostringstream msg;
  msg << field << " = " << value << ": " << rule;
  throw InvalidInput(msg.str());
}

void requireFinite(const std::string& field, double value)
{
  if (!std::isfinite(value))
  {
    reject(field, value, "must be a finite number");
  }
}

void requireNonNegative(const std::string& field, double value)
{
  requireFinite(field, value);
  if (value < 0.0)
  {
    reject(field, value, "must be >= 0");
  }
}

// Whether a nonzero double keeps its meaning as a Real: finite, and not below the smallest normal
// number (denormals lose precision and flush to zero on some GPUs).
template <class Real>
bool fits(double value)
{
  const double magnitude = std::abs(value);
  return magnitude <= static_cast<double>(std::numeric_limits<Real>::max()) &&
    (magnitude == 0.0 || magnitude >= static_cast<double>(std::numeric_limits<Real>::min()));
}

template <class Real>
const char* precisionName()
{
  return sizeof(Real) == sizeof(float) ? "single" : "double";
}

// Rejects `field` when a quantity derived from it does not fit Real.
template <class Real>
void requireFits(const std::string& field, double fieldValue, const std::string& quantity,
  double value, bool zeroAllowed = false)
{
  if (fits<Real>(value) && (zeroAllowed || value != 0.0))
  {
    return;
  }
  std::ostringstream rule;
  rule << quantity << " = " << value << " is out of " << precisionName<Real>()
       << "-precision range";
  if (sizeof(Real) == sizeof(float))
  {
    rule << "; use double precision or choose units that bring it nearer 1";
  }
  reject(field, fieldValue, rule.str());
}

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

void Parameters::validate() const
{
  // The user-facing parameters, each against its row's range (ParameterTable.h).
  validateTableParameters(*this);
  requireNonNegative("sceneSpeedHint", sceneSpeedHint);
  if (timeStepping != TimeStepping::Fixed && timeStepping != TimeStepping::Automatic)
  {
    reject("timeStepping", static_cast<double>(timeStepping), "must be Fixed (0) or Automatic (1)");
  }
  const char* axis[3] = { "x", "y", "z" };
  const double lo[3] = { domain.min.x, domain.min.y, domain.min.z };
  const double hi[3] = { domain.max.x, domain.max.y, domain.max.z };
  for (int a = 0; a < 3; ++a)
  {
    requireFinite(std::string("domain.min.") + axis[a], lo[a]);
    requireFinite(std::string("domain.max.") + axis[a], hi[a]);
    if (hi[a] - lo[a] < smoothingLength())
    {
      std::ostringstream rule;
      rule << "the domain must be at least one smoothing length h = " << smoothingLength()
           << " wide along " << axis[a] << " (min " << lo[a] << "; h = smoothingRatio "
           << smoothingRatio << " x particleSpacing " << particleSpacing
           << "): lower particleSpacing or enlarge the domain";
      reject(std::string("domain.max.") + axis[a], hi[a], rule.str());
    }
  }
}

template <class Real>
void validatePrecision(const Parameters& p)
{
  // The constants Coefficients<Real>::make derives, computed in double as it does.
  const double s = p.particleSpacing;
  const double h = p.smoothingLength();
  const auto kernels = Kernels<double>::make(h);
  requireFits<Real>("particleSpacing", s, "h^2", kernels.h2);
  requireFits<Real>("particleSpacing", s, "the poly6 constant 315 / (64 pi h^9)", kernels.poly6Scale);
  requireFits<Real>(
    "particleSpacing", s, "the spiky gradient constant 45 / (pi h^6)", kernels.spikyGradScale);
  const LatticeCalibration lattice = calibrateLattice(p);
  requireFits<Real>("restDensity", p.restDensity, "the particle mass [kg]", lattice.mass);
  requireFits<Real>("restDensity", p.restDensity, "1 / restDensity", 1.0 / p.restDensity);
  requireFits<Real>("particleSpacing", s, "mass / restDensity [m^3]", lattice.mass / p.restDensity);
  requireFits<Real>("relaxation", p.relaxation, "epsilon times the bulk denominator of eq. 11",
    p.relaxation * lattice.gradientSum);
  const double dq = p.sCorrDeltaQ * h;
  const double wDeltaQ = kernels.poly6(dq * dq);
  requireFits<Real>("sCorrDeltaQ", p.sCorrDeltaQ, "1 / W(delta_q)", 1.0 / wDeltaQ);
  // s_corr is largest for coincident particles: k (W(0) / W(delta_q))^n.
  requireFits<Real>("sCorrN", p.sCorrN, "the largest s_corr factor (W(0) / W(delta_q))^n",
    std::pow(kernels.poly6(0.0) / wDeltaQ, p.sCorrN), true);
  requireFits<Real>("sCorrK", p.sCorrK, "k g0 over the tensile term's surface push",
    p.sCorrK * kStandardGravity / lattice.tensileSurfacePush, true);
  // Every real parameter reaches the kernels as a Real (ParameterTable.h).
  for (const ParameterSpec& spec : parameterTable())
  {
    if (spec.type == ParameterType::Real || spec.type == ParameterType::Vector)
    {
      for (int c = 0; c < spec.components(); ++c)
      {
        const std::string name = std::string(spec.field) +
          (spec.type == ParameterType::Vector ? std::string(".") + "xyz"[c] : std::string());
        const double value = spec.get(p, c);
        requireFits<Real>(name, value, spec.field, value, true);
      }
    }
  }
  requireFits<Real>("timeStep", p.timeStep, "1 / timeStep", 1.0 / p.timeStep);
  const char* axis[3] = { "x", "y", "z" };
  const double lo[3] = { p.domain.min.x, p.domain.min.y, p.domain.min.z };
  const double hi[3] = { p.domain.max.x, p.domain.max.y, p.domain.max.z };
  double farthest = 0.0;
  for (int a = 0; a < 3; ++a)
  {
    requireFits<Real>(std::string("domain.min.") + axis[a], lo[a], "the coordinate", lo[a], true);
    requireFits<Real>(std::string("domain.max.") + axis[a], hi[a], "the coordinate", hi[a], true);
    farthest = std::max(farthest, std::max(std::abs(lo[a]), std::abs(hi[a])));
  }
  // The solver moves particles by small fractions of s: Real must resolve them everywhere in
  // the domain. 256 units in the last place leave about 8 bits below the spacing.
  const double resolution = farthest * static_cast<double>(std::numeric_limits<Real>::epsilon());
  if (s < 256.0 * resolution)
  {
    std::ostringstream rule;
    rule << precisionName<Real>() << " precision resolves only " << resolution
         << " m at the domain's coordinate " << farthest
         << " (the spacing must be at least 256 times that); "
         << (sizeof(Real) == sizeof(float) ? "use double precision or " : "")
         << "move the domain nearer the origin";
    reject("particleSpacing", s, rule.str());
  }
}

template void validatePrecision<float>(const Parameters& p);
template void validatePrecision<double>(const Parameters& p);

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
  return c;
}

std::string describe(const Parameters& p)
{
  // Every row of the table by its field name, then what the run derives from them.
  std::ostringstream out;
  for (const ParameterSpec& spec : parameterTable())
  {
    out << spec.field << "=";
    for (int c = 0; c < spec.components(); ++c)
    {
      out << (c ? "," : "") << spec.get(p, c);
    }
    out << " ";
  }
  out << "h=" << p.smoothingLength() << " m=" << calibratedParticleMass(p)
      << " xsphNu=" << p.xsphNu() << " dt="
      << (p.timeStepping == TimeStepping::Automatic ? "automatic" : "fixed");
  return out.str();
}

} // namespace pbf
