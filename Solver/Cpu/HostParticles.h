// What the steppers that keep their particles in host arrays share (CpuStepper and
// distributed::SubdomainStepper): the state as a Snapshot, out and in, and the health scan.
#pragma once

#include "LiquidDensities.h"
#include "Outflow.h"
#include "Parameters.h"
#include "ParticleChecks.h"
#include "SpeedHistogram.h"
#include "Stepper.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace pbf
{

// The arrays that are the state between steps (everything else is recomputed by the next step),
// to fill (HostParticles) or to read (ConstHostParticles).
template <class Real>
struct HostParticles
{
  std::vector<Vec3<Real>>& x;
  std::vector<Vec3<Real>>& v;
  std::vector<Real>& density;
  std::vector<Real>& lambda;
  std::vector<Real>& pressure;
  std::vector<std::int64_t>& id;
  std::vector<std::uint8_t>& liquid; // empty where the scene names no liquids
};

template <class Real>
struct ConstHostParticles
{
  const std::vector<Vec3<Real>>& x;
  const std::vector<Vec3<Real>>& v;
  const std::vector<Real>& density;
  const std::vector<Real>& lambda;
  const std::vector<Real>& pressure;
  const std::vector<std::int64_t>& id;
  const std::vector<std::uint8_t>& liquid;
};

template <class Real, class Out>
void copyToSnapshot(
  const Parameters& parameters, const ConstHostParticles<Real>& p, Snapshot<Out>& out)
{
  const std::size_t n = p.x.size();
  out.position.resize(n);
  out.velocity.resize(n);
  out.density.resize(n);
  out.lambda.resize(n);
  out.pressure.resize(n);
  out.id = p.id;
  out.liquid = p.liquid;
  for (std::size_t i = 0; i < n; ++i)
  {
    out.position[i] = Vec3<Out>::from(p.x[i]);
    out.velocity[i] = Vec3<Out>::from(p.v[i]);
    out.density[i] = static_cast<Out>(p.density[i]);
    out.lambda[i] = static_cast<Out>(p.lambda[i]);
    out.pressure[i] = static_cast<Out>(p.pressure[i]);
  }
  toLiquidDensities(parameters, out.liquid, out.density);
}

// Throws InvalidInput for a snapshot of the other precision or with arrays of different lengths.
template <class Real, class In>
void loadFromSnapshot(
  const Parameters& parameters, const Snapshot<In>& state, const HostParticles<Real>& p)
{
  if (sizeof(In) != sizeof(Real))
  {
    throw InvalidInput(std::string("checkpoint precision = ") +
      (sizeof(In) == sizeof(float) ? "single" : "double") + ": the stepper runs in " +
      (sizeof(Real) == sizeof(float) ? "single" : "double") + " precision");
  }
  const std::size_t n = state.id.size();
  if (state.position.size() != n || state.velocity.size() != n || state.density.size() != n ||
    state.lambda.size() != n || state.pressure.size() != n)
  {
    throw InvalidInput("checkpoint arrays differ in length (" + std::to_string(n) + " ids)");
  }
  checkLiquids(parameters, state.liquid, n, "checkpoint");
  p.x.resize(n);
  p.v.resize(n);
  p.density.resize(n);
  p.lambda.resize(n);
  p.pressure.resize(n);
  p.id = state.id;
  p.liquid = state.liquid;
  if (!parameters.liquids.empty() && p.liquid.empty())
  {
    p.liquid.assign(n, 0);
  }
  for (std::size_t i = 0; i < n; ++i)
  {
    p.x[i] = Vec3<Real>::from(state.position[i]);
    p.v[i] = Vec3<Real>::from(state.velocity[i]);
    p.density[i] = static_cast<Real>(state.density[i]);
    p.lambda[i] = static_cast<Real>(state.lambda[i]);
    p.pressure[i] = static_cast<Real>(state.pressure[i]);
  }
  fromLiquidDensities(parameters, p.liquid, p.density);
}

// Removes the particles whose position lies in an outflow zone, the others kept in their order
// (the next step's sort is stable, so the steps that follow do not depend on where a hole was);
// returns how many went. Density, lambda and pressure are the step's, the removed ones counted.
template <class Real>
std::size_t removeInside(const OutflowZones<Real>& zones, const HostParticles<Real>& p)
{
  const std::size_t n = p.x.size();
  const bool liquids = !p.liquid.empty();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    if (zones.contains(p.x[i]))
    {
      continue;
    }
    p.x[kept] = p.x[i];
    p.v[kept] = p.v[i];
    p.density[kept] = p.density[i];
    p.lambda[kept] = p.lambda[i];
    p.pressure[kept] = p.pressure[i];
    p.id[kept] = p.id[i];
    if (liquids)
    {
      p.liquid[kept] = p.liquid[i];
    }
    ++kept;
  }
  p.x.resize(kept);
  p.v.resize(kept);
  p.density.resize(kept);
  p.lambda.resize(kept);
  p.pressure.resize(kept);
  p.id.resize(kept);
  p.liquid.resize(liquids ? kept : 0);
  return n - kept;
}

// The divergence check's scan (Stepper::health) of the particles held here. maxDensity, when
// given, receives the largest density itself, and speedCounts (kSpeedBins) the speeds' histogram,
// for a caller that still has to combine them with others' (the ranks of a decomposed run).
template <class Real>
Health scanHealth(const Parameters& parameters, const ConstHostParticles<Real>& p,
  double* maxDensity, std::vector<std::uint64_t>* speedCounts = nullptr)
{
  Health h;
  const Box& d = parameters.domain;
  const double slack = parameters.particleSpacing; // as checkBatch allows
  double largest = 0.0;
  std::vector<std::uint64_t> counts(kSpeedBins, 0);
  for (std::size_t i = 0; i < p.x.size(); ++i)
  {
    const Vec3d x = Vec3d::from(p.x[i]);
    const Vec3d v = Vec3d::from(p.v[i]);
    if (!(std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z) && std::isfinite(v.x) &&
          std::isfinite(v.y) && std::isfinite(v.z)))
    {
      h.firstBadId = h.firstBadId < 0 ? p.id[i] : h.firstBadId;
      ++h.nonFinite;
      continue;
    }
    if (x.x < d.min.x - slack || x.y < d.min.y - slack || x.z < d.min.z - slack ||
      x.x > d.max.x + slack || x.y > d.max.y + slack || x.z > d.max.z + slack)
    {
      h.firstBadId = h.firstBadId < 0 ? p.id[i] : h.firstBadId;
      ++h.outside;
    }
    h.maxSpeed = std::max(h.maxSpeed, length(v));
    // The bins of speed^2 as the GPU's scan has it (DeviceHealth.h): the same double.
    ++counts[static_cast<std::size_t>(speedBin(v.x * v.x + v.y * v.y + v.z * v.z))];
    // NaN densities compare false and are left out; they make non-finite positions next step.
    largest = std::max(largest, static_cast<double>(p.density[i]));
  }
  h.maxDensityError = std::max(largest / parameters.restDensity - 1.0, 0.0);
  h.robustSpeed = robustSpeed(counts.data(), h.maxSpeed);
  if (maxDensity)
  {
    *maxDensity = largest;
  }
  if (speedCounts)
  {
    *speedCounts = std::move(counts);
  }
  return h;
}

} // namespace pbf
