// Solid obstacles as boundaries of the fluid: what a particle near a solid feels, from the solid's
// signed distance field (Scene/SignedDistance.h) alone, one lookup per particle per solid.
//
// The solid acts as the mirror walls do (Equations.h, WallMirrors): as if the fluid were reflected
// into it. For a flat solid and a particle at distance d from it on a column of the initial
// lattice, the reflected lattice has layers at d, d + s, ... inside (the particle's own image
// first), so its sums depend only on d: they are tabulated once, over d in [0, h]
// (BoundaryTable). A solid's true shape enters through its shape map (Scene/ShapeMap.h): the
// factors, 1 and the normal on a flat face, by which its edges and corners change the sums of its
// tangent plane at the particle, multiplied onto the table (SolidTerms.h, solidSample); a solid
// without one is taken as its tangent plane. A particle of
// the initial lattice next to a flat, lattice-aligned solid then reads exactly rho_0 at rest, as
// next to a mirror wall; the solid's share enters the density, the constraint gradient of eq. 8,
// lambda's denominator (eq. 11) and the position correction (eq. 14, with lambda_i for the
// solid's share, as a mirror image carries its particle's lambda, and s_corr), and nothing else:
// the walls are free-slip, as the mirror walls are. A particle found inside a solid is moved to
// its surface along the field's gradient, as the box's collision moves it to the wall. A moving
// solid (Scene/SolidMotion.h) is read through its pose at the step's end (DistanceGridView's
// rotation and translation): the constraint and the collision push the fluid it moves into, and
// with wall friction its surface velocity is what the fluid is smoothed towards.
#pragma once

#include "HostDevice.h"
#include "Kernels.h"
#include "Parameters.h"
#include "Vec3.h"

#include <cstdint>
#include <vector>

namespace pbf
{

// The values a shape map (Scene/ShapeMap.h) holds per node: the factors of poly6, of the spiky
// gradient (a vector), of |grad W|^2 and of s_corr's vector.
constexpr int kShapeValues = 8;

// A signed distance grid (DistanceGrid) as the stages read it: raw pointers, host or device.
template <class Real>
struct DistanceGridView
{
  Vec3<Real> origin;
  Real inverseCell;
  int nx, ny, nz;
  const float* phi; // x fastest
  // Where the solid is this step (Scene/SolidMotion.h, SolidPose): a point x of the grid's frame
  // is at rotation x + translation, and moves at pivotVelocity + angularVelocity x (y - pivot).
  // A solid that never moves skips all of it (moving false), at the bits it always had.
  bool moving;
  Real rotation[9]; // rows
  Vec3<Real> translation, pivot, pivotVelocity, angularVelocity;
  // cos(theta) of each liquid's contact angle with this solid (SurfaceTension.h's adhesion);
  // 0: neutral.
  Real contactCos[kMaxLiquids];
  // The solid's shape map (Scene/ShapeMap.h), kShapeValues per node in the grid's frame; null:
  // the solid is taken as its tangent plane everywhere.
  const float* shape;
  // Each node's outward unit normal, 3 per node in the grid's frame (DistanceGrid::normal); null:
  // contact() reads the trilinear field alone.
  const float* normal;

  // The trilinear field at q and its gradient, clamped to the grid (a particle beyond the grid is
  // farther than h from the solid, whose grid is padded by h).
  PBF_HD PBF_INLINE Real at(Vec3<Real> q, Vec3<Real>* gradient) const
  {
    const Real value = atInGridFrame(toGridFrame(q), gradient);
    if (gradient)
    {
      *gradient = toWorldDirection(*gradient);
    }
    return value;
  }

  // Whether the grid-frame point `local` lies on the grid. Written so that a NaN coordinate counts
  // as on it, where at() clamps it.
  PBF_HD PBF_INLINE bool onGrid(const Vec3<Real>& local) const
  {
    const Real u[3] = { (local.x - origin.x) * inverseCell, (local.y - origin.y) * inverseCell,
      (local.z - origin.z) * inverseCell };
    return !(u[0] < Real(0) || u[1] < Real(0) || u[2] < Real(0) || u[0] > Real(nx - 1) ||
      u[1] > Real(ny - 1) || u[2] > Real(nz - 1));
  }

