// The checks of Parameters: the table's ranges (ParameterTable.h) and what the solver derives
// from them in a given precision, and the one-line description of a run.
#include "ParameterTable.h"
#include "Parameters.h"

#include "Kernels.h"

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

// The liquids' densities, as ratios to the reference restDensity, scale each particle's
// correction (StepTime::liquidWeight): a ratio beyond kMostDensityRatio either way would make
// the lighter liquid's corrections that many times the heavier's, which the Jacobi projection
// does not converge for.
constexpr double kMostDensityRatio = 100.0;

void validateLiquids(const Parameters& p)
{
  if (p.liquids.size() > static_cast<std::size_t>(kMaxLiquids))
  {
    reject("liquids", static_cast<double>(p.liquids.size()),
      "at most " + std::to_string(kMaxLiquids) + " liquids in one scene");
  }
  for (std::size_t l = 0; l < p.liquids.size(); ++l)
  {
    const Liquid& liquid = p.liquids[l];
    // Named as the scene names them: liquids[1].restDensity, and the liquid's name in the rule.
    const std::string field = "liquids[" + std::to_string(l) + "].";
    const std::string of = " (liquid \"" + liquid.name + "\")";
    if (liquid.name.empty())
    {
      reject(field + "name", 0, "every liquid needs a name");
    }
    for (std::size_t k = 0; k < l; ++k)
    {
      if (p.liquids[k].name == liquid.name)
      {
        reject(field + "name", static_cast<double>(l), "liquids[" + std::to_string(k) +
          "] has the same name" + of);
      }
    }
    if (!(liquid.restDensity > 0.0) || !std::isfinite(liquid.restDensity))
    {
      reject(field + "restDensity", liquid.restDensity, "must be a finite number > 0 [kg/m^3]" + of);
    }
    const double ratio = liquid.restDensity / p.restDensity;
    if (ratio > kMostDensityRatio || ratio < 1.0 / kMostDensityRatio)
    {
      std::ostringstream rule;
      rule << "must be within " << kMostDensityRatio << " times restDensity (" << p.restDensity
           << " kg/m^3), the reference the particles' volume is calibrated at" << of;
      reject(field + "restDensity", liquid.restDensity, rule.str());
    }
    if (!std::isnan(liquid.xsphViscosity) &&
      !(liquid.xsphViscosity >= 0.0 && std::isfinite(liquid.xsphViscosity)))
    {
      reject(field + "xsphViscosity", liquid.xsphViscosity, "must be a finite number >= 0" + of);
    }
    if (!std::isnan(liquid.surfaceTension) &&
      !(liquid.surfaceTension >= 0.0 && std::isfinite(liquid.surfaceTension)))
    {
      reject(field + "surfaceTension", liquid.surfaceTension,
        "must be a finite number >= 0 [N/m]" + of);
    }
    if (!std::isnan(liquid.wallContactAngle) &&
      !(liquid.wallContactAngle >= 0.0 && liquid.wallContactAngle <= 180.0))
    {
      reject(field + "contactAngles.walls", liquid.wallContactAngle,
        "must lie in [0, 180] [degrees]" + of);
    }
  }
}

} // namespace

void Parameters::validate() const
{
  // The user-facing parameters, each against its row's range (ParameterTable.h).
  validateTableParameters(*this);
  requireNonNegative("sceneSpeedHint", sceneSpeedHint);
  if (timeStepping != TimeStepping::Fixed && timeStepping != TimeStepping::Automatic)
  {
    reject("timeStepping", static_cast<double>(timeStepping), "must be Fixed (0) or Automatic (1)");
  }
  validateLiquids(*this);
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
      << " xsphNu=" << p.xsphNu();
  for (const Liquid& liquid : p.liquids)
  {
    out << " liquid=" << liquid.name << ":" << liquid.restDensity << ":" << liquid.xsphViscosity << ":"
        << liquid.surfaceTension << ":" << liquid.wallContactAngle;
  }
  out << " dt="
      << (p.timeStepping == TimeStepping::Automatic ? "automatic" : "fixed");
  return out.str();
}

} // namespace pbf
