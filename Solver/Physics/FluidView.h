// The step's coefficients in the backend's precision (Coefficients, and StepTime for what depends
// on dt) and the particle arrays a stage reads and writes (FluidView), with what the stages read
// through a view for one particle: its liquid's weight, its volume and |omega|.
#pragma once

#include "Boundary.h"
#include "Grid.h"
#include "HostDevice.h"
#include "Kernels.h"
#include "Parameters.h"
#include "Vec3.h"

#include <cmath>
#include <cstdint>

namespace pbf
{

// Parameters in the precision of the backend, with the derived constants computed once.
template <class Real>
struct Coefficients
{
  Kernels<Real> kernels;
  Real mass;                // m, calibrated so the initial lattice reads rho_0
  Real pressureScale;       // rho_0 G: lambda / dt^2 to pressure (recordPressure)
  Real inverseRestDensity;  // 1 / rho_0
  Real massOverRho0;        // m / rho_0: scales the constraint gradient (eq. 8)
  Real relaxation;          // epsilon (eq. 11) times the bulk denominator
  Real jacobiRelaxation;    // omega on lambda (LatticeCalibration::jacobiRelaxation)
  Real sCorrN;              // n (eq. 13)
  Real inverseWDeltaQ;      // 1 / W(delta_q) (eq. 13)
  Real vorticityEpsilon;
  Vec3<Real> gravity;
  Vec3<Real> boxMin, boxMax;
  bool unilateral;
  bool mirrorWalls;
  Real wallFriction;        // phi of wallFrictionImage: 0 free-slip, 1 no-slip
  bool xsphHyper;           // alpha_4 > 0: the confinement pass reads the neighbours' XSPH sums
  bool surfaceTension;      // a surface tension > 0: the confinement pass adds its force
  bool wallAdhesion;        // a liquid's contact angle with the walls is not 90 degrees
  Real colourScale;         // 6 K of poly6 W = K (h^2 - r^2)^3 (SurfaceTension.h)
  Real inverseH2;           // 1 / h^2

  // Throws InvalidInput when a constant does not fit Real (validatePrecision).
  static Coefficients make(const Parameters& p)
  {
    validatePrecision<Real>(p);
    const double h = p.smoothingLength();
    const LatticeCalibration lattice = calibrateLattice(p);
    const double m = lattice.mass;
    Coefficients c;
    c.kernels = Kernels<Real>::make(h);
    c.mass = static_cast<Real>(m);
    c.pressureScale = static_cast<Real>(p.restDensity * lattice.gradientMoment);
    c.inverseRestDensity = static_cast<Real>(1.0 / p.restDensity);
    c.massOverRho0 = static_cast<Real>(m / p.restDensity);
    c.relaxation = static_cast<Real>(p.relaxation * lattice.gradientSum);
    c.jacobiRelaxation = static_cast<Real>(lattice.jacobiRelaxation);
    c.sCorrN = static_cast<Real>(p.sCorrN);
    const auto k64 = Kernels<double>::make(h);
    const double dq = p.sCorrDeltaQ * h;
    c.inverseWDeltaQ = static_cast<Real>(1.0 / k64.poly6(dq * dq));
    c.vorticityEpsilon = static_cast<Real>(p.vorticityEpsilon);
    c.gravity = Vec3<Real>::from(p.gravity);
    c.boxMin = Vec3<Real>::from(p.domain.min);
    c.boxMax = Vec3<Real>::from(p.domain.max);
    c.unilateral = p.unilateral;
    c.mirrorWalls = p.mirrorWalls;
    c.wallFriction = static_cast<Real>(p.wallFriction);
    c.xsphHyper = p.xsphHyperViscosity > 0;
    c.surfaceTension = p.largestSurfaceTension() > 0;
    c.wallAdhesion = p.wallAdhesion() && p.mirrorWalls;
    c.colourScale = static_cast<Real>(6.0 * k64.poly6Scale);
    c.inverseH2 = static_cast<Real>(1.0 / (h * h));
    return c;
  }
};

// What depends on the step's size dt, which the automatic time stepping changes from step to step.
// The stages read it through a pointer (FluidView::time), so that a GPU step captured once as a
// graph reads the current values from device memory.
template <class Real>
struct StepTime
{
  Real dt;        // [s]
  Real inverseDt; // 1 / dt
  // s_corr's coefficient for this step (eq. 13 as an acceleration): k g0 dt^2 over the lattice's
  // surface push, so that a flat free surface is pushed by k g0 dt^2 in the step.
  Real tensile;
  Real xsph;      // XSPH blend c of eq. 17 for this step: nu dt / (beta h^2), Parameters::xsphNu
  Real xsphHyper; // the bi-Laplacian blend c_4: nu_4 dt / (beta h^2), Parameters::xsphHyperNu
  // Per liquid (Parameters::liquids), indexed by a particle's liquid: its XSPH blend
  // (Parameters::liquidXsphNu; c_4 is shared, xsph is liquid 0's), w_l = restDensity / rho_l,
  // its inverse mass in units of the reference's (liquidWeight), and rho_l / restDensity. They
  // live here, in the stepper's memory read through FluidView::time, rather than in the
  // Coefficients a GPU kernel takes as its argument: a kernel's argument indexed at run time is
  // copied to local memory, which made the correction pass spill (+2 to +4 % a step at 1M
  // particles on an H100, one liquid or two).
  Real liquidXsph[kMaxLiquids];
  Real liquidWeight[kMaxLiquids];
  Real liquidDensityRatio[kMaxLiquids];
  // Surface tension (SurfaceTension.h) per liquid l: dt sigma_l / (rho_l surfaceColour), the
  // velocity its force density per unit sigma gives in the step (LatticeCalibration's
  // surfaceColour: the share of the colour's drop that particles carry). Zero without it.
  Real tension[kMaxLiquids];
  // Adhesion per liquid: the cosine of its contact angle with the walls (SurfaceTension.h).
  Real wallCos[kMaxLiquids];
  // The step's pressure joins a running mean over time (recordPressure): the mean before the step
  // (over `elapsed` seconds of steps) times pressureKeep = elapsed / (elapsed + dt), plus the
  // step's times pressureWeight = dt / (elapsed + dt). elapsed = 0 starts a new mean.
  Real pressureKeep;
  Real pressureWeight;

