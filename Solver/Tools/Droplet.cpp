#include "Droplet.h"

#include "LatticeShapes.h"

#include <cmath>
#include <limits>

namespace pbf::validation
{

namespace
{
constexpr double kPi = 3.14159265358979323846;

// D(t) = m + e^(-gamma t) (a cos(omega t) + b sin(omega t)) fitted by least squares: for each
// (omega, gamma) on a grid (omega from 0.2 to 3 times the guess, gamma up to twice it) the model
// is linear in m, a and b; the best pair is then refined by halving the grid's steps around it.
// A fit uses every sample, so a crossing that noise adds near the end of a damped oscillation
// does not shorten the period as counting crossings did (at 15 spacings per radius: -16 % by
// crossings where the fit reads the same as at the other step). Also counts the crossings of m.
struct DampedFit
{
  double omega = 0, gamma = 0, misfit = 0;
  int crossings = 0;
};
DampedFit fitDampedOscillation(
  const std::vector<double>& t, const std::vector<double>& d, double guess)
{
  // The residual of the linear least squares for one (omega, gamma), by the normal equations.
  const auto residual = [&](double omega, double gamma, double* offset) {
    double A[3][3] = {}, r[3] = {};
    for (std::size_t k = 0; k < t.size(); ++k)
    {
      const double e = std::exp(-gamma * t[k]);
      const double f[3] = { 1.0, e * std::cos(omega * t[k]), e * std::sin(omega * t[k]) };
      for (int a = 0; a < 3; ++a)
      {
        r[a] += f[a] * d[k];
        for (int b = 0; b < 3; ++b)
        {
          A[a][b] += f[a] * f[b];
        }
      }
    }
    // Cramer's rule on the 3 x 3 system.
    const auto det3 = [](const double M[3][3]) {
      return M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) -
        M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
        M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]);
    };
    const double D = det3(A);
    if (!(std::abs(D) > 0))
    {
      return std::numeric_limits<double>::infinity();
    }
    double x[3];
    for (int c = 0; c < 3; ++c)
    {
      double M[3][3];
      for (int a = 0; a < 3; ++a)
      {
        for (int b = 0; b < 3; ++b)
        {
          M[a][b] = b == c ? r[a] : A[a][b];
        }
      }
      x[c] = det3(M) / D;
    }
    double sum = 0;
    for (std::size_t k = 0; k < t.size(); ++k)
    {
      const double e = std::exp(-gamma * t[k]);
      const double model =
        x[0] + e * (x[1] * std::cos(omega * t[k]) + x[2] * std::sin(omega * t[k]));
      sum += (model - d[k]) * (model - d[k]);
    }
    if (offset)
    {
      *offset = x[0];
    }
    return sum;
  };
  DampedFit best;
  best.misfit = std::numeric_limits<double>::infinity();
  double dOmega = 0.01 * guess, dGamma = 0.02 * guess;
  for (double omega = 0.2 * guess; omega <= 3 * guess; omega += dOmega)
  {
    for (double gamma = 0; gamma <= 2 * guess; gamma += dGamma)
    {
      const double e = residual(omega, gamma, nullptr);
      if (e < best.misfit)
      {
        best = { omega, gamma, e, 0 };
      }
    }
  }
  for (int round = 0; round < 12; ++round)
  {
    dOmega /= 2;
    dGamma /= 2;
    const DampedFit centre = best;
    for (int a = -2; a <= 2; ++a)
    {
      for (int b = -2; b <= 2; ++b)
      {
        const double omega = centre.omega + a * dOmega, gamma = std::max(0.0, centre.gamma + b * dGamma);
        const double e = residual(omega, gamma, nullptr);
        if (e < best.misfit)
        {
          best = { omega, gamma, e, 0 };
        }
      }
    }
  }
  double mean = 0;
  residual(best.omega, best.gamma, &mean);
  for (std::size_t k = 1; k < d.size(); ++k)
  {
    best.crossings += (d[k - 1] > mean) != (d[k] > mean) ? 1 : 0;
  }
  return best;
}

// The mean pressure of the particles within `within` of the particles' centre.
double interiorPressure(const Snapshot<double>& state, double within)
{
  Vec3d c{ 0, 0, 0 };
  for (const Vec3d& x : state.position)
  {
    c += x * (1.0 / static_cast<double>(state.position.size()));
  }
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < state.position.size(); ++i)
  {
    const Vec3d d = state.position[i] - c;
    if (dot(d, d) < within * within && i < state.pressure.size())
    {
      sum += state.pressure[i];
      ++n;
    }
  }
  return n > 0 ? sum / n : 0.0;
}
} // namespace

Scene dropletScene(double radius)
{
  Scene scene;
  scene.name = "droplet";
  scene.domain = { { 0, 0, 0 }, { 4 * radius, 4 * radius, 4 * radius } };
  // The region the lattice is cut from (dropletFluid keeps the spheroid's sites).
  scene.boxes.push_back({ { 0, 0, 0 }, { 4 * radius, 4 * radius, 4 * radius }, {}, 0 });
  return scene;
}

ParticleBatch dropletFluid(
  const Scene& scene, const Parameters& parameters, double radius, double elongation)
{
  const double a = radius * (1 + elongation), b = radius / std::sqrt(1 + elongation);
  const Vec3d centre{ 2 * radius, 2 * radius, 2 * radius };
  return latticeSitesInside(scene, parameters, [&](const Vec3d& x) {
    const Vec3d d = x - centre;
    return d.x * d.x / (a * a) + (d.y * d.y + d.z * d.z) / (b * b) <= 1;
  });
}

double rayleighPeriod(double radius, double density, double sigma)
{
  return 2 * kPi * std::sqrt(density * radius * radius * radius / (8 * sigma));
}

double deformation(const Snapshot<double>& state)
{
  Vec3d c{ 0, 0, 0 };
  const double n = static_cast<double>(state.position.size());
  for (const Vec3d& x : state.position)
  {
    c += x * (1.0 / n);
  }
  double xx = 0, yy = 0, zz = 0;
  for (const Vec3d& x : state.position)
  {
    const Vec3d d = x - c;
    xx += d.x * d.x;
    yy += d.y * d.y;
    zz += d.z * d.z;
  }
  return (xx - 0.5 * (yy + zz)) / n;
}

DropletRun runDroplet(const Parameters& parameters, Backend backend, Precision precision,
  double radius, double elongation, double until, double sample)
{
  Parameters p = parameters;
  p.gravity = { 0, 0, 0 };
  const Scene scene = dropletScene(radius);
  Simulation simulation(scene, p, backend, precision, dropletFluid(scene, p, radius, elongation));
  DropletRun run;
  run.theory = rayleighPeriod(radius, p.restDensity, p.surfaceTension);
  const int samples = static_cast<int>(std::lround(until / sample));
  for (int s = 0; s <= samples; ++s)
  {
    simulation.advanceTo(s * sample);
    Snapshot<double> state;
    simulation.stepper().read(state);
    run.particles = state.position.size();
    run.t.push_back(s * sample);
    run.deformation.push_back(deformation(state));
    if (s == samples)
    {
      run.pressure = interiorPressure(state, radius / 2);
    }
  }
  run.laplace = 2 * p.surfaceTension / radius;
  run.steps = static_cast<double>(simulation.stepCount());
  const DampedFit fit = fitDampedOscillation(run.t, run.deformation, 2 * kPi / run.theory);
  run.period = fit.omega > 0 ? 2 * kPi / fit.omega : 0.0;
  run.damping = fit.gamma;
  run.crossings = fit.crossings;
  return run;
}

} // namespace pbf::validation
