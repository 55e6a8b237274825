// Chebyshev semi-iterative acceleration of the Jacobi projections (Wang 2015, "A Chebyshev
// Semi-Iterative Approach for Accelerating Projective and Position-based Dynamics").
//
// Jacobi carries a correction only a few neighbourhoods per projection, so a column of L layers
// needs on the order of L^2 projections to pass its weight to the floor: a projection multiplies
// an error pattern by its factor mu (1 - omega |G|^2 / D, LatticeCalibration::jacobiGain), near
// 1 for the smooth ones. Chebyshev's iteration blends each Jacobi result
// with the positions of the projection before the last,
//   p^{k+1} = p^{k-1} + omega_{k+1} (jacobi(p^k) - p^{k-1}),
// with the weights of the Chebyshev polynomials on [-rho, rho]. A pattern that Jacobi shrinks
// (|mu| < 1) still shrinks, one with mu near 1 by about 1 - sqrt(2 (1 - rho)) per projection
// when rho is near its mu, instead of mu: a column of L layers needs on the order of L
// projections, not L^2. A pattern that Jacobi does not shrink (|mu| >= 1: the relaxation of
// lambda leaves the lattice's most amplified pattern at -1, and a surface or a splash can have
// gains beyond the lattice's) grows faster than under Jacobi; that is what makes a large rho
// unsafe. Every position moves in the span of its own Jacobi corrections, so the iteration heads
// for the same solution, and each particle needs only its own past positions: the result does
// not depend on the order in which particles are visited.
#pragma once

namespace pbf
{

// omega for the projection with 0-based index `projection` (the one that makes p^{projection+1}),
// for the spectral radius estimate rho in [0, 1); 1 (plain Jacobi) for rho = 0. The first
// projection is plain Jacobi (there is no p^{-1}); the second starts the polynomial, as Wang's
// S = 1. The recurrence is evaluated from the start in double, so every backend gets the same
// bits for the same (rho, projection).
inline double chebyshevWeight(double rho, int projection)
{
  if (!(rho > 0.0) || projection < 1)
  {
    return 1.0;
  }
  const double rho2 = rho * rho;
  double omega = 2.0 / (2.0 - rho2);
  for (int k = 2; k <= projection; ++k)
  {
    omega = 4.0 / (4.0 - rho2 * omega);
  }
  return omega;
}

} // namespace pbf
