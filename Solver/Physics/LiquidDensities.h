// Densities between a stepper's units and each liquid's (Parameters::liquids): what every
// backend's read() and load() convert, so that a snapshot holds what the user sees.
#pragma once

#include "Parameters.h"

#include <cstdint>
#include <vector>

namespace pbf
{

// A stepper keeps rho_i in the reference's units, restDensity times the number density over the
// lattice's (Equations.h, liquidWeight): one compression measure for every liquid. A snapshot
// holds each particle's density in its own liquid's, rho_l / restDensity times that.
// n particles' densities in place, their liquids in `liquid` (read only where the scene names
// liquids).
template <class Real>
void toLiquidDensities(
  const Parameters& parameters, const std::uint8_t* liquid, Real* density, std::size_t n)
{
  if (parameters.liquids.empty())
  {
    return;
  }
  double ratio[kMaxLiquids];
  for (int l = 0; l < parameters.liquidCount(); ++l)
  {
    ratio[l] = parameters.liquidRestDensity(l) / parameters.restDensity;
  }
  for (std::size_t i = 0; i < n; ++i)
  {
    density[i] = static_cast<Real>(density[i] * ratio[liquid[i]]);
  }
}

template <class Real>
void toLiquidDensities(
  const Parameters& parameters, const std::vector<std::uint8_t>& liquid, std::vector<Real>& density)
{
  toLiquidDensities(parameters, liquid.data(), density.data(), density.size());
}

// The inverse of toLiquidDensities, for a snapshot loaded back (the next step recomputes rho_i
// before it reads it, so a rounding here never reaches the particles).
template <class Real>
void fromLiquidDensities(
  const Parameters& parameters, const std::vector<std::uint8_t>& liquid, std::vector<Real>& density)
{
  if (parameters.liquids.empty())
  {
    return;
  }
  for (std::size_t i = 0; i < density.size(); ++i)
  {
    density[i] = static_cast<Real>(
      density[i] * (parameters.restDensity / parameters.liquidRestDensity(liquid[i])));
  }
}

} // namespace pbf
