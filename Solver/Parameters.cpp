#include "Parameters.h"

#include "Kernels.h"

#include <cmath>
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

} // namespace

void Parameters::validate() const
{
  requirePositive("restDensity", restDensity);
  requirePositive("particleSpacing", particleSpacing);
  requireFinite("smoothingRatio", smoothingRatio);
  if (smoothingRatio < 1.0 || smoothingRatio > 4.0)
  {
    reject("smoothingRatio", smoothingRatio, "h / spacing must lie in [1, 4]");
  }
  if (solverIterations < 1 || solverIterations > 1000)
  {
    reject("solverIterations", solverIterations, "must lie in [1, 1000]");
  }
  requireNonNegative("densityErrorTolerance", densityErrorTolerance);
  requirePositive("relaxation", relaxation);
  requireNonNegative("sCorrK", sCorrK);
  requirePositive("sCorrN", sCorrN);
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
      reject(std::string("domain.max.") + axis[a], hi[a],
        "the domain must be at least one smoothing length h = " +
          std::to_string(smoothingLength()) + " wide along " + axis[a] + " (min " +
          std::to_string(lo[a]) + ")");
    }
  }
}

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
