// The equations of Position Based Fluids (Macklin & Mueller 2013), one function per particle and
// stage, written once for every backend: the CPU loops and the CUDA kernels call exactly these.
// Equation numbers refer to the paper. Particles are in cell-sorted order; i and j index it.
#pragma once

#include "Boundary.h"
#include "Grid.h"
#include "HostDevice.h"
#include "Kernels.h"
#include "Parameters.h"
#include "SurfaceTension.h"
#include "Vec3.h"

#include <algorithm>
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

  static StepTime make(const Parameters& p, const LatticeCalibration& lattice, double dt)
  {
    StepTime t;
    t.dt = static_cast<Real>(dt);
    t.inverseDt = static_cast<Real>(1.0 / dt);
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

// A solid's s_corr with particle i: its image in the solid is of i's liquid (tensileDensity).
// Liquids false: one liquid, whatever f.liquid holds (the GPU compiles the liquids' terms out).
template <bool Liquids = true, class Real, class Neighbors>
PBF_HD PBF_INLINE Real solidTensile(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Real tensile = f.tensile ? f.time->tensile : Real(0);
  return Liquids && f.liquid ? tensile * f.time->liquidDensityRatio[f.liquid[i]] : tensile;
}

// Calls visit(o, d, gradient, g) for each solid o whose grid holds q (DistanceGridView::within):
// d the field there, gradient its gradient and g that gradient's length. A particle beyond a
// solid's grid skips it, so a solid costs the particles near it.
template <class Real, class Neighbors, class Visit>
PBF_HD PBF_INLINE void forEachSolidField(
  const Vec3<Real>& q, const FluidView<Real, Neighbors>& f, Visit&& visit)
{
  for (int o = 0; o < f.obstacleCount; ++o)
  {
    Vec3<Real> gradient;
    Real d;
    if (f.obstacles[o].within(q, &d, &gradient))
    {
      visit(o, d, gradient, length(gradient));
    }
  }
}

// Calls visit(n, b, solid) for each solid within h of q: n its outward unit normal there (the
// field's gradient), b the table's sums at q's distance from it, solid its view (for its velocity).
template <class Real, class Neighbors, class Visit>
PBF_HD PBF_INLINE void forEachNearSolid(
  const Vec3<Real>& q, const FluidView<Real, Neighbors>& f, Visit&& visit)
{
  forEachSolidField(q, f, [&](int o, Real d, const Vec3<Real>& gradient, Real g) {
    if (d < f.c.kernels.h && g > Real(0))
    {
      visit(gradient * (Real(1) / g), sampleBoundary(f.boundary, d), f.obstacles[o]);
    }
  });
}

// The solid nearest to a particle within h, as surface tension sees it: a mirror at the solid's
// tangent plane there, as the boundary's sums take it (Boundary.h). Its images continue the
// colour and the surface into the solid as the walls' images do (SurfaceTension.h), so a solid is
// no surface, and its contact angle acts at the contact line. solid < 0: none within h.
template <class Real>
struct SolidMirror
{
  int solid;     // its index among the obstacles
  Vec3<Real> n;  // its outward unit normal
  Real offset;   // the plane: dot(n, x) = offset
  Real distance; // of the particle from it, in [0, h)

  // q reflected in the plane; an image is never closer to a particle on the fluid's side than q.
  PBF_HD PBF_INLINE Vec3<Real> image(const Vec3<Real>& q) const
  {
    return q - n * (Real(2) * (dot(n, q) - offset));
  }
  // A direction seen in the mirror.
  PBF_HD PBF_INLINE Vec3<Real> reflect(const Vec3<Real>& v) const
  {
    return v - n * (Real(2) * dot(n, v));
  }
};

template <class Real>
PBF_HD PBF_INLINE SolidMirror<Real> noSolid()
{
  return SolidMirror<Real>{ -1, Vec3<Real>{ Real(0), Real(0), Real(0) }, Real(0), Real(0) };
}

template <class Real, class Neighbors>
PBF_HD PBF_INLINE SolidMirror<Real> nearestSolid(
  const Vec3<Real>& q, const FluidView<Real, Neighbors>& f)
{
  SolidMirror<Real> m{ -1, Vec3<Real>{ Real(0), Real(0), Real(0) }, Real(0), f.c.kernels.h };
  forEachSolidField(q, f, [&](int o, Real d, const Vec3<Real>& gradient, Real g) {
    d = d < Real(0) ? Real(0) : d; // inside: on its surface, where the collision puts it
    if (d < m.distance && g > Real(0))
    {
      m.solid = o;
      m.n = gradient * (Real(1) / g);
      m.distance = d;
      m.offset = dot(m.n, q) - d;
    }
  });
  return m;
}

// A solid's share of delta p_i (eq. 14, before m / rho_0), for the solid at outward normal n with
// the table's sums b there: it carries lambda_i, as a mirror image does, and s_corr's push.
// positionCorrection adds it; the particle pushes the solid back with it (solidLoads).
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> solidShare(
  const Vec3<Real>& n, const BoundarySample<Real>& b, Real lambdaI, Real tensile)
{
  return n * (b.spiky * (lambdaI + lambdaI) + tensile * b.tensile);
}

// A particle inside an obstacle goes to its surface, along the field's gradient. Solid by solid:
// each is asked where the particle is after the ones before it moved it.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE Vec3<Real> collideWithObstacles(Vec3<Real> q, const FluidView<Real, Neighbors>& f)
{
  forEachSolidField(q, f, [&](int, Real d, const Vec3<Real>& gradient, Real g) {
    if (d < Real(0) && g > Real(0))
    {
      q -= gradient * (d / g);
    }
  });
  return q;
}

// Collision with the domain box: project the particle back inside (the paper's simple response).
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> collideWithBox(Vec3<Real> q, const Coefficients<Real>& c)
{
  q.x = q.x < c.boxMin.x ? c.boxMin.x : (q.x > c.boxMax.x ? c.boxMax.x : q.x);
  q.y = q.y < c.boxMin.y ? c.boxMin.y : (q.y > c.boxMax.y ? c.boxMax.y : q.y);
  q.z = q.z < c.boxMin.z ? c.boxMin.z : (q.z > c.boxMax.z ? c.boxMax.z : q.z);
  return q;
}

// Mirror walls: a particle within h of a domain wall also sees the reflections of its neighbours
// in that wall (and in both walls of an edge or corner), as if resting fluid continued beyond it.
// On the initial lattice, whose outer sites sit s/2 inside the walls, the images are exactly the
// lattice continued, so every particle reads rho_0 at rest; without them the unilateral
// constraint lets the fluid pack against the walls (a resting 12^3 block sank by a fifth). Images
// carry their particle's lambda. Only density and the position correction see them.
template <class Real>
struct WallMirrors
{
  int count[3];     // per axis: 1 (the neighbour itself) + the walls within h
  Real wall[3][2];  // the coordinates of those walls
};

template <class Real>
PBF_HD PBF_INLINE WallMirrors<Real> nearWalls(const Vec3<Real>& p, const Coefficients<Real>& c)
{
  WallMirrors<Real> m;
  const Real pa[3] = { p.x, p.y, p.z };
  const Real lo[3] = { c.boxMin.x, c.boxMin.y, c.boxMin.z };
  const Real hi[3] = { c.boxMax.x, c.boxMax.y, c.boxMax.z };
  // Unrolled, with the wall slot chosen by a branch rather than an index: on a GPU an array
  // indexed at run time lives in local memory.
#if defined(__CUDACC__)
#pragma unroll
#endif
  for (int a = 0; a < 3; ++a)
  {
    m.count[a] = 1;
    m.wall[a][0] = m.wall[a][1] = Real(0);
    if (!c.mirrorWalls)
    {
      continue;
    }
    if (pa[a] - lo[a] < c.kernels.h)
    {
      m.wall[a][0] = lo[a];
      m.count[a] = 2;
    }
    if (hi[a] - pa[a] < c.kernels.h)
    {
      if (m.count[a] == 1)
      {
        m.wall[a][0] = hi[a];
      }
      else
      {
        m.wall[a][1] = hi[a];
      }
      ++m.count[a];
    }
  }
  return m;
}

// Calls visit(image, ix, iy, iz) for each reflection of q in the walls of m (not q itself): ia is 0
// where the image is not reflected along axis a, else 1 + the slot of m.wall[a] it is reflected
// in. In the order of
// three nested loops over x, y, z (z innermost). A reflection is never closer to a particle on the
// fluid's side of a wall than q is, so the passes visit q's reflections only when q itself lies
// within h: most candidates, and every candidate of a particle that sees no wall, pay one test
// instead of the loop (on a GPU its counters and selects had been a sixth of the density pass's
// instructions). The wall is picked by a select, not an index, for the reason given in nearWalls;
// 2 w is exact, so an image is 2 w - q rounded once, whatever the path.
template <class Real, class Visit>
PBF_HD PBF_INLINE void forEachReflection(const WallMirrors<Real>& m, const Vec3<Real> q, Visit&& visit)
{
  const int images = m.count[0] * m.count[1] * m.count[2];
  int ix = 0, iy = 0, iz = 0;
  for (int k = 1; k < images; ++k)
  {
    // The next (ix, iy, iz), z fastest.
    if (++iz == m.count[2])
    {
      iz = 0;
      if (++iy == m.count[1])
      {
        iy = 0;
        ++ix;
      }
    }
    Vec3<Real> image;
    image.x = ix == 0 ? q.x : Real(2) * (ix == 1 ? m.wall[0][0] : m.wall[0][1]) - q.x;
    image.y = iy == 0 ? q.y : Real(2) * (iy == 1 ? m.wall[1][0] : m.wall[1][1]) - q.y;
    image.z = iz == 0 ? q.z : Real(2) * (iz == 1 ? m.wall[2][0] : m.wall[2][1]) - q.z;
    visit(image, ix, iy, iz);
  }
}

// Calls add(r, r2) for each reflection of q closer to p than h (r = p - reflection, r2 = |r|^2).
template <class Real, class Add>
PBF_HD PBF_INLINE void forEachReflectionWithin(
  const WallMirrors<Real>& m, const Vec3<Real>& p, const Vec3<Real>& q, Real h2, Add&& add)
{
  forEachReflection(m, q, [&](const Vec3<Real>& image, int, int, int) {
    const Vec3<Real> r = p - image;
    const Real r2 = dot(r, r);
    if (r2 < h2)
    {
      add(r, r2);
    }
  });
}

template <class Real>
PBF_HD PBF_INLINE bool hasReflections(const WallMirrors<Real>& m)
{
  return m.count[0] * m.count[1] * m.count[2] > 1;
}

// Algorithm 1, lines 1-4: apply gravity, predict x*_i = x_i + dt v_i.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void predictPosition(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Real dt = f.time->dt;
  const Vec3<Real> v = f.v[i] + f.c.gravity * dt;
  f.v[i] = v;
  f.p[i] = collideWithObstacles(collideWithBox(f.x[i] + v * dt, f.c), f);
}