  // The field and its gradient at q where q lies on the grid; false beyond it, where the solid is
  // farther than h (the grid is padded by h), without reading a node: a particle pays the lookup
  // of the solids near it only, however many the scene holds.
  PBF_HD PBF_INLINE bool within(const Vec3<Real>& q, Real* value, Vec3<Real>* gradient) const
  {
    const Vec3<Real> local = toGridFrame(q);
    if (!onGrid(local))
    {
      return false;
    }
    *value = atInGridFrame(local, gradient);
    *gradient = toWorldDirection(*gradient);
    return true;
  }

  // Where the collision reads the solid: within() where the grid has no normals; with them, the
  // lower of the trilinear field and the highest of the cell's 8 node tangent planes
  // phi_k + n_k . (q - x_k), along that plane's normal. At a convex edge the trilinear field reads
  // a point just inside as outside (the nodes beyond the edge average in up to about 0.3 of a
  // cell), while every tangent plane of a convex field lies below it and the faces' planes meet
  // exactly at the edge; at a concave edge the trilinear field is the lower one, as it was.
  PBF_HD PBF_INLINE bool contact(const Vec3<Real>& q, Real* value, Vec3<Real>* direction) const
  {
    const Vec3<Real> local = toGridFrame(q);
    if (!onGrid(local))
    {
      return false;
    }
    *value = atInGridFrame(local, direction);
    // A cell away the trilinear field overestimates by less than a cell: nothing to read there.
    if (normal && *value * inverseCell < Real(1))
    {
      lowerToNodePlanes(local, value, direction);
    }
    *direction = toWorldDirection(*direction);
    return true;
  }

  // The highest of the 8 tangent planes phi_k + n_k . (q - x_k) of the nodes of the cell around
  // the grid-frame point `local`, where it lies below *value: *value and *direction (grid frame)
  // become that plane's. It costs the corrections 8 registers (56 to 64, out of line too): the
  // GPU's corrections compile the solids in only where a scene has some (StepPasses.h).
  PBF_HD PBF_INLINE void lowerToNodePlanes(
    const Vec3<Real>& local, Real* value, Vec3<Real>* direction) const
  {
    int i[3];
    Real t[3];
    cellOf(local, i, t);
    Real highest = Real(0);
    Vec3<Real> along{ Real(0), Real(0), Real(0) };
#if defined(__CUDA_ARCH__)
#pragma unroll 1
#endif
    for (int corner = 0; corner < 8; ++corner)
    {
      const int d[3] = { corner & 1, (corner >> 1) & 1, (corner >> 2) & 1 };
      const std::size_t node =
        (static_cast<std::size_t>(i[2] + d[2]) * ny + (i[1] + d[1])) * nx + (i[0] + d[0]);
      const Vec3<Real> n{ static_cast<Real>(normal[3 * node]),
        static_cast<Real>(normal[3 * node + 1]), static_cast<Real>(normal[3 * node + 2]) };
      const Real plane = static_cast<Real>(phi[node]) +
        (n.x * (t[0] - Real(d[0])) + n.y * (t[1] - Real(d[1])) + n.z * (t[2] - Real(d[2]))) /
          inverseCell;
      if (corner == 0 || plane > highest)
      {
        highest = plane;
        along = n;
      }
    }
    if (highest < *value && dot(along, along) > Real(0))
    {
      *value = highest;
      *direction = along;
    }
  }

  // A world point in the grid's frame (itself when the solid never moves).
  PBF_HD PBF_INLINE Vec3<Real> toGridFrame(const Vec3<Real>& q) const
  {
    if (!moving)
    {
      return q;
    }
    const Vec3<Real> d = q - translation;
    return { rotation[0] * d.x + rotation[3] * d.y + rotation[6] * d.z,
      rotation[1] * d.x + rotation[4] * d.y + rotation[7] * d.z,
      rotation[2] * d.x + rotation[5] * d.y + rotation[8] * d.z };
  }

