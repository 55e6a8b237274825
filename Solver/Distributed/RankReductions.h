// Statistics and the divergence check's health scan over the ranks of a decomposed run, from each
// rank's own particles in host arrays: shared by the CPU SubdomainStepper and the CUDA one (which
// copies its particles back first). Collective; sums go in rank order, so every rank gets the
// same bits whatever the timing.
#pragma once

#include "Communicator.h"
#include "HostParticles.h"
#include "ParticleChecks.h"
#include "SpeedHistogram.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pbf::distributed
{

// averageNeighbors is not computed across ranks (NaN).
template <class Real>
Statistics reduceStatistics(
  Communicator& communicator, const Parameters& parameters, const ConstHostParticles<Real>& p)
{
  const LiquidMasses masses(parameters);
  double errorSum = 0, errorMax = 0, speedMax = 0, kinetic = 0, finite = 1;
  Vec3d momentum{ 0, 0, 0 };
  for (std::size_t i = 0; i < p.x.size(); ++i)
  {
    const double error = std::max(double(p.density[i]) / parameters.restDensity - 1.0, 0.0);
    errorSum += error;
    errorMax = std::max(errorMax, error);
    const Vec3d xi = Vec3d::from(p.x[i]);
    const Vec3d vi = Vec3d::from(p.v[i]);
    const double speed2 = dot(vi, vi);
    const double mass = masses(p.liquid, i);
    speedMax = std::max(speedMax, std::sqrt(speed2));
    kinetic += 0.5 * mass * speed2;
    momentum += vi * mass;
    if (!std::isfinite(xi.x + xi.y + xi.z + vi.x + vi.y + vi.z))
    {
      finite = 0;
    }
  }
  Statistics s;
  s.averageNeighbors = std::numeric_limits<double>::quiet_NaN();
  double count = 0;
  for (const std::vector<double>& r : allGather(communicator,
         { double(p.x.size()), errorSum, errorMax, speedMax, kinetic, momentum.x, momentum.y,
           momentum.z, finite }))
  {
    count += r[0];
    s.averageDensityError += r[1];
    s.maxDensityError = std::max(s.maxDensityError, r[2]);
    s.maxSpeed = std::max(s.maxSpeed, r[3]);
    s.kineticEnergy += r[4];
    s.momentum += Vec3d{ r[5], r[6], r[7] };
    s.finite = s.finite && r[8] != 0;
  }
  s.particles = static_cast<std::size_t>(count);
  s.averageDensityError = count > 0 ? s.averageDensityError / count : 0.0;
  return s;
}

template <class Real>
Health reduceHealth(
  Communicator& communicator, const Parameters& parameters, const ConstHostParticles<Real>& p)
{
  double maxDensity = 0.0;
  std::vector<std::uint64_t> speeds;
  const Health h = scanHealth(parameters, p, &maxDensity, &speeds);
  // Every rank must reach the same verdict, or one would stop while the others wait for it.
  // The speeds' histograms travel along (exact as doubles) and add into the ranks' robust speed.
  std::vector<double> mine = { double(h.nonFinite), double(h.outside), h.maxSpeed, maxDensity,
    double(h.firstBadId) };
  mine.insert(mine.end(), speeds.begin(), speeds.end());
  Health all;
  std::vector<double> counts(kSpeedBins, 0.0);
  for (const std::vector<double>& r : allGather(communicator, mine))
  {
    for (int b = 0; b < kSpeedBins; ++b)
    {
      counts[static_cast<std::size_t>(b)] += r[5 + static_cast<std::size_t>(b)];
    }
    all.nonFinite += static_cast<std::size_t>(r[0]);
    all.outside += static_cast<std::size_t>(r[1]);
    all.maxSpeed = std::max(all.maxSpeed, r[2]);
    all.maxDensityError = std::max(all.maxDensityError, r[3] / parameters.restDensity - 1.0);
    if (all.firstBadId < 0 && r[4] >= 0)
    {
      all.firstBadId = static_cast<std::int64_t>(r[4]);
    }
  }
  all.maxDensityError = std::max(all.maxDensityError, 0.0);
  all.robustSpeed = robustSpeed(counts.data(), all.maxSpeed);
  return all;
}

// Collective: the particle count of each rank.
inline std::vector<std::uint64_t> countsPerRank(Communicator& communicator, std::size_t mine)
{
  std::vector<std::uint64_t> counts;
  for (const std::vector<double>& r : allGather(communicator, { double(mine) }))
  {
    counts.push_back(static_cast<std::uint64_t>(r[0]));
  }
  return counts;
}

} // namespace pbf::distributed