// Eq. 2 (poly6 density), eq. 1 (C_i = rho_i / rho_0 - 1), eq. 8 (spiky constraint gradients) and
// eq. 11 (lambda_i with relaxation epsilon), in one pass over the neighbours and their images.
// Liquids false compiles the liquids' weight out (a GPU pass of a scene without liquids: the
// branch's registers made the double-precision passes spill).
template <class Real, class Neighbors, bool Liquids = true>
PBF_HD PBF_INLINE void densityAndLambda(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Vec3<Real> pi = f.p[i];
  const WallMirrors<Real> mirrors = nearWalls(pi, f.c);
  Real rho = Real(0);
  Vec3<Real> gradI{ Real(0), Real(0), Real(0) }; // grad_{p_i} C_i
  Real sumGradJ2 = Real(0);                      // sum_j |grad_{p_j} C_i|^2
  const bool reflections = hasReflections(mirrors);
  const auto add = [&](const Vec3<Real>& r, Real r2) {
    rho += f.c.kernels.poly6Within(r2);
    const Vec3<Real> g = f.c.kernels.spikyGradientWithin(r, r2) * f.c.massOverRho0;
    gradI += g;
    sumGradJ2 += dot(g, g);
  };
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> pj = f.p[j];
    const Vec3<Real> r = pi - pj;
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2)
    {
      add(r, r2);
      if (reflections)
      {
        forEachReflectionWithin(mirrors, pi, pj, f.c.kernels.h2, add);
      }
    }
  });
  // Each solid within h: its share, the lattice reflected in its tangent plane (Boundary.h).
  forEachNearSolid(pi, f,
    [&](const Vec3<Real>& n, const BoundarySample<Real>& b, const DistanceGridView<Real>&) {
    rho += b.poly6;
    gradI += n * (b.spiky * f.c.massOverRho0);
    sumGradJ2 += b.spiky2 * f.c.massOverRho0 * f.c.massOverRho0;
  });
  rho *= f.c.mass;
  Real C = rho * f.c.inverseRestDensity - Real(1);
  if (f.c.unilateral && C < Real(0))
  {
    C = Real(0);
  }
  f.density[i] = rho;
  const Real denominator = sumGradJ2 + dot(gradI, gradI) + f.c.relaxation;
  f.lambda[i] = -C * f.c.jacobiRelaxation /
    (Liquids && f.liquid ? denominator * liquidWeight(i, f) : denominator);
}