  // A direction of the grid's frame in the world's.
  PBF_HD PBF_INLINE Vec3<Real> toWorldDirection(const Vec3<Real>& l) const
  {
    if (!moving)
    {
      return l;
    }
    return { rotation[0] * l.x + rotation[1] * l.y + rotation[2] * l.z,
      rotation[3] * l.x + rotation[4] * l.y + rotation[5] * l.z,
      rotation[6] * l.x + rotation[7] * l.y + rotation[8] * l.z };
  }

  // The cell of the grid's frame point q, clamped to the grid: its first node i and q's place t
  // in it.
  PBF_HD PBF_INLINE void cellOf(const Vec3<Real>& q, int i[3], Real t[3]) const
  {
    const Real u[3] = { (q.x - origin.x) * inverseCell, (q.y - origin.y) * inverseCell,
      (q.z - origin.z) * inverseCell };
    const int n[3] = { nx, ny, nz };
    for (int a = 0; a < 3; ++a)
    {
      // Written so that a NaN coordinate (a diverged particle, reported by the health check
      // after the step) reads node 0 instead of converting NaN to int.
      Real c = u[a] > Real(0) ? u[a] : Real(0);
      c = c < Real(n[a] - 1) ? c : Real(n[a] - 1);
      i[a] = static_cast<int>(c);
      i[a] = i[a] > n[a] - 2 ? n[a] - 2 : i[a];
      t[a] = c - Real(i[a]);
    }
  }

  // The shape map at the world point q, trilinear between the nodes; the vectors in the world's
  // frame. Only for a grid with a shape map.
  PBF_HD PBF_INLINE void shapeAt(const Vec3<Real>& q, Real values[kShapeValues]) const
  {
    int i[3];
    Real t[3];
    cellOf(toGridFrame(q), i, t);
    for (int v = 0; v < kShapeValues; ++v)
    {
      values[v] = Real(0);
    }
    // One corner at a time: unrolled, the corners' 64 loads would all be in flight at once, and
    // their registers would count against every pass that reads a solid.
#if defined(__CUDA_ARCH__)
#pragma unroll 1
#endif
    for (int corner = 0; corner < 8; ++corner)
    {
      const int d[3] = { corner & 1, (corner >> 1) & 1, (corner >> 2) & 1 };
      const Real w = (d[0] ? t[0] : Real(1) - t[0]) * (d[1] ? t[1] : Real(1) - t[1]) *
        (d[2] ? t[2] : Real(1) - t[2]);
      const float* node = shape +
        ((static_cast<std::size_t>(i[2] + d[2]) * ny + (i[1] + d[1])) * nx + (i[0] + d[0])) *
          kShapeValues;
      for (int v = 0; v < kShapeValues; ++v)
      {
        values[v] += w * static_cast<Real>(node[v]);
      }
    }
    const Vec3<Real> spiky = toWorldDirection({ values[1], values[2], values[3] });
    const Vec3<Real> tensile = toWorldDirection({ values[5], values[6], values[7] });
    values[1] = spiky.x, values[2] = spiky.y, values[3] = spiky.z;
    values[5] = tensile.x, values[6] = tensile.y, values[7] = tensile.z;
  }

