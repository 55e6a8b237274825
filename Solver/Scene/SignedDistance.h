// Solids as signed distance fields: the distance to the solid's surface in metres, negative
// inside. A field is sampled once, on a regular grid of nodes in the solid's own frame, and read
// by trilinear interpolation: one lookup per particle per solid, the same on the CPU and the GPU.
// This is how FleX and PhysX hold triangle-mesh colliders, and what the volume maps of Bender et
// al. (2019) are built on.
#pragma once

#include "Boundary.h"
#include "Parameters.h"
#include "SolidMotion.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace pbf
{

// A solid's view with its pose of this step (the pose's values in Real).
template <class Real>
DistanceGridView<Real> placed(DistanceGridView<Real> view, const SolidPose& pose)
{
  view.moving = pose.moving;
  for (int k = 0; k < 9; ++k)
  {
    view.rotation[k] = static_cast<Real>(pose.rotation[k]);
  }
  view.translation = Vec3<Real>::from(pose.translation);
  view.pivot = Vec3<Real>::from(pose.pivot);
  view.pivotVelocity = Vec3<Real>::from(pose.pivotVelocity);
  view.angularVelocity = Vec3<Real>::from(pose.angularVelocity);
  return view;
}

struct DistanceGrid
{
  Vec3d origin{ 0, 0, 0 }; // the first node [m]
  double cell = 0;         // node spacing [m]
  int nx = 0, ny = 0, nz = 0;
  std::vector<float> phi; // node values [m], x fastest, then y, then z
  // The shape map (ShapeMap.h): kShapeValues per node, in the order of phi's nodes; empty: the
  // stages take the solid as its tangent plane.
  std::vector<float> shape;
  const float* shapeNodes() const { return shape.empty() ? nullptr : shape.data(); }
  // Each node's outward unit normal, 3 per node in the order of phi's: the direction from the
  // node's nearest surface point (the field's exact gradient there, where the trilinear one
  // averages across an edge). With phi it gives the node's tangent plane, which the collision
  // reads at convex edges (DistanceGridView::contact). Empty: the collision reads phi alone.
  std::vector<float> normal;
  const float* normalNodes() const { return normal.empty() ? nullptr : normal.data(); }
  // Each liquid's contact angle with the solid [degrees] (SolidRegion::contactAngle); 90: neutral.
  std::array<double, kMaxLiquids> contactAngle = [] {
    std::array<double, kMaxLiquids> neutral;
    neutral.fill(90.0);
    return neutral;
  }();

  float& node(int i, int j, int k) { return phi[index(i, j, k)]; }
  float node(int i, int j, int k) const { return phi[index(i, j, k)]; }
  std::size_t index(int i, int j, int k) const
  {
    return (static_cast<std::size_t>(k) * ny + static_cast<std::size_t>(j)) * nx +
      static_cast<std::size_t>(i);
  }
  Vec3d nodePosition(int i, int j, int k) const
  {
    return origin + Vec3d{ i * cell, j * cell, k * cell };
  }
  // The field at x, trilinear between the nodes. Beyond the grid: the value at the nearest point
  // of the grid plus the distance to it, which stays positive far from the solid. NaN where x is
  // not finite (neither inside nor outside: the particle checks name such a point).
  double at(const Vec3d& x) const;
  // The gradient of the trilinear field at x (about the outward normal near the surface); zero
  // where x is not finite.
  Vec3d gradient(const Vec3d& x) const;
  // How the stages read this grid, its node values at `nodes`, its shape map at `shapeNodes`
  // and its normals at `normalNodes` (host or device memory; null: none).
  template <class Real>
  DistanceGridView<Real> view(
    const float* nodes, const float* shapeNodes, const float* normalNodes = nullptr) const
  {
    DistanceGridView<Real> v{};
    v.origin = Vec3<Real>::from(origin);
    v.inverseCell = static_cast<Real>(1.0 / cell);
    v.nx = nx;
    v.ny = ny;
    v.nz = nz;
    v.phi = nodes;
    v.shape = shapeNodes;
    v.normal = normalNodes;
    for (int l = 0; l < kMaxLiquids; ++l)
    {
      // Exactly 0 at 90 degrees (cos of the rounded pi / 2 is 6e-17): a neutral solid adds nothing.
      const double theta = contactAngle[static_cast<std::size_t>(l)];
      v.contactCos[l] =
        theta == 90.0 ? Real(0) : static_cast<Real>(std::cos(theta * (3.14159265358979323846 / 180.0)));
    }
    return placed(v, SolidPose{});
  }
};

struct TriangleMesh
{
  std::vector<Vec3d> points;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// The signed distance of a triangle mesh on a grid over the mesh's bounds padded by `margin`,
// nodes `cell` apart (MeshDistance.cpp). Within `band` of the surface the magnitude is the distance
// to the nearest triangle; beyond it, a chamfer estimate that keeps growing away from the surface
// (infinite `band`: exact everywhere, at a cost of nodes x triangles); a node's normal points
// from its nearest surface point within the band, along phi's differences beyond it and on the
// surface. The sign comes from the
// parity of the crossings of rays along x, so a closed mesh needs no particular orientation. A
// mesh is closed when every edge is shared by two triangles (or an even number, where solids
// touch along it); an open one is InvalidInput
// naming `what` and an edge, unless `thickness` > 0: then the solid is the shell within
// thickness / 2 of the surface (a plate, a sheet of a model). Empty meshes, indices out of range
// and non-finite points are InvalidInput naming `what`.
// `within`: when given, the grid covers only the part of the mesh's bounds inside it (the part of a
// large solid that the fluid can reach); the sign still counts every triangle.
DistanceGrid meshDistance(const TriangleMesh& mesh, double cell, double margin, double thickness,
  const std::string& what, double band = std::numeric_limits<double>::infinity(),
  const Box* within = nullptr);

// The bounds of a mesh's points, after the checks meshDistance makes (InvalidInput naming `what`
// for no triangles, an index out of range, a non-finite point, a bad thickness, or an open surface
// when thickness is 0).
Box meshBounds(const TriangleMesh& mesh, double thickness, const std::string& what);

// Exact fields of the simple solids, on the same kind of grid, with their normals.
DistanceGrid sphereDistance(const Vec3d& centre, double radius, double cell, double margin);
DistanceGrid boxDistance(const Box& box, double cell, double margin);
// The box's exact field and normals on the nodes of `grid` (which may cover only part of the box).
DistanceGrid boxDistanceOn(const Box& box, DistanceGrid grid);
// A grid of zeros over `over` padded by `margin`, nodes `cell` apart; InvalidInput naming `what`
// for a bad cell or margin, or too many nodes.
DistanceGrid gridOver(const Box& over, double cell, double margin, const std::string& what);

} // namespace pbf