// The pressure p_i that the step's corrections of particle i stand for [Pa]. SPH's symmetric
// pressure acceleration, -sum_j m (p_i + p_j) / rho_0^2 grad W_ij, moves a particle by dt^2 times
// it in a step; eq. 14 moves it by (m / rho_0) sum_j (lambda_i + lambda_j) grad W_ij. The two
// agree term by term when p_i = -rho_0 lambda_i / dt^2, summed over the projections that were
// applied (a stopped solve applies none after it stops). That sum is then scaled by the
// lattice's gradient moment G (LatticeCalibration::gradientMoment): the discrete gradient
// reads G times a smooth field's, so water at rest holds itself up with 1 / G times rho_0 g d.
// s_corr's push is not part of it: it is an artificial pressure between pairs, not a
// particle's. The first projection (f.tensile) starts the sum.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void recordPressure(
  std::uint32_t i, const FluidView<Real, Neighbors>& f, Real lambdaI)
{
  if (f.pressure)
  {
    const Real p = -f.c.pressureScale * lambdaI * f.time->inverseDt * f.time->inverseDt;
    f.pressure[i] = f.tensile ? p : f.pressure[i] + p;
  }
}

// positionCorrection's default: nothing is done with the mirror walls' terms.
struct NoWallTerms
{
  template <class... Any>
  PBF_HD PBF_INLINE void operator()(const Any&...) const
  {
  }
};

