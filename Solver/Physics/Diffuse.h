// Diffuse particles: spray, foam and bubbles (Ihmsen et al. 2012, "Unified spray, foam and
// bubbles for particle-based fluids", The Visual Computer 28). Fluid particles emit them from
// three potentials; they are classified by how much fluid surrounds them and advected, never
// acting on the fluid. Written in physical units, so that a threshold or a rate means the same at
// any spacing, smoothing ratio and time step (the paper's are per particle and per step):
// - trapped air: the fluid's relative speed around a particle [m/s], its neighbours' share of
//   |v_ij| (1 - v^_ij . x^_ij) (eq. 2) weighted as an SPH average (sum V_j W_ij |...| / sum V_j W_ij)
//   instead of summed, which grows with the neighbour count;
// - wave crest: the surface's curvature [1/m] where it moves outward (eqs. 4-7);
// - kinetic energy per kilogram, |v|^2 / 2 [J/kg] (eq. 8 without the particle's mass).
// Each potential is clamped to [0, 1] between two thresholds (eq. 1, potential()); a particle of
// volume V emits V I_k (k_ta I_ta + k_wc I_wc) dt diffuse particles in a step (eq. 9 with rates
// per second and cubic metre), rounded up or down at random so that the expected count is that at
// any dt. The random numbers come from a hash of (fluid id, step, draw): the same on every
// backend and rank, whatever order the particles are stored in.
#pragma once

#include "HostDevice.h"
#include "Math.h"
#include "Vec3.h"

#include <cmath>
#include <cstdint>
#include <limits>

