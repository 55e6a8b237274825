#include "Probes.h"

#include "Boundary.h"
#include "CellSort.h"
#include "Grid.h"
#include "Kernels.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pbf
{

template <class Real>
ParticleSums::ParticleSums(const Parameters& parameters, const Vec3<Real>* x,
  const Vec3<Real>* v, const Real* pressure, std::size_t n)
  : parameters_(parameters)
{
  h_ = parameters.smoothingLength();
  h2_ = h_ * h_;
  volume_ = calibratedParticleMass(parameters) / parameters.restDensity;
  grid_ = makeGridGeometry<double>(parameters.domain, h_);
  const GridGeometry<double>& grid = grid_;
  std::vector<CellKey> keys(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    keys[i] = grid.keyOf(Vec3d::from(x[i]));
  }
  std::vector<std::uint32_t> order, cursor;
  cellOffsets_.assign(std::size_t(grid.cellCount()) + 1, 0);
  countingSortByCell(keys, cellOffsets_, order, cursor);
  x_.resize(n);
  values_.resize(4 * n);
  for (std::size_t k = 0; k < n; ++k)
  {
    const std::size_t i = order[k];
    x_[k] = Vec3d::from(x[i]);
    values_[4 * k] = pressure ? static_cast<double>(pressure[i]) : 0.0;
    values_[4 * k + 1] = static_cast<double>(v[i].x);
    values_[4 * k + 2] = static_cast<double>(v[i].y);
    values_[4 * k + 3] = static_cast<double>(v[i].z);
  }
}

template ParticleSums::ParticleSums(
  const Parameters&, const Vec3<float>*, const Vec3<float>*, const float*, std::size_t);
template ParticleSums::ParticleSums(
  const Parameters&, const Vec3<double>*, const Vec3<double>*, const double*, std::size_t);

template <class Visit>
void ParticleSums::forEachNear(const Vec3d& q, Visit&& visit) const
{
  const GridGeometry<double>& g = grid_;
  const int cx = g.clampedCell(q.x, g.origin.x, g.nx);
  const int cy = g.clampedCell(q.y, g.origin.y, g.ny);
  const int cz = g.clampedCell(q.z, g.origin.z, g.nz);
  for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, g.nz - 1); ++z)
  {
    for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, g.ny - 1); ++y)
    {
      for (int x = std::max(cx - 1, 0); x <= std::min(cx + 1, g.nx - 1); ++x)
      {
        const std::size_t cell = (static_cast<std::size_t>(z) * g.ny + y) * g.nx + x;
        for (std::uint32_t k = cellOffsets_[cell]; k < cellOffsets_[cell + 1]; ++k)
        {
          visit(k);
        }
      }
    }
  }
}

void ParticleSums::at(const std::vector<Vec3d>& points, std::vector<double>& out) const
{
  const Kernels<double> kernels = Kernels<double>::make(h_);
  for (const Vec3d& q : points)
  {
    double sums[kProbeSums] = {};
    if (insideDomain(parameters_, q))
    {
      forEachNear(q, [&](std::uint32_t k) {
        const Vec3d r = q - x_[k];
        const double r2 = dot(r, r);
        if (r2 < h2_)
        {
          const double w = volume_ * kernels.poly6(r2);
          sums[0] += w;
          for (std::size_t c = 0; c < 4; ++c)
          {
            sums[1 + c] += w * values_[4 * k + c];
          }
        }
      });
    }
    out.insert(out.end(), sums, sums + kProbeSums);
  }
}

void ParticleSums::onSolids(const SurfaceSolids& solids, const std::vector<Vec3d>& points,
  const std::vector<int>& solidOf, std::vector<double>& out) const
{
  const BoundaryTableData data = makeBoundaryTable(parameters_);
  const std::vector<double> packed = data.packed<double>();
  const BoundaryTable<double> table = data.view(packed.data());
  const double pressToForce =
    2.0 * volume_ * volume_ / calibrateLattice(parameters_).gradientMoment;
  const double pi = 3.14159265358979323846;
  const double kernel2D = 4.0 / (pi * h2_);
  for (std::size_t q = 0; q < points.size(); ++q)
  {
    const int o = solidOf[q];
    double sum = 0;
    if (o >= 0 && static_cast<std::size_t>(o) < solids.views.size() &&
      insideDomain(parameters_, points[q]))
    {
      const DistanceGridView<double>& solid = solids.views[static_cast<std::size_t>(o)];
      Vec3d gradient;
      solid.at(points[q], &gradient);
      const double g = length(gradient);
      const Vec3d n = g > 0 ? gradient * (1.0 / g) : Vec3d{ 0, 0, 0 };
      forEachNear(points[q], [&](std::uint32_t k) {
        const Vec3d r = x_[k] - points[q];
        const double along = dot(r, n);
        const double t2 = dot(r, r) - along * along;
        const double d = solid.at(x_[k], nullptr);
        if (t2 < h2_ && d < h_)
        {
          // The table's spiky sum is negative (it points into the solid): pressing is -spiky.
          const double force = -pressToForce * sampleBoundary(table, d).spiky * values_[4 * k];
          const double fade = 1.0 - t2 / h2_;
          sum += force * kernel2D * fade * fade * fade;
        }
      });
    }
    out.push_back(sum);
  }
}

bool insideDomain(const Parameters& parameters, const Vec3d& q)
{
  const Box& d = parameters.domain;
  return q.x >= d.min.x && q.x <= d.max.x && q.y >= d.min.y && q.y <= d.max.y && q.z >= d.min.z &&
    q.z <= d.max.z;
}

std::vector<Vec3d> gaugeColumn(const Parameters& parameters, const Vec3d& probe)
{
  std::vector<Vec3d> column;
  if (!insideDomain(parameters, probe))
  {
    return column;
  }
  const double dy = 0.25 * parameters.particleSpacing;
  for (double y = probe.y + 0.5 * dy; y < parameters.domain.max.y; y += dy)
  {
    column.push_back(Vec3d{ probe.x, y, probe.z });
  }
  return column;
}

double readPressure(const double* sums)
{
  return sums[1] / std::max(sums[0], 0.5);
}

ProbeReading readProbe(const Parameters& parameters, const Vec3d& probe, const double* atProbe,
  const double* column, std::size_t samples, double wet)
{
  ProbeReading r;
  r.inside = insideDomain(parameters, probe);
  if (!r.inside)
  {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    r.fraction = r.pressure = r.waterHeight = nan;
    r.velocity = Vec3d{ nan, nan, nan };
    return r;
  }
  const double fill = std::max(atProbe[0], 0.5);
  r.fraction = atProbe[0];
  r.pressure = readPressure(atProbe);
  r.velocity = Vec3d{ atProbe[2] / fill, atProbe[3] / fill, atProbe[4] / fill };
  const double dy = 0.25 * parameters.particleSpacing;
  const double floorBand = parameters.domain.min.y + 0.5 * parameters.particleSpacing;
  for (std::size_t k = 0; k < samples; ++k)
  {
    const double fraction = column[k * kProbeSums];
    const double y = probe.y + (static_cast<double>(k) + 0.5) * dy;
    r.waterHeight += fraction > wet || (y < floorBand && fraction > 0.5 * wet) ? dy : 0.0;
  }
  return r;
}

} // namespace pbf
