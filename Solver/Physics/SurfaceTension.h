// Surface tension as cohesion between particle pairs (Akinci, Akinci and Teschner 2013's
// cohesion kernel C(r)), in physical units: Parameters::surfaceTension sigma [N/m].
//
// A pair at distance r holds the potential energy -e Phi(r), Phi(r) = integral from r to h of
// C, so it attracts with e C(r) (C > 0 beyond 0.28 h; closer it repels, which keeps cohesion
// from clumping pairs). The pair energy e comes from the rest lattice, as s_corr's push does
// (LatticeCalibration::cohesionWork): parting the lattice along a plane costs 2 sigma per unit
// area, the work of the two surfaces it makes. So sigma means the same at any spacing and
// smoothing ratio, and a liquid's pressure rises by 2 sigma / R inside a drop of radius R.
// Between liquids a and b the pair energy is sqrt(e_a e_b) (a geometric mean), which makes their
// interfacial tension (sqrt(sigma_a) - sqrt(sigma_b))^2.
//
// The attraction acts on the velocity in the confinement pass, on the step's final positions, so
// the next step's prediction carries it (as gravity): no pass is added.
#pragma once

#include "HostDevice.h"

namespace pbf
{

// C(r) = 32 / (pi h^3) c(q) with q = r / h: Akinci's spline, dimensionless,
//   c(q) = (1 - q)^3 q^3                     for 1/2 < q <= 1,
//   c(q) = 2 (1 - q)^3 q^3 - 1/64            for 0 < q <= 1/2.
template <class Real>
PBF_HD PBF_INLINE Real cohesionSpline(Real q)
{
  const Real a = (Real(1) - q) * q;
  const Real a3 = a * a * a;
  return q > Real(0.5) ? a3 : Real(2) * a3 - Real(1) / Real(64);
}

// Phi(r) h^2 pi / 32 = integral from q to 1 of c, in closed form (host only, for the
// calibration): with F(v) = v^4/4 - 3 v^5/5 + v^6/2 - v^7/7 the antiderivative of (1 - v)^3 v^3.
double cohesionPotential(double q);

} // namespace pbf