namespace pbf
{

// What surrounds a diffuse particle (classifyDiffuse): little fluid, spray; some, foam on the
// surface; much, a bubble under it.
enum class DiffuseKind : std::uint8_t
{
  Spray = 0,
  Foam = 1,
  Bubble = 2
};

// The model's coefficients in the solver's precision (Parameters' diffuse settings, checked).
template <class Real>
struct DiffuseCoefficients
{
  Real trappedAir[2]; // the clamp of the relative speed [m/s]
  Real waveCrest[2];  // of the curvature [1/m]
  Real energy[2];     // of the kinetic energy [J/kg]
  Real trappedAirRate; // k_ta [diffuse particles per second per m^3 of fluid]
  Real waveCrestRate;  // k_wc [same]
  int mostPerStep;     // the most one fluid particle emits in a step
  Real sprayBelow;     // fluid fraction below which a diffuse particle is spray
  Real bubbleAbove;    // above which it is a bubble
};

// What a step gives the diffuse update, made once on the host from dt (makeDiffuseStep). A
// bubble's slip s = v - v_fluid follows ds/dt = -s / tau_b - k_b g and spray's velocity
// dv/dt = -v / tau_s + g; over a step with the fluid's velocity held, exactly
// s' = s e^(-dt/tau_b) - k_b g tau_b (1 - e^(-dt/tau_b)), and likewise for spray, so that a drag
// of time tau acts the same at any dt (the paper's drag is a share per step).
template <class Real>
struct DiffuseStep
{
  Real dt;
  Real bubbleKeep; // e^(-dt / tau_b): the share of a bubble's slip that the step keeps
  Real bubbleRise; // k_b tau_b (1 - e^(-dt / tau_b)) [s]: times -g, what the step adds to it
  Real sprayKeep;  // e^(-dt / tau_s) (1 without air drag)
  Real sprayFall;  // tau_s (1 - e^(-dt / tau_s)) [s] (dt without air drag): times g
};

// The step's factors for dt [s], the bubbles' drag time and the spray's [s] (infinity: no air
// drag) and the buoyancy k_b, in double, then in the solver's precision.
template <class Real>
DiffuseStep<Real> makeDiffuseStep(
  double dt, double bubbleDragTime, double sprayDragTime, double buoyancy)
{
  DiffuseStep<Real> s;
  s.dt = static_cast<Real>(dt);
  const double bubbleLost = -std::expm1(-dt / bubbleDragTime);
  s.bubbleKeep = static_cast<Real>(1.0 - bubbleLost);
  s.bubbleRise = static_cast<Real>(buoyancy * bubbleDragTime * bubbleLost);
  if (sprayDragTime == std::numeric_limits<double>::infinity())
  {
    s.sprayKeep = Real(1);
    s.sprayFall = static_cast<Real>(dt);
  }
  else
  {
    const double sprayLost = -std::expm1(-dt / sprayDragTime);
    s.sprayKeep = static_cast<Real>(1.0 - sprayLost);
    s.sprayFall = static_cast<Real>(sprayDragTime * sprayLost);
  }
  return s;
}

// Eq. 1: the potential of a value I clamped between lo and hi, in [0, 1]; lo < hi.
template <class Real>
PBF_HD PBF_INLINE Real potential(Real value, Real lo, Real hi)
{
  const Real top = value < hi ? value : hi;
  const Real bottom = value < lo ? value : lo;
  return (top - bottom) / (hi - lo);
}

// One neighbour's term of the trapped-air potential (eq. 2, before the weights): |v_ij| times
// (1 - v^_ij . x^_ij), with v_ij = v_i - v_j and x_ij = x_i - x_j; 0 to 2 |v_ij|, largest for
// particles that approach each other.
template <class Real>
PBF_HD PBF_INLINE Real trappedAirTerm(const Vec3<Real>& vij, const Vec3<Real>& xij)
{
  const Real speed2 = dot(vij, vij), distance2 = dot(xij, xij);
  if (!(speed2 > Real(0)) || !(distance2 > Real(0)))
  {
    return Real(0);
  }
  const Real speed = squareRoot(speed2);
  return speed - dot(vij, xij) / squareRoot(distance2);
}

// A 64-bit mix of x (SplitMix64's finaliser, Steele et al. 2014): consecutive inputs give
// unrelated outputs, with integer operations only, so every backend gets the same bits.
PBF_HD PBF_INLINE std::uint64_t mixBits(std::uint64_t x)
{
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// A uniform number in [0, 1) for draw `draw` of fluid particle `id` in step `step`: the top 53
// bits of the hash of the three, exact in double.
PBF_HD PBF_INLINE double uniformDraw(std::uint64_t id, std::uint64_t step, std::uint32_t draw)
{
  const std::uint64_t bits = mixBits(mixBits(mixBits(id) ^ step) ^ draw);
  return static_cast<double>(bits >> 11) * (1.0 / 9007199254740992.0);
}

// How many diffuse particles a fluid particle emits when it is expected to emit `expected` (>= 0)
// this step: the whole part, and one more with the fraction's probability (u uniform in [0, 1)),
// at most `most`. Its mean is `expected` (below the cap), however small dt makes it.
PBF_HD PBF_INLINE int birthCount(double expected, double u, int most)
{
  if (!(expected > 0.0))
  {
    return 0;
  }
  if (expected >= static_cast<double>(most))
  {
    return most;
  }
  const int whole = static_cast<int>(expected);
  const int count = whole + (u < expected - static_cast<double>(whole) ? 1 : 0);
  return count < most ? count : most;
}

// The expected births of a fluid particle of volume `volume` [m^3] with these potentials (each in
// [0, 1]) over dt [s] (eq. 9).
template <class Real>
PBF_HD PBF_INLINE double expectedBirths(const DiffuseCoefficients<Real>& c, double volume,
  Real trappedAir, Real waveCrest, Real energy, double dt)
{
  return volume * static_cast<double>(energy) *
    (static_cast<double>(c.trappedAirRate) * trappedAir +
      static_cast<double>(c.waveCrestRate) * waveCrest) *
    dt;
}

// The kind of a diffuse particle where the fluid fills `fraction` of its surroundings (sum of
// V_j W over the fluid particles and their wall images: 1 inside the fluid, 1/2 on a flat free
// surface, 0 in the air).
template <class Real>
PBF_HD PBF_INLINE DiffuseKind classifyDiffuse(Real fraction, const DiffuseCoefficients<Real>& c)
{
  if (fraction < c.sprayBelow)
  {
    return DiffuseKind::Spray;
  }
  return fraction > c.bubbleAbove ? DiffuseKind::Bubble : DiffuseKind::Foam;
}

// One step of a diffuse particle at x with velocity v, of kind `kind`, where the fluid around it
// moves at `fluid` (its SPH average), under gravity g (DiffuseStep gives the exact factors):
// - spray flies: its velocity relaxes towards still air and falls;
// - foam rides the surface: it moves with the fluid;
// - a bubble rises: its slip relative to the fluid relaxes while buoyancy, k_b times -g, pushes
//   it, towards a slip of -k_b g tau_b.
// The velocity first, then x with the new one, as the fluid's prediction does.
template <class Real>
PBF_HD PBF_INLINE void advanceDiffuse(DiffuseKind kind, Vec3<Real>& x, Vec3<Real>& v,
  const Vec3<Real>& fluid, const Vec3<Real>& gravity, const DiffuseStep<Real>& s)
{
  if (kind == DiffuseKind::Foam)
  {
    v = fluid;
  }
  else if (kind == DiffuseKind::Spray)
  {
    v = v * s.sprayKeep + gravity * s.sprayFall;
  }
  else
  {
    v = fluid + (v - fluid) * s.bubbleKeep - gravity * s.bubbleRise;
  }
  x += v * s.dt;
}

// Room for `room` of the step's `total` candidates (room < total): candidate g (0-based, in the
// order of the births' scan) is kept when floor((g + 1) room / total) > floor(g room / total),
// into slot floor(g room / total). Exactly `room` are kept, one in every total / room, so that the
// cap thins the births everywhere alike instead of keeping the first cells'; integers only.
PBF_HD PBF_INLINE bool keptUnderCap(
  std::uint64_t g, std::uint64_t total, std::uint64_t room, std::uint64_t* slot)
{
  if (room >= total)
  {
    *slot = g;
    return true;
  }
  const std::uint64_t before = g * room / total, after = (g + 1) * room / total;
  *slot = before;
  return after > before;
}

} // namespace pbf
