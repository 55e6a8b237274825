// Everything that decides how the fluid behaves, in SI units. Where the fluid is lives in Scene.h.
#pragma once

#include "Vec3.h"

#include <stdexcept>
#include <string>

namespace pbf
{

// A parameter or scene value that cannot be simulated. what() names the field and the value.
class InvalidInput : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

struct Box
{
  Vec3d min{ 0, 0, 0 };
  Vec3d max{ 1, 1, 1 };
};

struct Parameters
{
  // Fluid
  double restDensity = 1000.0;    // rho_0 [kg/m^3], water
  double particleSpacing = 0.02;  // lattice spacing s of the initial fluid [m]
  double smoothingRatio = 2.0;    // h / s; the support radius h of poly6 and spiky

  // Solver (Macklin & Mueller 2013)
  int solverIterations = 4;     // constraint projections per step (paper: 2-4); the most when
                                // adaptive
  // Adaptive mode when > 0: iterate until the mean compression max(rho_i / rho_0 - 1, 0) is at or
  // below this many percent, or solverIterations are done. 0: always solverIterations.
  double densityErrorTolerance = 0.0;
  // epsilon of eq. 11 and k of eq. 13 are in units of the bulk denominator of eq. 11 (see
  // LatticeCalibration): the paper's values assume its own unit system, these stay meaningful in SI
  // at any h. epsilon = 0.01 softens the bulk constraint by 1%; k = 0.1 makes a pair at delta_q
  // push apart like a 10% compression.
  double relaxation = 0.01;     // epsilon of eq. 11
  double sCorrK = 0.1;          // k of eq. 13 (paper: 0.1)
  double sCorrN = 4.0;          // n of eq. 13 (paper: 4)
  double sCorrDeltaQ = 0.2;     // delta_q of eq. 13 as a fraction of h (paper: 0.1..0.3)
  double xsphC = 0.01;          // c of eq. 17 (paper: 0.01); the sum is weighted by m/rho_j
  double vorticityEpsilon = 0.01; // epsilon of eq. 16 [m/s]: confinement acceleration per |omega|
  bool unilateral = true;       // clamp C_i at 0: a free surface is not pulled together
  bool mirrorWalls = true;      // walls mirror the fluid near them (Equations.h, WallMirrors)
  Vec3d gravity{ 0.0, -9.81, 0.0 };

  // Time
  double timeStep = 1.0 / 240.0; // one solver step dt [s]

  Box domain;

  double smoothingLength() const { return smoothingRatio * particleSpacing; }

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
  // is the natural unit of lambda, used to make epsilon and s_corr independent of h and rho_0.
  double gradientSum = 0;
};
LatticeCalibration calibrateLattice(const Parameters& p);

inline double calibratedParticleMass(const Parameters& p)
{
  return calibrateLattice(p).mass;
}

std::string describe(const Parameters& p);

} // namespace pbf