// Eq. 13 (s_corr, the artificial pressure against clustering) and eq. 14 (delta p_i). s_corr
// enters in the step's first projection only, with this step's coefficient (StepTime::tensile).
// onWall(term, mirrors, p_i, image, ix, iy, iz) hears each mirror image's term of delta p_i (before
// m / rho_0) with forEachReflection's arguments: what the walls' loads are made of (wallShares).
// Liquids false compiles the liquids' terms out, as densityAndLambda's.
template <class Real, class Neighbors, class OnWall = NoWallTerms, bool Liquids = true>
PBF_HD PBF_INLINE void positionCorrection(
  std::uint32_t i, const FluidView<Real, Neighbors>& f, OnWall&& onWall = OnWall{})
{
  const Vec3<Real> pi = f.p[i];
  const WallMirrors<Real> mirrors = nearWalls(pi, f.c);
  const Real lambdaI = f.lambda[i];
  const Real tensile = f.tensile ? f.time->tensile : Real(0);
  Vec3<Real> delta{ Real(0), Real(0), Real(0) };
  const bool reflections = hasReflections(mirrors);
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> pj = f.p[j];
    const Vec3<Real> r = pi - pj;
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2)
    {
      const Real lambdaJ = f.lambda[j];
      const auto add = [&](const Vec3<Real>& d, Real d2) {
        // s_corr only in the step's first projection: the later ones do not evaluate poly6.
        Real sCorr = Real(0);
        if (tensile != Real(0))
        {
          const Real pair = Liquids && f.liquid ? tensile * tensileDensity(i, j, f) : tensile;
          sCorr = -pair * power(f.c.kernels.poly6Within(d2) * f.c.inverseWDeltaQ, f.c.sCorrN);
        }
        const Vec3<Real> term = f.c.kernels.spikyGradientWithin(d, d2) * (lambdaI + lambdaJ + sCorr);
        delta += term;
        return term;
      };
      // The particle itself needs no test: its gradient at r = 0 is exactly zero
      // (spikyGradientWithin), so it adds a zero to a sum that started at +0.
      add(r, r2);
      if (reflections)
      {
        // A particle's own reflections count: they are the wall's share next to it.
        forEachReflection(mirrors, pj, [&](const Vec3<Real>& image, int ix, int iy, int iz) {
          const Vec3<Real> d = pi - image;
          const Real d2 = dot(d, d);
          if (d2 < f.c.kernels.h2)
          {
            onWall(add(d, d2), mirrors, pi, image, ix, iy, iz);
          }
        });
      }
    }
  });
  // The solid's share carries lambda_i, as a mirror image does (Boundary.h).
  const Real tensileI = solidTensile<Liquids>(i, f);
  forEachNearSolid(pi, f,
    [&](const Vec3<Real>& n, const BoundarySample<Real>& b, const DistanceGridView<Real>&) {
    delta += solidShare(n, b, lambdaI, tensileI);
  });
  f.scratch[i] =
    delta * (Liquids && f.liquid ? f.c.massOverRho0 * liquidWeight(i, f) : f.c.massOverRho0);
  recordPressure(i, f, lambdaI);
}

// What particle i pushes each solid with in this projection: the solid's share of its delta p_i
// (positionCorrection's) as a force, m delta p / dt^2, reversed, and that force's torque about
// the world's origin; add(solid index, force, torque). The same model that keeps the fluid out:
// a solid feels exactly what it does to the fluid.
template <class Real, class Neighbors, class Add>
PBF_HD PBF_INLINE void solidLoads(std::uint32_t i, const FluidView<Real, Neighbors>& f, Add&& add)
{
  const Vec3<Real> pi = f.p[i];
  const Real lambdaI = f.lambda[i];
  const Real tensile = solidTensile(i, f);
  const Real scale = -f.c.massOverRho0 * f.c.mass * f.time->inverseDt * f.time->inverseDt;
  forEachNearSolid(pi, f,
    [&](const Vec3<Real>& n, const BoundarySample<Real>& b, const DistanceGridView<Real>& solid) {
    const Vec3<Real> force = solidShare(n, b, lambdaI, tensile) * scale;
    add(static_cast<int>(&solid - f.obstacles), force, cross(pi, force));
  });
}

// Which walls a mirror image's term of delta p_i belongs to (positionCorrection's onWall): add(wall,
// part) with wall = 2 a + 0 for the low wall of axis a, + 1 for the high one. A term reflected in
// one wall is that wall's; one reflected in an edge or a corner gives each of its walls the
// component along the wall's normal and an equal share of the rest. As a force on the wall the
// parts are scaled by -m (m / rho_0) / dt^2 (the reaction, as solidLoads has it for a solid).
template <class Real, class Add>
PBF_HD PBF_INLINE void wallShares(const Vec3<Real>& term, const WallMirrors<Real>& mirrors, int ix,
  int iy, int iz, const Coefficients<Real>& c, Add&& add)
{
  const int slot[3] = { ix, iy, iz };
  const Real along[3] = { term.x, term.y, term.z };
  const Real lo[3] = { c.boxMin.x, c.boxMin.y, c.boxMin.z };
  const int walls = (ix > 0) + (iy > 0) + (iz > 0);
  for (int a = 0; a < 3; ++a)
  {
    if (slot[a] == 0)
    {
      continue;
    }
    Real share[3];
    for (int b = 0; b < 3; ++b)
    {
      share[b] = b == a ? along[b] : (slot[b] > 0 ? Real(0) : along[b] / Real(walls));
    }
    add(2 * a + (mirrors.wall[a][slot[a] - 1] == lo[a] ? 0 : 1),
      Vec3<Real>{ share[0], share[1], share[2] });
  }
}

