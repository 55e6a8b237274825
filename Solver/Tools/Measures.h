// What the validation measures on a running Simulation, independent of what the solver reports
// about itself.
#pragma once

#include "Simulation.h"

#include <cstdint>

namespace pbf::validation
{

// Density error of the positions the step ended with. The solver's own statistics() reuse the
// densities of the last constraint evaluation, which in fixed-iteration mode comes before the
// last position correction (with 1 iteration: before any correction); this evaluates the
// solver's own density (poly6, mirror walls) afresh on the current positions.
struct DensityError
{
  double average = 0; // mean of max(rho_i / rho_0 - 1, 0)
  double max = 0;     // max of the same
  double averageNeighbors = 0;
};
DensityError densityErrorNow(const Simulation& simulation);

// Sum of m g . (x - x_floor) over the particles [J], height measured along -gravity from the
// domain's lowest corner.
double potentialEnergy(const Simulation& simulation);

// What must never change in a closed run: empty when all holds, else the first violation
// (count, ids 0..N-1 each once, every particle inside the domain box in the solver's precision,
// nothing NaN or infinite).
std::string conservationViolation(const Simulation& simulation, std::int64_t expectedCount);

} // namespace pbf::validation