  // The field at q given in the grid's own frame.
  PBF_HD PBF_INLINE Real atInGridFrame(const Vec3<Real>& q, Vec3<Real>* gradient) const
  {
    int i[3];
    Real t[3];
    cellOf(q, i, t);
    Real value = Real(0);
    Real g[3] = { Real(0), Real(0), Real(0) };
    for (int corner = 0; corner < 8; ++corner)
    {
      const int d[3] = { corner & 1, (corner >> 1) & 1, (corner >> 2) & 1 };
      const Real node = static_cast<Real>(
        phi[(static_cast<std::size_t>(i[2] + d[2]) * ny + (i[1] + d[1])) * nx + (i[0] + d[0])]);
      Real w[3];
      for (int a = 0; a < 3; ++a)
      {
        w[a] = d[a] ? t[a] : Real(1) - t[a];
      }
      value += w[0] * w[1] * w[2] * node;
      g[0] += (d[0] ? Real(1) : Real(-1)) * w[1] * w[2] * node;
      g[1] += (d[1] ? Real(1) : Real(-1)) * w[0] * w[2] * node;
      g[2] += (d[2] ? Real(1) : Real(-1)) * w[0] * w[1] * node;
    }
    if (gradient)
    {
      *gradient = Vec3<Real>{ g[0], g[1], g[2] } * inverseCell;
    }
    return value;
  }

  // The solid's velocity at the world point q (zero when it does not move).
  PBF_HD PBF_INLINE Vec3<Real> velocityAt(const Vec3<Real>& q) const
  {
    if (!moving)
    {
      return { Real(0), Real(0), Real(0) };
    }
    return pivotVelocity + cross(angularVelocity, q - pivot);
  }
};

// The sums over the reflected lattice beyond a flat surface, for a particle at distance d from it
// (d in [0, h], `samples` points, linear between them), along the surface's outward normal n:
//   poly6:   sum W(r)                                   (density, before the mass)
//   spiky:   sum gradW(r) . n                           (eq. 8 and 14, before m / rho_0)
//   spiky2:  sum |gradW(r)|^2                           (eq. 11's denominator)
//   tensile: sum gradW(r) . n (-(W(r) / W(delta_q))^n)  (s_corr, before this step's coefficient)
// with r from the lattice site to the particle.
template <class Real>
struct BoundaryTable
{
  int samples;
  Real inverseStep; // (samples - 1) / h
  const Real* poly6;
  const Real* spiky;
  const Real* spiky2;
  const Real* tensile;
};

template <class Real>
struct BoundarySample
{
  Real poly6, spiky, spiky2, tensile;
};

template <class Real>
PBF_HD PBF_INLINE BoundarySample<Real> sampleBoundary(const BoundaryTable<Real>& table, Real d)
{
  Real u = (d < Real(0) ? Real(0) : d) * table.inverseStep;
  const Real last = Real(table.samples - 1);
  u = u > last ? last : u;
  int k = static_cast<int>(u);
  k = k > table.samples - 2 ? table.samples - 2 : k;
  const Real t = u - Real(k);
  auto lerp = [&](const Real* a) { return a[k] + (a[k + 1] - a[k]) * t; };
  return { lerp(table.poly6), lerp(table.spiky), lerp(table.spiky2), lerp(table.tensile) };
}

// The table's values, computed in double on the host: the particle at (0, 0, d) and its lattice
// column's layers reflected in the plane z = 0 (sites at z = -d, -d - s, ...).
struct BoundaryTableData
{
  std::vector<double> poly6, spiky, spiky2, tensile;
  int samples = 0;
  double h = 0;

  // The four columns one after the other in Real (poly6, spiky, spiky2, tensile), for one copy to
  // wherever the steps run, and the table's view of such an array there.
  template <class Real>
  std::vector<Real> packed() const
  {
    std::vector<Real> values;
    for (const std::vector<double>* column : { &poly6, &spiky, &spiky2, &tensile })
    {
      for (double v : *column)
      {
        values.push_back(static_cast<Real>(v));
      }
    }
    return values;
  }
  template <class Real>
  BoundaryTable<Real> view(const Real* packedValues) const
  {
    const auto n = static_cast<std::size_t>(samples);
    return { samples, static_cast<Real>((samples - 1) / h), packedValues, packedValues + n,
      packedValues + 2 * n, packedValues + 3 * n };
  }
};
BoundaryTableData makeBoundaryTable(double spacing, double h, double sCorrN, double wDeltaQ,
  int samples = 129);
// The table of a run's parameters: its spacing, h, s_corr's n and W(delta_q).
BoundaryTableData makeBoundaryTable(const Parameters& parameters);

} // namespace pbf
