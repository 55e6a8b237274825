// What the particles read at points of space: SPH sums with the solver's own poly6 kernel (the one
// the density is), for gauges and probes (a ParaView Probes input, the validation's wave gauges)
// and for the pressure on a solid's surface. A rank sums over its own particles; the sums add
// over the ranks (sumInRankOrder), and only then are they read (readProbe, readPressure), so that
// a decomposed run reads what one rank would.
#pragma once

#include "Grid.h"
#include "Parameters.h"
#include "SurfaceTypes.h"
#include "Vec3.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pbf
{

// Per point, kProbeSums values: the fluid fraction F = sum_j (m / rho_0) W_ij (1 inside the fluid,
// about 1/2 on a flat free surface or a wall, 0 in air), then sum_j (m / rho_0) W_ij times p_j,
// times v_j.x, v_j.y and v_j.z.
constexpr std::size_t kProbeSums = 5;

// The particles on a grid of cells h wide over the domain, to sum over those near a point.
class ParticleSums
{
public:
  // x, v and pressure: n particles each (pressure may be null: read as 0).
  template <class Real>
  ParticleSums(const Parameters& parameters, const Vec3<Real>* x, const Vec3<Real>* v,
    const Real* pressure, std::size_t n);

  // The kProbeSums sums at each point, appended to `out` (points outside the domain read 0).
  void at(const std::vector<Vec3d>& points, std::vector<double>& out) const;

  // The pressure on the solids' surfaces [Pa], one value per point appended to `out`: points[k]
  // lies on solid solidOf[k] (an index into solids.views, where the solids stand now; -1: on
  // none, 0). It is what the boundary model pushes the solid with (SolidTerms.h's solidLoads),
  // spread over its surface: particle i presses solid o along its normal with
  // F_i = (m / rho_0)^2 2 b_spiky(d_i) p_i / G (the step's load written with the particle's
  // pressure, recordPressure; s_corr's small push aside), d_i its distance to the solid, and
  // the surface point q gets sum_i F_i K(t_i), t_i the distance from q to x_i along the surface
  // (across q's normal) and K(t) = 4 / (pi h^2) (1 - t^2 / h^2)^3 the 2D kernel of unit
  // integral: so the pressure integrates over the surface to the solid's load. Additive over
  // the ranks like at()'s sums.
  void onSolids(const SurfaceSolids& solids, const std::vector<Vec3d>& points,
    const std::vector<int>& solidOf, std::vector<double>& out) const;

private:
  // visit(k) for the particles (cell order) in the 27 cells about q.
  template <class Visit>
  void forEachNear(const Vec3d& q, Visit&& visit) const;

  Parameters parameters_;
  double h_ = 0, h2_ = 0, volume_ = 0;
  std::vector<Vec3d> x_;
  std::vector<double> values_; // per particle, in cell order: p, v.x, v.y, v.z
  std::vector<std::uint32_t> cellOffsets_;
  GridGeometry<double> grid_{}; // cells h wide over the domain, made once
};

// A probe's reading.
struct ProbeReading
{
  bool inside = false;     // within the domain; the values are NaN otherwise
  double fraction = 0;     // F at the probe
  double pressure = 0;     // [Pa]
  Vec3d velocity{ 0, 0, 0 }; // [m/s]
  double waterHeight = 0;  // the wetted length above the probe along +y [m] (gaugeColumn)
};

// Where the wave gauge above `probe` samples: every s/4 from it up to the domain's top.
std::vector<Vec3d> gaugeColumn(const Parameters& parameters, const Vec3d& probe);

// Whether the point is in the domain (a probe outside reads NaN).
bool insideDomain(const Parameters& parameters, const Vec3d& q);

// A probe's reading from the summed values at it and along its column (kProbeSums per point).
// The pressure and velocity are the sums over max(F, 1/2): the particles' weighted mean inside the
// fluid and at a wall (where F is about 1/2), fading to 0 where the fluid thins out (spray, the
// surface). The water height is the length of the column where F exceeds `wet` (1/2: the level of
// a flat surface), as a wave gauge's wire measures the wetted length; within s/2 of the domain's
// floor the threshold is halved, since the floor has no particles below to fill the kernel.
ProbeReading readProbe(const Parameters& parameters, const Vec3d& probe, const double* atProbe,
  const double* column, std::size_t samples, double wet = 0.5);

// The pressure at a point from its summed values, as readProbe reads it [Pa].
double readPressure(const double* sums);

} // namespace pbf
