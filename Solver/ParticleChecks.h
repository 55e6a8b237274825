// Checks on particles handed to a stepper, shared by every backend so that bad input gets the
// same message wherever it is detected.
#pragma once

#include "Parameters.h"
#include "Stepper.h"

namespace pbf
{

// Throws InvalidInput naming the particle and the value: mismatched array sizes, NaN or infinite
// coordinates or velocities, positions outside the domain, more particles than 32-bit indices.
void checkBatch(const Parameters& parameters, const ParticleBatch& batch);

} // namespace pbf
