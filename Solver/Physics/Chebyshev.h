// Chebyshev semi-iterative acceleration of the Jacobi projections (Wang 2015, "A Chebyshev
// Semi-Iterative Approach for Accelerating Projective and Position-based Dynamics").
//
// Jacobi carries a correction only a few neighbourhoods per projection, so a column of L layers
// needs on the order of L^2 projections to pass its weight to the floor; an error pattern of
// Jacobi gain mu shrinks by mu per projection. Chebyshev's iteration blends each Jacobi result
// with the positions of the projection before the last,
//   p^{k+1} = p^{k-1} + omega_{k+1} (jacobi(p^k) - p^{k-1}),
// with the weights of the Chebyshev polynomials on [-rho, rho]: a smooth pattern (mu near 1)
// then shrinks by about 1 - sqrt(2 (1 - rho)) per projection where Jacobi gives mu, while every
// pattern with |mu| <= rho still shrinks. Every position moves in the span of its own Jacobi
// corrections, so the iteration heads for the same solution, and each particle needs only its
// own past positions: the result does not depend on the order in which particles are visited.
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
