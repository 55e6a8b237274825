#include "ParameterTable.h"

#include <cmath>
#include <limits>
#include <sstream>

namespace pbf
{
namespace
{

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Ranges as the messages read them.
constexpr ValidRange positive{ 0, kInfinity, true, true };
constexpr ValidRange nonNegative{ 0, kInfinity, false, true };
constexpr ValidRange unitInterval{ 0, 1, false, false };
constexpr ValidRange finite{ -kInfinity, kInfinity, true, true };
constexpr ValidRange boolean{ 0, 1, false, false };

// The accessors of a scalar member and of a vector member, as plain function pointers.
#define PBF_SCALAR(member)                                                                       \
  [](const Parameters& p, int) { return static_cast<double>(p.member); },                      \
    [](Parameters& p, int, double value) { p.member = static_cast<decltype(p.member)>(value); }
#define PBF_BOOLEAN(member)                                                                      \
  [](const Parameters& p, int) { return p.member ? 1.0 : 0.0; },                               \
    [](Parameters& p, int, double value) { p.member = value != 0.0; }
#define PBF_VECTOR(member)                                                                       \
  [](const Parameters& p, int c) { return c == 0 ? p.member.x : (c == 1 ? p.member.y : p.member.z); }, \
    [](Parameters& p, int c, double value) {                                                   \
      (c == 0 ? p.member.x : (c == 1 ? p.member.y : p.member.z)) = value;                      \
    }

using T = ParameterType;

std::vector<ParameterSpec> fluidRows()
{
  return {
    { "restDensity", "RestDensity", "rest-density", "Rest Density", "Fluid", "kg/m^3", T::Real,
      positive, 1.0, 100000.0, false, nullptr, "",
      "Rest density rho_0 of the fluid [kg/m^3]; 1000 is water. The particle mass is calibrated "
      "so that the initial lattice reads exactly rho_0.",
      PBF_SCALAR(restDensity) },
    { "particleSpacing", "ParticleSpacing", "spacing", "Particle Spacing", "Fluid", "m", T::Real,
      positive, 0.002, 0.2, false, nullptr, "",
      "Lattice spacing s of the initial fluid [m]. Halving it makes eight times the particles "
      "(the default dam break has about 18000); 0.04 is a quick preview.",
      PBF_SCALAR(particleSpacing) },
    { "smoothingRatio", "SmoothingRatio", "smoothing-ratio", "Smoothing Ratio", "Fluid", "",
      T::Real, { 1, 4, true, false }, 1.1, 4.0, false, nullptr,
      "h / spacing at 1 or less leaves a particle no neighbour within h",
      "Ratio h / s of the kernel support radius h (poly6 and spiky) to the particle spacing. 2 "
      "gives about 30 neighbours.",
      PBF_SCALAR(smoothingRatio) },
  };
}

// The constraint projections.
std::vector<ParameterSpec> solverRows()
{
  return {
    { "solverIterations", "SolverIterations", "iterations", "Solver Iterations", "Solver", "",
      T::Integer, { 1, 1000, false, false }, 1, 200, false, nullptr, "",
      "With Adaptive Iterations on (the default), the most density constraint projections a "
      "solver step may take. Off: the projections of every step (Algorithm 1 of the paper: 2 to "
      "4). More iterations make the fluid less compressible and cost time linearly.",
      PBF_SCALAR(solverIterations) },
    { "densityErrorTolerance", "DensityErrorTolerance", "tolerance", "Density Error Tolerance",
      "Solver", "%", T::Real, nonNegative, 0.001, 10.0, false,
      "enabled_state AdaptiveIterations 1", "",
      "With Adaptive Iterations: the mean compression, in percent of the rest density, at which "
      "a solver step stops projecting (0.2: a fifth of a percent). The diagnostics output shows "
      "the iterations this took per step.",
      PBF_SCALAR(densityErrorTolerance) },
    { "maxDensityErrorTolerance", "MaxDensityErrorTolerance", "max-tolerance",
      "Max Density Error Tolerance", "Solver", "%", T::Real, nonNegative, 0.0, 100.0, true,
      "enabled_state AdaptiveIterations 1", "",
      "With Adaptive Iterations: a solver step also goes on projecting while any particle is "
      "compressed by more than this many percent (0: the mean alone decides). Impacts squeeze "
      "single particles that the mean hardly sees.",
      PBF_SCALAR(maxDensityErrorTolerance) },
    { "relaxation", "RelaxationEpsilon", "epsilon", "Relaxation Epsilon", "Solver", "", T::Real,
      positive, 0.0001, 10.0, true, nullptr, "",
      "Constraint force mixing epsilon of eq. 11, in units of the bulk denominator of eq. 11: "
      "0.01 softens the bulk constraint by 1%. Larger values are more stable and more "
      "compressible.",
      PBF_SCALAR(relaxation) },
    { "chebyshevRho", "ChebyshevRho", "chebyshev", "Chebyshev Rho", "Solver", "", T::Real,
      { 0, 1, false, true }, 0.0, 0.99, true, nullptr,
      "the spectral radius estimate of a Jacobi projection; 0: plain Jacobi",
      "Chebyshev acceleration of the density projections (Wang 2015): from the second "
      "projection of a step on, each Jacobi result is blended with the positions two "
      "projections back, with the weights of the Chebyshev polynomials for this estimate rho of "
      "the projection's spectral radius. A deep column then meets the density tolerance in "
      "fewer projections (a 120-layer column: 5.6 a step instead of 9.3 at 0.8; the 9.2M dam "
      "break: 2.4 instead of 3.6) and costs less per simulated second; too large an estimate "
      "makes the solve overshoot (0.9 boils that column), and with few neighbours "
      "(SmoothingRatio 1.5) 0.7 already throws single particles at 13 m/s in the dam break. It "
      "also changes the flow: the collapse of a dam break starts sooner and depends more on "
      "the time step. So it is off by default. 0 projects with plain Jacobi, the paper's solver.",
      PBF_SCALAR(chebyshevRho) },
    { "sCorrK", "SCorrK", "scorr-k", "S Corr K", "Solver", "g0", T::Real, nonNegative, 0.0, 1.0,
      true, nullptr, "",
      "k of the artificial pressure s_corr (eq. 13), as an acceleration in units of standard "
      "gravity: once per solver step it pushes a particle on a flat free surface outward by "
      "k g0 dt^2 (0.1: a tenth of gravity), whatever the spacing, smoothing ratio, time step or "
      "number of iterations; below 1 it cannot lift the surface. It keeps particles from "
      "clumping. 0 turns it off.",
      PBF_SCALAR(sCorrK) },
    { "sCorrN", "SCorrN", "scorr-n", "S Corr N", "Solver", "", T::Real, { 0, 16, true, false },
      1.0, 8.0, true, nullptr, "paper: 4",
      "Exponent n of the artificial pressure s_corr (eq. 13); the paper uses 4.",
      PBF_SCALAR(sCorrN) },
    { "sCorrDeltaQ", "SCorrDeltaQ", "scorr-dq", "S Corr Delta Q", "Solver", "h", T::Real,
      { 0, 1, true, true }, 0.01, 0.99, true, nullptr, "a fraction of h",
      "delta_q of the artificial pressure s_corr (eq. 13) as a fraction of h; the paper uses 0.1 "
      "to 0.3.",
      PBF_SCALAR(sCorrDeltaQ) },
  };
}

// What acts on the fluid besides the projections (the GUI's Solver group too).
std::vector<ParameterSpec> forceRows()
{
  return {
    { "xsphViscosity", "XSPHViscosity", "xsph", "XSPH Viscosity", "Solver", "", T::Real,
      unitInterval, 0.0, 1.0, false, nullptr,
      "the artificial viscosity alpha of nu = alpha h v_scene",
      "alpha of the XSPH viscosity (eq. 17) as an artificial viscosity nu = alpha h v_scene, "
      "v_scene the speed of a fall across the domain: the blend of each particle's velocity "
      "with its neighbours' per step is nu dt / (beta h^2), so the smoothing per second is the "
      "same at any time step and fades as the spacing is refined. It damps the particle scale "
      "noise of the solver, with XSPHHyperViscosity (0.0125 and 0.05 by default keep a deep "
      "column at rest, as 0.05 alone does). Larger is more viscous.",
      PBF_SCALAR(xsphViscosity) },
    { "xsphHyperViscosity", "XSPHHyperViscosity", "xsph-hyper", "XSPH Hyper Viscosity",
      "Solver", "", T::Real, unitInterval, 0.0, 1.0, false, nullptr,
      "alpha_4 of nu_4 = alpha_4 h v_scene",
      "alpha_4 of a second, bi-Laplacian XSPH filter: XSPH's neighbour sum is smoothed once "
      "more and taken off the velocity, with the blend of XSPHViscosity's form "
      "(nu_4 = alpha_4 h v_scene). On the particle scale, where the solver leaves its noise, it "
      "damps as XSPHViscosity does at the same alpha; a flow on a scale L much larger than h it "
      "damps about (h/L)^2 times less, so a wave or a bore keeps its speed. 0.05 by default; 0 "
      "turns it off (XSPHViscosity alone, the paper's filter). With WallFriction the walls' "
      "share of XSPH's sum is smoothed with it.",
      PBF_SCALAR(xsphHyperViscosity) },
    { "vorticityEpsilon", "VorticityEpsilon", "vorticity", "Vorticity Epsilon", "Solver", "m/s",
      T::Real, nonNegative, 0.0, 1.0, false, nullptr, "",
      "epsilon of the vorticity confinement (eq. 16) [m/s]: gives back the small-scale swirl "
      "that damping removes. 0 turns it off.",
      PBF_SCALAR(vorticityEpsilon) },
    { "surfaceTension", "SurfaceTension", "surface-tension", "Surface Tension", "Solver", "N/m",
      T::Real, nonNegative, 0.0, 1.0, false, nullptr, "",
      "Surface tension sigma [N/m] of the liquid against the empty space around it (0.072 is "
      "water and air; 0, the default, turns it off): the continuum surface force, sigma times "
      "the curvature of the fluid's surface, so the pressure inside a drop of radius R rises by "
      "2 sigma / R at any spacing and a flat surface feels nothing. It shows where the capillary "
      "length sqrt(sigma / (rho g)) is a few spacings or more (2.7 mm for water on Earth): "
      "droplets, jets, films; a drop without gravity becomes a sphere. Automatic time steps then "
      "stay below the capillary wave limit.",
      PBF_SCALAR(surfaceTension) },
    { "contactAngle", "ContactAngle", "contact-angle", "Contact Angle", "Solver", "deg",
      T::Real, { 0, 180, false, false }, 0.0, 180.0, false, nullptr, "90: neutral",
      "Adhesion to the domain's walls as the contact angle theta [degrees] that the liquid's "
      "surface makes with them, measured through the liquid (Brackbill's wall adhesion): 90, "
      "the default, is neutral; less wets the walls (a drop spreads, the surface climbs a wall), "
      "more beads up on them. Felt with SurfaceTension only; a scene's liquid sets its own.",
      PBF_SCALAR(contactAngle) },
    { "unilateral", "Unilateral", "unilateral", "Unilateral", "Solver", "", T::Boolean, boolean,
      0, 1, true, nullptr, "",
      "Clamp the density constraint C_i at 0, so that it only pushes particles apart: a free "
      "surface particle lacks neighbours, not mass, and is not pulled into the fluid.",
      PBF_BOOLEAN(unilateral) },
    { "mirrorWalls", "MirrorWalls", "walls", "Mirror Walls", "Solver", "", T::Boolean, boolean,
      0, 1, true, nullptr, "",
      "A particle within h of a domain wall also sees its neighbours mirrored in the wall, as if "
      "the fluid continued beyond it: fluid at rest against a wall then reads rho_0 instead of "
      "packing against it.",
      PBF_BOOLEAN(mirrorWalls) },
    { "tankLoads", "TankLoads", "tank-loads", "Tank Loads", "Solver", "", T::Boolean, boolean, 0,
      1, false, nullptr, "",
      "Sum what the fluid pushes each of the tank's six walls with (a force and a torque, in "
      "the Diagnostics with the obstacles' loads); needs MirrorWalls. A CPU step barely notices; "
      "on a GPU a step takes about an eighth longer, so it is off unless asked for.",
      PBF_BOOLEAN(tankLoads) },
    { "exactBoundaries", "ExactBoundaries", "exact-boundaries", "Exact Boundaries", "Solver", "",
      T::Boolean, boolean, 0, 1, true, nullptr, "",
      "Obstacles and floating bodies push the fluid by their true shape: near a solid's edges "
      "and corners a particle feels only the part of the solid within its reach, from a shape "
      "map integrated over the solid's distance field at the run's start (seconds of the cores "
      "for a large solid, then cached). Off: every solid acts as its tangent plane, exact on "
      "flat faces only.",
      PBF_BOOLEAN(exactBoundaries) },
    { "wallFriction", "WallFriction", "friction", "Wall Friction", "Solver", "", T::Real,
      unitInterval, 0.0, 1.0, false, nullptr, "0 free-slip, 1 no-slip",
      "Friction of the domain walls and the obstacles: 0 (the default) lets the fluid slide "
      "along them (free-slip); 1 holds the fluid at a wall as the fluid's own viscosity "
      "(XSPHViscosity) holds it elsewhere (no-slip at that viscosity). Between the two, the wall "
      "removes that share. The domain walls take part when MirrorWalls is on.",
      PBF_SCALAR(wallFriction) },
    { "gravity", "Gravity", "gravity", "Gravity", "Solver", "m/s^2", T::Vector, finite, -100.0,
      100.0, false, nullptr, "",
      "Gravitational acceleration [m/s^2]; the shipped scenes have their floor at y = 0.",
      PBF_VECTOR(gravity) },
  };
}

// The automatic step's bounds; the filter's Frame Interval, Time Stepping and Substeps Per Frame
// decide which of these a run uses.
std::vector<ParameterSpec> timeRows()
{
  return {
    { "cflNumber", "CFLNumber", "cfl", "CFL Number", "Time", "", T::Real, { 0, 1, true, false },
      0.05, 1.0, false, "visibility TimeStepping 1",
      "a particle may move at most that fraction of a spacing per step",
      "With automatic time stepping: the most spacings a particle may move in one solver step "
      "(all but the fastest thousandth of them; the fastest at most one spacing, or this many "
      "with solids). Smaller is "
      "more accurate and costs time linearly.",
      PBF_SCALAR(cflNumber) },
    { "timeStep", "MaxTimeStep", "dt", "Max Time Step", "Time", "s", T::Real, positive, 0.00001,
      0.1, true, "visibility TimeStepping 1", "",
      "With automatic time stepping: the largest solver step [s] (1/240 by default).",
      PBF_SCALAR(timeStep) },
  };
}

// The groups in the GUI's order.
std::vector<ParameterSpec> makeTable()
{
  std::vector<ParameterSpec> table;
  for (auto rows : { fluidRows, solverRows, forceRows, timeRows })
  {
    const std::vector<ParameterSpec> group = rows();
    table.insert(table.end(), group.begin(), group.end());
  }
  return table;
}

#undef PBF_SCALAR
#undef PBF_BOOLEAN
#undef PBF_VECTOR

std::string number(double value)
{
  std::ostringstream text;
  text << value;
  return text.str();
}

} // namespace

std::string ValidRange::rule() const
{
  const bool lowEnd = std::isfinite(min), highEnd = std::isfinite(max);
  if (lowEnd && highEnd)
  {
    return "must lie in " + std::string(minOpen ? "(" : "[") + number(min) + ", " + number(max) +
      (maxOpen ? ")" : "]");
  }
  if (lowEnd)
  {
    return std::string("must be ") + (minOpen ? "> " : ">= ") + number(min);
  }
  if (highEnd)
  {
    return std::string("must be ") + (maxOpen ? "< " : "<= ") + number(max);
  }
  return "must be a finite number";
}

bool ValidRange::contains(double value) const
{
  return std::isfinite(value) && (minOpen ? value > min : value >= min) &&
    (maxOpen ? value < max : value <= max);
}

const std::vector<ParameterSpec>& parameterTable()
{
  static const std::vector<ParameterSpec> table = makeTable();
  return table;
}

const ParameterSpec* findParameter(const std::string& name)
{
  for (const ParameterSpec& spec : parameterTable())
  {
    if (name == spec.field || name == spec.property)
    {
      return &spec;
    }
  }
  return nullptr;
}

void validateTableParameters(const Parameters& p)
{
  const char* axis[3] = { ".x", ".y", ".z" };
  for (const ParameterSpec& spec : parameterTable())
  {
    for (int c = 0; c < spec.components(); ++c)
    {
      const double value = spec.get(p, c);
      if (spec.valid.contains(value))
      {
        continue;
      }
      const std::string name =
        std::string(spec.field) + (spec.type == ParameterType::Vector ? axis[c] : "");
      std::string rule = std::isfinite(value) ? spec.valid.rule() : "must be a finite number";
      if (std::isfinite(value) && spec.why[0] != '\0')
      {
        rule += std::string(" (") + spec.why + ")";
      }
      std::ostringstream message;
      message << name << " = " << value << ": " << rule;
      throw InvalidInput(message.str());
    }
  }
}

bool sameTableParameters(const Parameters& a, const Parameters& b)
{
  for (const ParameterSpec& spec : parameterTable())
  {
    for (int c = 0; c < spec.components(); ++c)
    {
      const double x = spec.get(a, c), y = spec.get(b, c);
      // Bit for bit: NaN is never a valid value, and +0 and -0 run the same.
      if (!(x == y))
      {
        return false;
      }
    }
  }
  return true;
}

} // namespace pbf
