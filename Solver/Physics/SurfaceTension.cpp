#include "SurfaceTension.h"

namespace pbf
{
namespace
{

// The antiderivative of (1 - v)^3 v^3 = v^3 - 3 v^4 + 3 v^5 - v^6.
double F(double v)
{
  const double v4 = v * v * v * v;
  return v4 * (1.0 / 4.0 - v * (3.0 / 5.0 - v * (1.0 / 2.0 - v / 7.0)));
}

} // namespace

double cohesionPotential(double q)
{
  if (q >= 1.0)
  {
    return 0.0;
  }
  if (q > 0.5)
  {
    return F(1.0) - F(q);
  }
  // Below 1/2 the spline is 2 (1 - v)^3 v^3 - 1/64.
  return (F(1.0) - F(0.5)) + 2.0 * (F(0.5) - F(q)) - (0.5 - q) / 64.0;
}

} // namespace pbf