  // `elapsed`: the seconds of steps the particles' pressure is a mean over before this step.
  static StepTime make(
    const Parameters& p, const LatticeCalibration& lattice, double dt, double elapsed = 0)
  {
    StepTime t;
    t.dt = static_cast<Real>(dt);
    t.inverseDt = static_cast<Real>(1.0 / dt);
    t.pressureKeep = static_cast<Real>(elapsed / (elapsed + dt));
    t.pressureWeight = static_cast<Real>(dt / (elapsed + dt));
    t.tensile =
      static_cast<Real>(p.sCorrK * kStandardGravity * dt * dt / lattice.tensileSurfacePush);
    // c + c_4 at most kMaxXsphBlend: explicit smoothing beyond it is unstable (a pattern's gain
    // S is at most about 1 on the lattice, so each blend damps, never flips, it). Automatic steps
    // stay below (Simulation::nextTimeStep); a long fixed step scales both down to it.
    // With several liquids, the most viscous one's c + c_4 decides the clamp for all of them.
    const double c4 = p.xsphHyperNu() * dt / lattice.xsphSecondMoment;
    const double largest = p.largestXsphNu() * dt / lattice.xsphSecondMoment;
    const bool clamped = largest + c4 > kMaxXsphBlend;
    for (int l = 0; l < kMaxLiquids; ++l)
    {
      const double c = l < p.liquidCount() ? p.liquidXsphNu(l) * dt / lattice.xsphSecondMoment : 0.0;
      t.liquidXsph[l] = static_cast<Real>(clamped ? kMaxXsphBlend * (c / (largest + c4)) : c);
    }
    for (int l = 0; l < kMaxLiquids; ++l)
    {
      const bool named = l < p.liquidCount();
      t.liquidWeight[l] = static_cast<Real>(named ? p.restDensity / p.liquidRestDensity(l) : 1.0);
      t.liquidDensityRatio[l] =
        static_cast<Real>(named ? p.liquidRestDensity(l) / p.restDensity : 1.0);
    }
    for (int l = 0; l < kMaxLiquids; ++l)
    {
      t.tension[l] = static_cast<Real>(
        l < p.liquidCount()
          ? dt * p.liquidSurfaceTension(l) / (p.liquidRestDensity(l) * lattice.surfaceColour)
          : 0.0);
    }
    for (int l = 0; l < kMaxLiquids; ++l)
    {
      const double theta =
        (l < p.liquidCount() ? p.liquidWallContactAngle(l) : 90.0) * (3.14159265358979323846 / 180.0);
      t.wallCos[l] = static_cast<Real>(std::cos(theta));
    }
    const double c = p.liquidXsphNu(0) * dt / lattice.xsphSecondMoment;
    t.xsph = static_cast<Real>(clamped ? kMaxXsphBlend * (c / (largest + c4)) : c);
    t.xsphHyper = static_cast<Real>(clamped ? kMaxXsphBlend * (c4 / (largest + c4)) : c4);
    return t;
  }
};

// The particle arrays one stage reads and writes, as raw pointers so the same view works on host
// and device memory.
// Neighbors is what forEachNeighbor walks: GridView<Real> (the 27 cells) on every CPU backend;
// the CUDA backend may pass a view that visits a subset of the same candidates in the same
// order, skipping only particles that cannot be within h (Solver/Cuda/NeighborMasks.h).
template <class Real, class Neighbors = GridView<Real>>
struct FluidView
{
  const Vec3<Real>* x; // positions at the start of the step
  Vec3<Real>* p;       // predicted positions x*_i, corrected by the solver
  Vec3<Real>* v;
  Real* density;
  Real* lambda;
  Vec3<Real>* scratch; // delta p_i during the solve
  Vec3<Real>* omega;   // vorticity
  Vec3<Real>* smoothing; // XSPH's sum of eq. 17 (vorticityAndXsph), which the confinement reads
  // Optional, per particle (null: computed in place for every pair, as the CPU backends do): the
  // SPH volume m / rho_j, written with the last correction, and |omega_j|, written with omega.
  // The vorticity passes read them for every neighbour pair; stored once, they save a division
  // and a square root per pair and give the same bits.
  Real* volume;
  Real* omegaLength;
  // Optional (null: not recorded): the pressure each particle's corrections of this step stand
  // for (recordPressure), written by positionCorrection.
  Real* pressure;
  // Each particle's liquid (Parameters::liquids); null: one liquid, and no particle reads it.
  const std::uint8_t* liquid;
  // grad c_i, the colour field's gradient (SurfaceTension.h), written by the vorticity pass and
  // read for the neighbours by the confinement; null without surface tension.
  Vec3<Real>* colour;
  // grad c averaged over the neighbours (smoothColour), whose directions the curvature is taken
  // from; null without surface tension.
  Vec3<Real>* normal;
  Neighbors grid;
  Coefficients<Real> c;
  const StepTime<Real>* time; // this step's dt and what follows from it
  // The tensile term is a once-per-step push: positionCorrection adds it in the step's first
  // projection only (so its displacement is k g0 dt^2 whatever the number of iterations).
  bool tensile;
  // Solid obstacles (Boundary.h): obstacleCount signed distance grids and the table of the
  // solid's sums. None unless a stepper sets them.
  const DistanceGridView<Real>* obstacles;
  int obstacleCount;
  BoundaryTable<Real> boundary;
};

// w_i = restDensity / rho_l of particle i's liquid l: its inverse mass in units of the reference
// particle's (StepTime::liquidWeight). The constraint C_i is on the number density, the same
// for every liquid; lambda_i's denominator carries w_i (the neighbours' weights taken as its own:
// exact inside a liquid, where a particle's corrections then equal the one-liquid solver's), so
// lambda_i is rho_l / restDensity times the one-liquid lambda, a pressure continuous across an
// interface; and the correction carries w_i, so that m_i delta p_i = m_ref (m / rho_0) sum_j
// (lambda_i + lambda_j + s_corr) grad W_ij is antisymmetric in i and j (momentum is kept) and a
// pressure gradient rho_l g lifts each liquid by its own weight: buoyancy between liquids follows.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE Real liquidWeight(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  return f.liquid ? f.time->liquidWeight[f.liquid[i]] : Real(1);
}

// s_corr between particles i and j as a pressure: scaled by the mean of their liquids' density
// ratios, so that the push it gives (times w_i) is the calibrated acceleration inside any liquid
// (Parameters::sCorrK) and stays antisymmetric across an interface. 1 for one liquid.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE Real tensileDensity(
  std::uint32_t i, std::uint32_t j, const FluidView<Real, Neighbors>& f)
{
  return Real(0.5) *
    (f.time->liquidDensityRatio[f.liquid[i]] + f.time->liquidDensityRatio[f.liquid[j]]);
}

// m / rho_j, stored or computed in place (the same division either way).
template <class Real, class Neighbors>
PBF_HD PBF_INLINE Real volumeOf(std::uint32_t j, const FluidView<Real, Neighbors>& f)
{
  return f.volume ? f.volume[j] : f.c.mass / f.density[j];
}

// |omega_j|, stored or computed in place.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE Real omegaLengthOf(std::uint32_t j, const FluidView<Real, Neighbors>& f)
{
  return f.omegaLength ? f.omegaLength[j] : length(f.omega[j]);
}

} // namespace pbf