// Algorithm 1, lines 17-19: apply delta p_i and resolve collisions (Jacobi update).
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void applyCorrection(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  f.p[i] = collideWithObstacles(collideWithBox(f.p[i] + f.scratch[i], f.c), f);
}

// Chebyshev's acceleration of that update (Chebyshev.h): the Jacobi result `jacobi` blended with
// the particle's positions two projections back, p^{k+1} = p^{k-1} + omega (jacobi - p^{k-1}),
// then the collisions again (the blend may reach past a wall that jacobi was kept from).
template <class Real, class Neighbors>
PBF_HD PBF_INLINE Vec3<Real> acceleratedCorrection(const Vec3<Real>& jacobi,
  const Vec3<Real>& twoBack, Real omega, const FluidView<Real, Neighbors>& f)
{
  return collideWithObstacles(collideWithBox(twoBack + (jacobi - twoBack) * omega, f.c), f);
}

// Algorithm 1, line 21: v_i = (x*_i - x_i) / dt. The density is final now, so the volume that the
// vorticity passes read is stored here when the view keeps one.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void updateVelocity(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  f.v[i] = (f.p[i] - f.x[i]) * f.time->inverseDt;
  if (f.volume)
  {
    f.volume[i] = f.c.mass / f.density[i];
  }
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

// Wall friction (Parameters::wallFriction, phi) as the walls' share of XSPH's smoothing: a wall's
// image of a particle moves as the particle reflected in the wall, its normal velocity reversed
// (the free-slip image) and its tangential velocity scaled by 1 - 2 phi (reversed at phi = 1: the
// no-slip image, whose mean with the particle is at rest on the wall). The free-slip image is
// left out of XSPH (the walls were always free-slip), so only the difference enters:
// -2 phi v_t, weighted as a neighbour is. For a mirror wall (the box's) the images are those of
// the neighbours, and an image's tangential components are the ones it was not reflected along;
// for a solid, the image of the particle itself in the solid's tangent plane, weighted by the
// solid's share of the density (Boundary.h), as the density and correction passes treat it.
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> wallFrictionImage(
  const Vec3<Real>& q, const Vec3<Real>& image, const Vec3<Real>& v, Real weight)
{
  return Vec3<Real>{ image.x == q.x ? v.x : Real(0), image.y == q.y ? v.y : Real(0),
           image.z == q.z ? v.z : Real(0) } *
    weight;
}

// Eq. 15 (vorticity omega_i) and eq. 17's sum S_i = sum_j V_j (v_j - v_i) W_ij (XSPH) from the
// same neighbour pass, into f.omega and f.smoothing; the confinement pass applies XSPH, because
// its bi-Laplacian needs every neighbour's S_j first. Both sums carry the SPH volume
// V_j = m / rho_j, so omega is a true curl in 1/s and c is a dimensionless blend.
// With wall friction the walls' images join the smoothing (wallFrictionImage), in the same pass:
// one neighbour walk, so the GPU stages its neighbour rows once. Friction = false compiles them
// out: the GPU launches that pass when the friction is 0, as the images' code made the kernel
// slower even where they were not visited (3 % a step in double at 1M particles on the H200).
// Solids = false compiles the solids' images of the colour out (the GPU launches that pass when
// the scene has no solid: their registers cost the colour's pass 3 % a step).
template <class Real, class Neighbors, bool Friction = true, bool Colour = true, bool Solids = true>
PBF_HD PBF_INLINE void vorticityAndXsph(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Vec3<Real> pi = f.p[i];
  const Vec3<Real> vi = f.v[i];
  Vec3<Real> omega{ Real(0), Real(0), Real(0) };
  Vec3<Real> smoothing{ Real(0), Real(0), Real(0) };
  Vec3<Real> gradC{ Real(0), Real(0), Real(0) };
  const Real friction = Friction ? Real(-2) * f.c.wallFriction : Real(0);
  WallMirrors<Real> mirrors{ { 1, 1, 1 }, { { Real(0), Real(0) }, { Real(0), Real(0) }, { Real(0), Real(0) } } };
  const bool colour = Colour && f.colour;
  if ((Friction && friction != Real(0)) || colour)
  {
    mirrors = nearWalls(pi, f.c);
  }
  const bool images = hasReflections(mirrors);
  // The nearest solid's images continue the colour as the walls' do (SolidMirror).
  SolidMirror<Real> solid = noSolid<Real>();
  if (Solids && colour && f.obstacleCount > 0)
  {
    solid = nearestSolid(pi, f);
  }
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> pj = f.p[j];
    const Vec3<Real> r = pi - pj;
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2) // the particle itself adds zeros: no test
    {
      const Real volume = volumeOf(j, f);
      const Vec3<Real> vij = f.v[j] - vi;
      omega += cross(f.c.kernels.spikyGradientWithin(r, r2), vij) * volume;
      smoothing += vij * (volume * f.c.kernels.poly6Within(r2));
      if (colour)
      {
        gradC += colourGradientTerm(r, f.c.kernels.h2 - r2, f.c.colourScale * volume);
      }
    }
    if (colour && images && r2 < f.c.kernels.h2)
    {
      // The walls' images continue the colour as they continue the density: a wall is no
      // surface, and the surface meets it at a right angle (no adhesion).
      const Real scale = f.c.colourScale * volumeOf(j, f);
      forEachReflectionWithin(mirrors, pi, pj, f.c.kernels.h2, [&](const Vec3<Real>& ri, Real ri2) {
        gradC += colourGradientTerm(ri, f.c.kernels.h2 - ri2, scale);
      });
    }
    if (Solids && colour && solid.solid >= 0 && r2 < f.c.kernels.h2)
    {
      const Vec3<Real> ri = pi - solid.image(pj);
      const Real ri2 = dot(ri, ri);
      if (ri2 < f.c.kernels.h2)
      {
        gradC += colourGradientTerm(ri, f.c.kernels.h2 - ri2, f.c.colourScale * volumeOf(j, f));
      }
    }
    if (Friction && friction != Real(0) && images && r2 < f.c.kernels.h2)
    {
      // An image is never closer than its neighbour (both on the fluid's side of the wall).
      const Vec3<Real> vj = f.v[j];
      const Real volume = volumeOf(j, f);
      forEachReflection(mirrors, pj, [&](const Vec3<Real>& image, int, int, int) {
        const Vec3<Real> ri = pi - image;
        const Real ri2 = dot(ri, ri);
        if (ri2 < f.c.kernels.h2)
        {
          smoothing += wallFrictionImage(
            pj, image, vj, friction * volume * f.c.kernels.poly6Within(ri2));
        }
      });
    }
  });
  if (Friction && friction != Real(0))
  {
    forEachNearSolid(pi, f,
      [&](const Vec3<Real>& n, const BoundarySample<Real>& b, const DistanceGridView<Real>& solid) {
      // The velocity relative to the solid's surface (a moving obstacle drags the fluid along).
      const Vec3<Real> slip = vi - solid.velocityAt(pi);
      smoothing += (slip - n * dot(slip, n)) * (friction * f.c.massOverRho0 * b.poly6);
    });
  }
  f.omega[i] = omega;
  if (f.omegaLength)
  {
    f.omegaLength[i] = length(omega);
  }
  f.smoothing[i] = smoothing;
  if (colour)
  {
    f.colour[i] = gradC;
  }
}

