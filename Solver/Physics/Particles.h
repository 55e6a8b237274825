// Particles as plain data: what a scene hands a stepper (ParticleBatch) and what a stepper hands
// back (Snapshot, or the caller's arrays through a SnapshotView). Below the stepper interface, so
// that scenes and steppers share them without depending on each other.
#pragma once

#include "Vec3.h"

#include <cstdint>
#include <vector>

namespace pbf
{

// Particles as the host sees them, in the stepper's current (cell-sorted) order: follow a
// particle across steps by its id, not by its index.
template <class Real>
struct Snapshot
{
  std::vector<Vec3<Real>> position;
  std::vector<Vec3<Real>> velocity;
  std::vector<Real> density; // rho_i from the last constraint evaluation [kg/m^3], of its liquid
  std::vector<Real> lambda;  // lambda_i from the last constraint evaluation
  // p_i [Pa]: the pressure the corrections stand for (Equations.h's recordPressure), a mean
  // over the steps since the mean began (Stepper::setTimeStep; Simulation's frame); 0 before a
  // particle's first step.
  std::vector<Real> pressure;
  std::vector<std::int64_t> id;
  // Each particle's liquid, its index in Parameters::liquids; empty where the scene names none.
  std::vector<std::uint8_t> liquid;
};

// Caller-owned host arrays of size() particles laid out as a Snapshot's (a Vec3 is three packed
// reals, as VTK's interleaved arrays are), for Stepper::readInto. A null pointer skips the array.
template <class Real>
struct SnapshotView
{
  Vec3<Real>* position = nullptr;
  Vec3<Real>* velocity = nullptr;
  Real* density = nullptr;
  Real* lambda = nullptr;
  Real* pressure = nullptr;
  std::int64_t* id = nullptr;
  std::uint8_t* liquid = nullptr; // left as it is where the scene names no liquids
};

// New particles (emitters); ids are given by the caller so they stay unique across backends.
struct ParticleBatch
{
  std::vector<Vec3d> position;
  std::vector<Vec3d> velocity;
  std::vector<std::int64_t> id;
  // Each particle's liquid (Parameters::liquids); empty: liquid 0 for all.
  std::vector<std::uint8_t> liquid;
};

} // namespace pbf
