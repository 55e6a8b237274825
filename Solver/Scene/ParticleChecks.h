// Checks on particles handed to a stepper, shared by every backend so that bad input gets the
// same message wherever it is detected.
#pragma once

#include "Parameters.h"
#include "FluidSource.h"
#include "Particles.h"

#include <string>

namespace pbf
{

// Throws InvalidInput naming the particle and the value: mismatched array sizes, NaN or infinite
// coordinates or velocities, positions outside the domain, more particles than 32-bit indices.
void checkBatch(const Parameters& parameters, const ParticleBatch& batch);

// checkBatch's tests of one particle, `which` naming it (its id, for a part of a fluid that no one
// holds whole): finite, inside the domain, and of a liquid the scene names.
void checkParticle(const Parameters& parameters, std::int64_t which, const Vec3d& x, const Vec3d& v);
void checkLiquid(const Parameters& parameters, std::int64_t which, std::uint8_t liquid);

// Throws InvalidInput when `liquid` holds an index beyond the parameters' liquids, or when its
// length is neither `count` nor (where the scene names no liquids, or for a batch all of
// liquid 0) empty. `what` names the array in the message ("checkpoint", "particle batch").
void checkLiquids(const Parameters& parameters, const std::vector<std::uint8_t>& liquid,
  std::size_t count, const char* what);

// Initial particles the solver would tear apart, named before any work is done (a VTK filter's
// input points, say): packed several times denser than the fluid's one particle per spacing^3
// (the first projection flings them out, and the neighbour search takes minutes on the way), or,
// with mirror walls, lying on a wall (the wall's image doubles them). Throws InvalidInput with the
// numbers and what to set, point k being the k-th of the fluid's positions; `where` names the
// scene whose domain it is. Over a fluid in pieces each piece counts its own occupied cells
// (collective), which holds memory to the piece.
void checkPacking(const Parameters& parameters, const FluidSource& fluid, const std::string& where);
void checkPacking(const Parameters& parameters, const ParticleBatch& batch, const std::string& where);

// checkPacking's walls alone, over a fluid that every rank generates whole (a decomposed run's
// scene: its lattice is one particle per spacing^3 by construction, and counting its cells would
// hold the whole fluid's).
void checkOffWalls(const Parameters& parameters, const FluidSource& fluid, const std::string& where);

// The mean number of particles per occupied cell of side particleSpacing above which
// checkPacking refuses them: a lattice at the spacing has 1, random points at the fluid's density
// about 1.6, a lattice at 0.8 s 2 (which the solver relaxes), at 0.5 s 8 (which it cannot).
constexpr double kMaxParticlesPerCell = 2.5;

} // namespace pbf