// How far p is from the nearest mirror wall; h where none is nearer (or the walls mirror nothing).
template <class Real>
PBF_HD PBF_INLINE Real nearestWallDistance(const Vec3<Real>& p, const Coefficients<Real>& c)
{
  if (!c.mirrorWalls)
  {
    return c.kernels.h;
  }
  Real nearest = c.kernels.h;
  nearest = p.x - c.boxMin.x < nearest ? p.x - c.boxMin.x : nearest;
  nearest = p.y - c.boxMin.y < nearest ? p.y - c.boxMin.y : nearest;
  nearest = p.z - c.boxMin.z < nearest ? p.z - c.boxMin.z : nearest;
  nearest = c.boxMax.x - p.x < nearest ? c.boxMax.x - p.x : nearest;
  nearest = c.boxMax.y - p.y < nearest ? c.boxMax.y - p.y : nearest;
  nearest = c.boxMax.z - p.z < nearest ? c.boxMax.z - p.z : nearest;
  return nearest;
}

// Adhesion at the walls (SurfaceTension.h's youngForce) for a surface particle at p with smoothed
// normal n and colour gradient gradC: the nearest wall within h sets it; zero beyond h.
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> wallYoungForce(const Vec3<Real>& p, const Vec3<Real>& n,
  const Vec3<Real>& gradC, const Coefficients<Real>& c, Real cosTheta)
{
  const Real pa[3] = { p.x, p.y, p.z };
  const Real lo[3] = { c.boxMin.x, c.boxMin.y, c.boxMin.z };
  const Real hi[3] = { c.boxMax.x, c.boxMax.y, c.boxMax.z };
  Real nearest = c.kernels.h;
  Vec3<Real> nw{ Real(0), Real(0), Real(0) };
#if defined(__CUDACC__)
#pragma unroll
#endif
  for (int a = 0; a < 3; ++a)
  {
    const Vec3<Real> unit{ a == 0 ? Real(1) : Real(0), a == 1 ? Real(1) : Real(0),
      a == 2 ? Real(1) : Real(0) };
    if (pa[a] - lo[a] < nearest)
    {
      nearest = pa[a] - lo[a];
      nw = unit;
    }
    if (hi[a] - pa[a] < nearest)
    {
      nearest = hi[a] - pa[a];
      nw = unit * Real(-1);
    }
  }
  if (!(nearest < c.kernels.h))
  {
    return Vec3<Real>{ Real(0), Real(0), Real(0) };
  }
  return youngForce(n, nw, gradC, cosTheta, nearest < Real(0) ? Real(0) : nearest, c.kernels.h);
}

