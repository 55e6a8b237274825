// Everything that decides how the fluid behaves, in SI units. Where the fluid is lives in Scene.h.
#pragma once

#include "Vec3.h"

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbf
{

// A parameter or scene value that cannot be simulated. what() names the field and the value.
class InvalidInput : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

// Standard gravity [m/s^2]: the unit of the tensile term's strength (Parameters::sCorrK).
constexpr double kStandardGravity = 9.80665;
// The Jacobi gain (LatticeCalibration::jacobiGain) that the relaxation of lambda brings every
// smoothing ratio down to: 2, where the most amplified pattern no longer grows. Measured on a
// 120-layer column at rest (0.2 s): 2.8 (omega = 1 at h = 2 s) boils at 1.5 m/s, 2.0 at 0.7, 1.0
// at 0.4 for twice the iterations; h = 3 s blows up within 24 steps with omega = 1.
constexpr double kJacobiGainTarget = 2.0;
// The largest XSPH blend per step (nu dt / (beta h^2)) that explicit smoothing keeps stable.
constexpr double kMaxXsphBlend = 0.5;

// The most liquids one scene holds: a particle's liquid is a byte, and each liquid's constants
// travel with the step's coefficients (Equations.h) into every kernel.
constexpr int kMaxLiquids = 8;

// One liquid of a scene that holds several (Scene's "liquids", Data/README.md).
struct Liquid
{
  std::string name;
  double restDensity = 1000.0;   // its rho_0 [kg/m^3]
  // Its alpha, as Parameters::xsphViscosity; NaN (unset): Parameters::xsphViscosity.
  double xsphViscosity = std::numeric_limits<double>::quiet_NaN();
  // Its sigma [N/m], as Parameters::surfaceTension; NaN (unset): Parameters::surfaceTension.
  double surfaceTension = std::numeric_limits<double>::quiet_NaN();
  // Its contact angle with the domain's walls [degrees], as Parameters::contactAngle; NaN
  // (unset): Parameters::contactAngle.
  double wallContactAngle = std::numeric_limits<double>::quiet_NaN();
};

struct Box
{
  Vec3d min{ 0, 0, 0 };
  Vec3d max{ 1, 1, 1 };
};

// How the solver's step is chosen (Simulation.h).
enum class TimeStepping
{
  Fixed,     // every step is timeStep
  Automatic, // each step follows the CFL condition, at most timeStep (Simulation::nextTimeStep)
};

struct Parameters
{
  // Fluid
  double restDensity = 1000.0;    // rho_0 [kg/m^3], water
  double particleSpacing = 0.02;  // lattice spacing s of the initial fluid [m]
  double smoothingRatio = 2.0;    // h / s; the support radius h of poly6 and spiky

  // Several liquids (the scene's "liquids"); empty: one, of restDensity and xsphViscosity. A
  // particle's liquid is its index here. Every particle has the volume V = m / restDensity that
  // the lattice calibrates (restDensity is then the reference, not a liquid's), and the mass
  // V rho_l of its liquid's rest density. The constraint is on the number density
  // sum_j W_ij (Solenthaler and Pajarola 2008's density contrast), the same for every liquid, so
  // each liquid is held at its own rest density and an interface is not smeared; a particle's
  // correction is weighted by its inverse mass, so buoyancy follows (Equations.h, liquidWeight).
  std::vector<Liquid> liquids;

  // Solver (Macklin & Mueller 2013)
  int solverIterations = 40;    // constraint projections per step: the most when adaptive (the
                                // default), every step's count when densityErrorTolerance is 0
  // Adaptive mode when > 0: after the first projection, iterate until the mean compression
  // max(rho_i / rho_0 - 1, 0) is at or below this many percent (with several liquids, each
  // liquid's mean over its own particles), or solverIterations are done.
  // 0: always solverIterations (the paper's fixed count).
  double densityErrorTolerance = 0.2;
  // Adaptive mode: iterate also while any particle is compressed by more than this many percent
  // (0: the mean alone decides). The mean alone lets an impact squeeze single particles by 20 %
  // at one projection per step (the dam break at 1.15M particles); the cap still bounds the cost.
  double maxDensityErrorTolerance = 5.0;
  // Chebyshev acceleration of the projections (Chebyshev.h): the estimate rho in [0, 1) of the
  // spectral radius of one Jacobi projection; 0: plain Jacobi (the paper). The projections from
  // the second on blend each Jacobi result with the positions two projections back, so a deep
  // column needs fewer of them for the same tolerance; an estimate above the true radius
  // amplifies the patterns beyond it (a 120-layer column boils at 0.9).
  double chebyshevRho = 0.0;
  // epsilon of eq. 11 is in units of the bulk denominator of eq. 11 (see LatticeCalibration): it
  // softens the constraint by that fraction at any h, s and rho_0 (the paper's value assumes its
  // own unit system). It is a regularisation for particles with few neighbours, not a stiffness:
  // a relative softening per projection has the same effect at any time step.
  double relaxation = 0.01;     // epsilon of eq. 11
  // The tensile term s_corr (eq. 13) as an artificial-pressure acceleration: once per step, in the
  // first projection, each pair closer than h pushes apart by k g0 (W / W(delta_q))^n scaled so
  // that a particle on the flat free surface of the rest lattice is pushed outward by sCorrK x
  // standard gravity g0 = 9.80665 m/s^2 (LatticeCalibration::tensileSurfacePush). A displacement
  // of a dt^2, not a fixed push per iteration: the same acceleration at any dt, s, h / s and
  // number of iterations. Below 1 it cannot lift a surface against gravity.
  double sCorrK = 0.1;          // k of eq. 13, in units of g0
  double sCorrN = 4.0;          // n of eq. 13 (paper: 4)
  double sCorrDeltaQ = 0.2;     // delta_q of eq. 13 as a fraction of h (paper: 0.1..0.3)
  // XSPH (eq. 17) as an artificial viscosity alpha: nu = alpha h v_scene [m^2/s] (xsphNu()), the
  // form of SPH's artificial viscosity (alpha h c), and each step blends c = nu dt / (beta h^2)
  // of the neighbours' velocity (LatticeCalibration::xsphSecondMoment: the blend whose smoothing
  // approximates nu laplace(v)). So halving dt halves the blend per step and keeps the smoothing
  // per second; at the CFL step the blend per step is the same at every spacing and h / s (about
  // 4 alpha), while nu itself vanishes as h does, so finer runs converge. It damps the
  // particle-scale velocity noise of the Jacobi projections: alone, 0.05 keeps a 120-layer column
  // at rest, where 0.001 (the paper's c = 0.01 at 240 steps/s) lets it boil at 1-2 m/s; by
  // default a quarter of that, with xsphHyperViscosity doing the rest of the particle-scale work.
  double xsphViscosity = 0.0125;
  // XSPH's sum smoothed once more (a bi-Laplacian, hyperviscous filter), alpha_4: each step takes
  // c_4 S(S(v)) off the velocity, S the sum of eq. 17 and c_4 = nu_4 dt / (beta h^2) with
  // nu_4 = alpha_4 h v_scene (xsphHyperNu()), the blend of xsphViscosity's form. On the particle
  // scale, where the Jacobi projections leave their noise, it damps as XSPH does at the same
  // alpha; a flow on a scale L >> h it damps by about (h / L)^4 instead of (h / L)^2, so a bore
  // or a collapsing column is slowed far less. 0: off (the paper's XSPH alone). The default,
  // 0.05 with xsphViscosity 0.0125, holds the 120-layer column at rest as XSPH 0.05 alone does
  // and slows a bore, a surge front or an impact jet less (Documentation/Validation.md).
  double xsphHyperViscosity = 0.05;
  double vorticityEpsilon = 0.01; // epsilon of eq. 16 [m/s]: confinement acceleration per |omega|
  // Surface tension sigma [N/m] (0.072 is water against air; 0: off): Brackbill's continuum
  // surface force, sigma times the curvature of the fluid's smoothed colour field, on the
  // particles of its surface (SurfaceTension.h). It is felt on the scale of the capillary length
  // sqrt(sigma / (rho g)), 2.7 mm for water on Earth: a droplet, a thin jet, a film, not a tank
  // of spacing 1 cm.
  double surfaceTension = 0.0;
  // Adhesion as the contact angle theta [degrees] the liquid's surface makes with the walls
  // (Young's force at the contact line, SurfaceTension.h's youngForce): 90, the default, is
  // neutral (the walls' mirror images alone); less wets the wall, more beads up on it. Felt
  // with surface tension only.
  double contactAngle = 90.0;
  bool unilateral = true;       // clamp C_i at 0: a free surface is not pulled together
  bool mirrorWalls = true;      // walls mirror the fluid near them (Equations.h, WallMirrors)
  // The mirror walls' loads summed with the solids' (StepReport::loads, the tank's rows of the
  // Diagnostics): a CPU step barely notices, a GPU step pays about an eighth
  // (Documentation/Performance.md), so they are asked for.
  bool tankLoads = false;
  // Solids push by their true shape: each solid's grid carries a shape map (Scene/ShapeMap.h)
  // that corrects the flat-wall table near its edges and corners; off: every solid is its
  // tangent plane (exact on flat faces only, and no map to build at the run's start).
  bool exactBoundaries = true;
  // Whether a step sums the six mirror walls' loads.
  bool sumsWallLoads() const { return mirrorWalls && tankLoads; }
  // Friction of the walls and solids, phi in [0, 1]: 0 lets the fluid slide along them
  // (free-slip), 1 holds it as the fluid's own XSPH viscosity holds the fluid (no-slip at that
  // viscosity): a wall's image of a particle moves with its tangential velocity scaled by
  // 1 - 2 phi (Equations.h, wallFrictionImage). The box's walls take part when mirrorWalls is on.
  double wallFriction = 0.0;
  Vec3d gravity{ 0.0, -9.81, 0.0 };

  // Time
  TimeStepping timeStepping = TimeStepping::Automatic;
  // Fixed: every solver step dt [s]. Automatic: the largest step (MaxTimeStep in the plugin).
  double timeStep = 1.0 / 240.0;
  // Automatic: dt = cflNumber s / v, v the larger of the speeds' 99.9th percentile and the
  // scene's fall speed (Simulation::nextTimeStep says why); also dt <= s / v_max, dt <=
  // cflNumber sqrt(s / |g|) and the XSPH diffusion limit.
  double cflNumber = 0.4;

  Box domain;

  // The scene's speed scale v_scene = sqrt(v0^2 + 2 |g| L) [m/s], v0 the fastest initial or
  // emitted speed and L the domain's extent along gravity. Simulation fills it in from the scene;
  // 0 means sqrt(2 |g| L) from the domain alone (sceneSpeed()).
  double sceneSpeedHint = 0;

  double smoothingLength() const { return smoothingRatio * particleSpacing; }
  double sceneSpeed() const;
  double xsphNu() const { return xsphViscosity * smoothingLength() * sceneSpeed(); } // [m^2/s]
  double xsphHyperNu() const { return xsphHyperViscosity * smoothingLength() * sceneSpeed(); }
  // Liquid l's rest density and XSPH nu (restDensity and xsphNu() when there are no liquids).
  double liquidRestDensity(int l) const;
  double liquidXsphNu(int l) const;
  int liquidCount() const { return liquids.empty() ? 1 : static_cast<int>(liquids.size()); }
  // The largest XSPH nu of the liquids: what bounds the explicit smoothing's step.
  double largestXsphNu() const;
  // Liquid l's sigma (surfaceTension when there are no liquids or l's is unset), and the largest.
  double liquidSurfaceTension(int l) const;
  double largestSurfaceTension() const;
  // Liquid l's contact angle with the walls [degrees] (contactAngle when unset), and whether
  // any liquid's differs from the neutral 90 degrees.
  double liquidWallContactAngle(int l) const;
  bool wallAdhesion() const;

  // Throws InvalidInput naming the first bad field and its value.
  void validate() const;
};

// Throws InvalidInput, naming the parameter, when a constant the solver derives from p does not
// fit Real (Coefficients<Real>::make calls it): it overflows, or underflows below the smallest
// normal number (a relaxation that rounds to 0 turns an isolated particle's lambda into 0 / 0),
// or the spacing is too fine for Real to resolve at the domain's coordinates. validate() first.
template <class Real>
void validatePrecision(const Parameters& p);

// What a particle inside the initial cubic lattice sees, computed once from the parameters.
struct LatticeCalibration
{
  // The mass that makes the lattice read exactly rho_0 with poly6: summing over a lattice at
  // h = 2 s reads about 1% high with m = rho_0 s^3.
  double mass = 0;
  // sum_j |grad_{p_j} C_i|^2 at rest [1/m^2]: the denominator of eq. 11 in the bulk. Its inverse
  // is the natural unit of lambda, used to make epsilon independent of h and rho_0.
  double gradientSum = 0;
  // sum_j (m / rho_0) (W_ij / W(delta_q))^n (-grad W_ij) . n over the sites below a particle on a
  // flat free surface of the lattice (n its outward normal) [1/m]: the tensile term's push there
  // per unit of s_corr's coefficient. k g0 dt^2 over it makes the push k g0 dt^2.
  double tensileSurfacePush = 0;
  // beta h^2 = (1/6) sum_j (m / rho_0) W_ij |r_ij|^2 [m^2]: the XSPH sum of a smooth velocity
  // field is beta h^2 laplace(v), so a blend c per step is a viscosity c beta h^2 / dt.
  double xsphSecondMoment = 0;
  // G = -(1/3) sum_j (m / rho_0) r_ij . grad W_ij: SPH's gradient of a linear field on the
  // lattice is G times the exact one (G = 1 for the continuous kernel). A pressure that holds
  // the fluid up against gravity through the discrete gradient is 1 / G times rho_0 g d, so
  // the reported pressure is G times the corrections' (Equations.h's recordPressure).
  double gradientMoment = 0;
  // sum over the layers k = 0, 1, ... below a flat free surface of the lattice of
  // (V / s^2) |grad c_k| w_k (SurfaceTension.h: c the colour, w its surface weight): the share of
  // the colour's drop from 1 to 0 that the particles carry. The rest lies outside the fluid,
  // where there are none (0.53 at h = 2 s), so the surface force is divided by it.
  double surfaceColour = 0;
  // The Jacobi projection's largest gain on the lattice, max over wave vectors k of
  // |G(k)|^2 / D, G(k) = sum_j grad W_ij sin(k . r_ij), D = sum_j |grad W_ij|^2: a correction
  // pattern of wave vector k is multiplied by 1 - omega |G(k)|^2 / D per projection, so omega
  // times this must stay below 2. It grows with the neighbours: 2.8 at h = 2 s, 6.7 at h = 3 s.
  double jacobiGain = 0;
  // omega, the factor on lambda (eq. 11): kJacobiGainTarget / jacobiGain, at most 1, so that
  // every smoothing ratio has the same margin against the projection's overshoot.
  double jacobiRelaxation = 1;
};
LatticeCalibration calibrateLattice(const Parameters& p);

inline double calibratedParticleMass(const Parameters& p)
{
  return calibrateLattice(p).mass;
}

// Each liquid's particle mass [kg], the calibrated volume m / restDensity times its rest density;
// slots beyond the liquids hold liquid 0's.
struct LiquidMasses
{
  explicit LiquidMasses(const Parameters& p)
  {
    const double m = calibratedParticleMass(p);
    for (int l = 0; l < kMaxLiquids; ++l)
    {
      of[l] = m * (p.liquidRestDensity(l < p.liquidCount() ? l : 0) / p.restDensity);
    }
  }
  // The mass of particle i of a liquid array (empty: liquid 0).
  double operator()(const std::vector<std::uint8_t>& liquid, std::size_t i) const
  {
    return liquid.empty() ? of[0] : of[liquid[i]];
  }
  double of[kMaxLiquids];
};

std::string describe(const Parameters& p);

} // namespace pbf
