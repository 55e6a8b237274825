#include "Boundary.h"

#include <cmath>

namespace pbf
{

BoundaryTableData makeBoundaryTable(
  double spacing, double h, double sCorrN, double wDeltaQ, int samples)
{
  const auto kernels = Kernels<double>::make(h);
  BoundaryTableData t;
  t.samples = samples;
  t.h = h;
  t.poly6.assign(samples, 0.0);
  t.spiky.assign(samples, 0.0);
  t.spiky2.assign(samples, 0.0);
  t.tensile.assign(samples, 0.0);
  const int reach = static_cast<int>(std::ceil(h / spacing)) + 1;
  for (int k = 0; k < samples; ++k)
  {
    const double d = h * k / (samples - 1);
    const Vec3d particle{ 0, 0, d };
    // The lattice through the particle, reflected in the plane: layers at -d, -d - s, ... (the
    // particle's own image first), as a mirror wall reflects the particle's neighbours. At d = s/2
    // that is the initial lattice continued; closer, the images close in as the mirror's do.
    for (int layer = 0; d + layer * spacing < h; ++layer)
    {
      for (int i = -reach; i <= reach; ++i)
      {
        for (int j = -reach; j <= reach; ++j)
        {
          const Vec3d site{ i * spacing, j * spacing, -(d + layer * spacing) };
          const Vec3d r = particle - site;
          const double r2 = dot(r, r);
          if (r2 >= kernels.h2)
          {
            continue;
          }
          const double w = kernels.poly6Within(r2);
          const Vec3d g = kernels.spikyGradientWithin(r, r2);
          t.poly6[k] += w;
          t.spiky[k] += g.z;
          t.spiky2[k] += dot(g, g);
          t.tensile[k] += g.z * -std::pow(w / wDeltaQ, sCorrN);
        }
      }
    }
  }
  return t;
}

BoundaryTableData makeBoundaryTable(const Parameters& parameters)
{
  const double h = parameters.smoothingLength();
  const double dq = parameters.sCorrDeltaQ * h;
  return makeBoundaryTable(parameters.particleSpacing, h, parameters.sCorrN,
    Kernels<double>::make(h).poly6(dq * dq));
}

} // namespace pbf