// A direction seen in the walls that made an image (forEachReflection's ix, iy, iz): the
// components along the axes it was reflected along change sign.
template <class Real>
PBF_HD PBF_INLINE Vec3<Real> reflected(const Vec3<Real>& v, int ix, int iy, int iz)
{
  return Vec3<Real>{ ix != 0 ? -v.x : v.x, iy != 0 ? -v.y : v.y, iz != 0 ? -v.z : v.z };
}

// grad c averaged over particle i's neighbours (Shepard's weights V_j W_ij) into f.normal[i]:
// the directions the curvature is taken from, smoothed over twice the kernel's support, so that
// a surface rough on the particles' scale does not read as curved (SurfaceTension.h).
// Solids as in vorticityAndXsph.
template <class Real, class Neighbors, bool Solids = true>
PBF_HD PBF_INLINE void smoothColour(std::uint32_t i, const FluidView<Real, Neighbors>& f)
{
  const Vec3<Real> pi = f.p[i];
  Vec3<Real> sum{ Real(0), Real(0), Real(0) };
  Real weight = Real(0);
  // The walls' images take part with their gradients reflected, as in the colour itself: near a
  // wall the average is over the whole support, so a surface meeting the wall at a right angle
  // keeps its normal along the wall.
  const WallMirrors<Real> mirrors = nearWalls(pi, f.c);
  const bool images = hasReflections(mirrors);
  const SolidMirror<Real> solid =
    Solids && f.obstacleCount > 0 ? nearestSolid(pi, f) : noSolid<Real>();
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> pj = f.p[j];
    const Vec3<Real> r = pi - pj;
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2)
    {
      const Real volume = volumeOf(j, f);
      const Real w = volume * f.c.kernels.poly6Within(r2);
      const Vec3<Real> gj = f.colour[j];
      sum += gj * w;
      weight += w;
      if (Solids && solid.solid >= 0)
      {
        const Vec3<Real> ri = pi - solid.image(pj);
        const Real ri2 = dot(ri, ri);
        if (ri2 < f.c.kernels.h2)
        {
          const Real wi = volume * f.c.kernels.poly6Within(ri2);
          sum += solid.reflect(gj) * wi;
          weight += wi;
        }
      }
      if (images)
      {
        forEachReflection(mirrors, pj, [&](const Vec3<Real>& image, int ix, int iy, int iz) {
          const Vec3<Real> ri = pi - image;
          const Real ri2 = dot(ri, ri);
          if (ri2 < f.c.kernels.h2)
          {
            const Real wi = volume * f.c.kernels.poly6Within(ri2);
            sum += reflected(gj, ix, iy, iz) * wi;
            weight += wi;
          }
        });
      }
    }
  });
  f.normal[i] = sum * (Real(1) / weight);
}

// The step's new velocity into velocityOut[i]: XSPH, v_i + c S_i (eq. 17), minus c_4 times S
// smoothed once more, S(S)_i = sum_j V_j (S_j - S_i) W_ij (Parameters::xsphHyperViscosity; a
// pattern of gain g under S is damped by c g + c_4 g^2, so long waves, g ~ (k h)^2, hardly feel
// c_4), plus eq. 16: f_i = epsilon (N x omega_i), N = eta / |eta|, eta = grad |omega|_i (SPH
// difference gradient, zero in uniform rotation), as an acceleration. Where |eta| h is negligible
// against |omega| the direction N is noise, and the force is dropped. velocityOut may be f.v or
// f.omega: each particle reads only its own of those. SmoothTwice = false compiles the
// bi-Laplacian out: the GPU launches that pass when alpha_4 is 0 (its registers made the double
// precision pass spill). Then surface tension (SurfaceTension.h): dt times its acceleration,
// -sigma (div n) grad c_i / rho, with div n from the surface neighbours' smoothed normals in the
// same walk; Tension = false compiles it out, as SmoothTwice does, and Solids = false the solids'
// images and adhesion (vorticityAndXsph says why).
template <class Real, class Neighbors, bool SmoothTwice = true, bool Tension = true,
  bool Solids = true>
