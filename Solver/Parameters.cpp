#include "Parameters.h"

#include "Kernels.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

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

void requirePositive(const std::string& field, double value)
{
  requireFinite(field, value);
  if (value <= 0.0)
  {
    reject(field, value, "must be > 0");
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

} // namespace

void Parameters::validate() const
{
  requirePositive("restDensity", restDensity);
  requirePositive("particleSpacing", particleSpacing);
  requireFinite("smoothingRatio", smoothingRatio);
  if (smoothingRatio <= 1.0 || smoothingRatio > 4.0)
  {
    // At 1 the nearest lattice neighbours sit exactly at h, outside the kernels' support (r < h):
    // every particle would be alone and the constraint has no gradient.
    reject("smoothingRatio", smoothingRatio,
      "h / spacing must lie in (1, 4]: at 1 or less a particle has no neighbour within h");
  }
  if (solverIterations < 1 || solverIterations > 1000)
  {
    reject("solverIterations", solverIterations, "must lie in [1, 1000]");
  }
  requireNonNegative("densityErrorTolerance", densityErrorTolerance);
  requirePositive("relaxation", relaxation);
  requireNonNegative("sCorrK", sCorrK);
  requirePositive("sCorrN", sCorrN);
  if (sCorrN > 16.0)
  {
    // Beyond that, float rounding of W / W(delta_q) near 1 is raised to inf (and 0 x inf = NaN
    // for coincident particles).
    reject("sCorrN", sCorrN, "must lie in (0, 16] (paper: 4)");
  }
  requireFinite("sCorrDeltaQ", sCorrDeltaQ);
  if (sCorrDeltaQ <= 0.0 || sCorrDeltaQ >= 1.0)
  {
    reject("sCorrDeltaQ", sCorrDeltaQ, "must lie in (0, 1) (a fraction of h)");
  }
  requireFinite("xsphC", xsphC);
  if (xsphC < 0.0 || xsphC > 1.0)
  {
    reject("xsphC", xsphC, "must lie in [0, 1]");
  }
  requireNonNegative("vorticityEpsilon", vorticityEpsilon);
  requireFinite("gravity.x", gravity.x);
  requireFinite("gravity.y", gravity.y);
  requireFinite("gravity.z", gravity.z);
  requirePositive("timeStep", timeStep);
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
  requireFits<Real>("sCorrK", p.sCorrK, "k over the bulk denominator of eq. 11",
    p.sCorrK / lattice.gradientSum, true);
  const double dq = p.sCorrDeltaQ * h;
  const double wDeltaQ = kernels.poly6(dq * dq);
  requireFits<Real>("sCorrDeltaQ", p.sCorrDeltaQ, "1 / W(delta_q)", 1.0 / wDeltaQ);
  // s_corr is largest for coincident particles: k (W(0) / W(delta_q))^n.
  requireFits<Real>("sCorrN", p.sCorrN, "the largest s_corr, k (W(0) / W(delta_q))^n",
    p.sCorrK / lattice.gradientSum * std::pow(kernels.poly6(0.0) / wDeltaQ, p.sCorrN), true);
  requireFits<Real>("xsphC", p.xsphC, "xsphC", p.xsphC, true);
  requireFits<Real>("vorticityEpsilon", p.vorticityEpsilon, "vorticityEpsilon",
    p.vorticityEpsilon, true);
  requireFits<Real>("timeStep", p.timeStep, "timeStep", p.timeStep);
  requireFits<Real>("timeStep", p.timeStep, "1 / timeStep", 1.0 / p.timeStep);
  const char* axis[3] = { "x", "y", "z" };
  const double g[3] = { p.gravity.x, p.gravity.y, p.gravity.z };
  const double lo[3] = { p.domain.min.x, p.domain.min.y, p.domain.min.z };
  const double hi[3] = { p.domain.max.x, p.domain.max.y, p.domain.max.z };
  double farthest = 0.0;
  for (int a = 0; a < 3; ++a)
  {
    requireFits<Real>(std::string("gravity.") + axis[a], g[a], "gravity", g[a], true);
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
  // Sum poly6 and the squared spiky gradients over every lattice site within h of a site.
  const double s = p.particleSpacing;
  const double h = p.smoothingLength();
  const auto kernels = Kernels<double>::make(h);
  const int reach = static_cast<int>(std::ceil(h / s));
  double sum = 0.0;
  double gradient2 = 0.0;
  for (int i = -reach; i <= reach; ++i)
  {
    for (int j = -reach; j <= reach; ++j)
    {
      for (int k = -reach; k <= reach; ++k)
      {
        const Vec3d r{ i * s, j * s, k * s };
        const double r2 = dot(r, r);
        sum += kernels.poly6(r2);
        const Vec3d g = kernels.spikyGradient(r, r2);
        gradient2 += dot(g, g);
      }
    }
  }
  LatticeCalibration c;
  c.mass = p.restDensity / sum;
  const double massOverRho0 = c.mass / p.restDensity;
  c.gradientSum = massOverRho0 * massOverRho0 * gradient2;
  return c;
}

std::string describe(const Parameters& p)
{
  std::ostringstream out;
  out << "rho0=" << p.restDensity << " s=" << p.particleSpacing << " h=" << p.smoothingLength()
      << " m=" << calibratedParticleMass(p) << " iterations=" << p.solverIterations
      << (p.densityErrorTolerance > 0 ? " (adaptive to " + std::to_string(p.densityErrorTolerance) + "%)" : "")
      << " epsilon=" << p.relaxation << " k=" << p.sCorrK << " n=" << p.sCorrN
      << " dq=" << p.sCorrDeltaQ << " c=" << p.xsphC << " vorticity=" << p.vorticityEpsilon
      << " dt=" << p.timeStep;
  return out.str();
}

} // namespace pbf