PBF_HD PBF_INLINE void vorticityConfinement(
  std::uint32_t i, const FluidView<Real, Neighbors>& f, Vec3<Real>* velocityOut)
{
  const Vec3<Real> pi = f.p[i];
  const Vec3<Real> omegaI = f.omega[i];
  const Real magI = omegaLengthOf(i, f);
  const Vec3<Real> si = f.smoothing[i];
  const bool smoothTwice = SmoothTwice && f.time->xsphHyper != Real(0);
  // Surface tension where particle i is on the surface (SurfaceTension.h).
  Real weight = Real(0);
  Vec3<Real> gradC{ Real(0), Real(0), Real(0) };
  if (Tension && f.colour)
  {
    gradC = f.colour[i];
    weight = surfaceWeight(squareRoot(dot(gradC, gradC)) * f.c.kernels.h);
  }
  // A smoothed normal of zero length (a sheet one particle thin, whose sides' gradients cancel)
  // has no direction: no force, rather than a NaN.
  if (Tension && f.colour && !(dot(f.normal[i], f.normal[i]) > Real(0)))
  {
    weight = Real(0);
  }
  const bool tension = weight > Real(0);
  const Vec3<Real> smooth = tension ? f.normal[i] : Vec3<Real>{ Real(0), Real(0), Real(1) };
  SurfaceDivergence<Real> divergence(smooth * (Real(1) / squareRoot(dot(smooth, smooth))));
  const Real gate2 = Real(kSurfaceGate * kSurfaceGate) * f.c.inverseH2;
  // The walls' images of the surface neighbours take part with their normals reflected
  // (smoothColour says why).
  WallMirrors<Real> mirrors{ { 1, 1, 1 }, { { Real(0), Real(0) }, { Real(0), Real(0) }, { Real(0), Real(0) } } };
  SolidMirror<Real> solid = noSolid<Real>();
  if (tension)
  {
    mirrors = nearWalls(pi, f.c);
    if (Solids && f.obstacleCount > 0)
    {
      solid = nearestSolid(pi, f);
    }
  }
  const bool images = hasReflections(mirrors);
  Vec3<Real> eta{ Real(0), Real(0), Real(0) };
  Vec3<Real> hyper{ Real(0), Real(0), Real(0) };
  forEachNeighbor(f.grid, i, [&](std::uint32_t j) {
    const Vec3<Real> r = pi - f.p[j];
    const Real r2 = dot(r, r);
    if (r2 < f.c.kernels.h2) // the particle itself adds zeros: no test
    {
      const Real volume = volumeOf(j, f);
      eta += f.c.kernels.spikyGradientWithin(r, r2) * (volume * (omegaLengthOf(j, f) - magI));
      if (smoothTwice)
      {
        hyper += (f.smoothing[j] - si) * (volume * f.c.kernels.poly6Within(r2));
      }
      if (tension)
      {
        const Vec3<Real> gj = f.colour[j];
        if (dot(gj, gj) > gate2) // j on the surface too (the particle itself adds zeros)
        {
          const Vec3<Real> nj = f.normal[j];
          const Real nj2 = dot(nj, nj);
          if (nj2 > Real(0)) // as particle i's own, above
          {
            const Vec3<Real> unit = nj * (Real(1) / squareRoot(nj2));
            divergence.add(unit, r, f.c.kernels.spikyGradientWithin(r, r2), volume);
            if (images)
            {
              const Vec3<Real> pj = f.p[j];
              forEachReflection(mirrors, pj, [&](const Vec3<Real>& image, int ix, int iy, int iz) {
                const Vec3<Real> ri = pi - image;
                const Real ri2 = dot(ri, ri);
                if (ri2 < f.c.kernels.h2)
                {
                  divergence.add(reflected(unit, ix, iy, iz), ri,
                    f.c.kernels.spikyGradientWithin(ri, ri2), volume);
                }
              });
            }
            if (Solids && solid.solid >= 0)
            {
              const Vec3<Real> ri = pi - solid.image(f.p[j]);
              const Real ri2 = dot(ri, ri);
              if (ri2 < f.c.kernels.h2)
              {
                divergence.add(solid.reflect(unit), ri, f.c.kernels.spikyGradientWithin(ri, ri2),
                  volume);
              }
            }
          }
        }
      }
    }
  });
  // XSPH (eq. 17) and its bi-Laplacian: v + c S_i - c_4 S(S)_i.
  Vec3<Real> v = f.v[i] + si * (f.liquid ? f.time->liquidXsph[f.liquid[i]] : f.time->xsph);
  if (smoothTwice)
  {
    v -= hyper * f.time->xsphHyper;
  }
  if (tension)
  {
    // f = -sigma (div n) grad c, as a velocity change dt f / rho_l.
    const int l = f.liquid ? f.liquid[i] : 0;
    v -= gradC * (divergence.divergence(f.c.kernels.h) * weight * f.time->tension[l]);
    // Adhesion at the nearest boundary within h: a solid nearer than every wall takes the line
    // with its own angle for this liquid, else a wall with the liquid's.
    if (Solids && solid.solid >= 0 && solid.distance < nearestWallDistance(pi, f.c))
    {
      const Real cosTheta = f.obstacles[solid.solid].contactCos[l];
      if (cosTheta != Real(0))
      {
        v += youngForce(f.normal[i], solid.n, gradC, cosTheta, solid.distance, f.c.kernels.h) *
          (weight * f.time->tension[l]);
      }
    }
    else if (f.c.wallAdhesion)
    {
      v += wallYoungForce(pi, f.normal[i], gradC, f.c, f.time->wallCos[l]) *
        (weight * f.time->tension[l]);
    }
  }
  const Real etaLength = length(eta);
  if (etaLength * f.c.kernels.h > Real(1e-4) * magI && etaLength > Real(0))
  {
    const Vec3<Real> N = eta * (Real(1) / etaLength);
    v += cross(N, omegaI) * (f.c.vorticityEpsilon * f.time->dt);
  }
  velocityOut[i] = v;
}

// Algorithm 1, line 23: x_i = x*_i. The step's start positions become the corrected ones.
template <class Real, class Neighbors>
PBF_HD PBF_INLINE void commitPosition(std::uint32_t i, const FluidView<Real, Neighbors>& f, Vec3<Real>* x)
{
  x[i] = f.p[i];
}

} // namespace pbf
