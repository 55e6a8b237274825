// The fluid's surface as a triangle mesh: the level set of the SPH colour function
//   phi(x) = sum_j (m / rho_0) W_poly6(x - x_j)
// at isoValue (1/2: where the smoothed occupancy is half, s/2 beyond the last layer of a flat
// lattice), sampled on a grid of nodes resolution x s apart, triangulated cell by cell.
//
// Narrow band: the grid exists only as blocks of 8^3 cells within h of a particle, sampled one at
// a time; a block whose nodes all lie on one side of the level is dropped at once. What is kept
// grows with the surface's area, not with the box or the fluid's volume. (Every block within h of
// a particle is sampled: a test that skipped the fluid's interior by counting the particles of
// its cells left holes where a surface ran through a nearly full region.)
//
// Triangulation: each cell is cut into six tetrahedra around its main diagonal (Kuhn's
// triangulation, the same diagonal on both sides of every face), each tetrahedron cut by the
// linear level set (one or two triangles). A vertex is keyed by the grid edge it lies on, so the
// cells and blocks that share an edge share the vertex: a surface inside the band is closed, with
// no crack at a block's face. The result depends only on the particles and the options, not on
// the number of threads: blocks are sampled in parallel and joined in their order, vertices in
// key order.
#pragma once

#include "Boundary.h"
#include "Parameters.h"
#include "Vec3.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pbf
{

struct SurfaceOptions
{
  double resolution = 0.5; // node spacing / particle spacing, in (0, 4]
  double isoValue = 0.5;   // of the colour function, in (0, 1)
  int smoothing = 0;       // Laplacian smoothing passes over the vertices (0..100)
  // Anisotropic kernels (Yu & Turk 2013, SurfaceCells.h): flatter water surfaces and thin
  // sheets. They reach 1.59 h, so the surface costs about 3 to 4 times as much.
  bool anisotropic = false;

  // Throws InvalidInput naming the field and value.
  void validate() const;
};

struct SurfaceMesh
{
  std::vector<Vec3<float>> points;
  std::vector<Vec3<float>> normals;  // outward unit normals (minus the colour's gradient)
  std::vector<Vec3<float>> velocity; // the particles' velocity interpolated (Shepard, poly6)
  std::vector<float> density;        // likewise
  std::vector<std::array<std::uint32_t, 3>> triangles; // counter-clockwise seen from outside

  // What the narrow band held: blocks sampled, blocks kept (the level passes through them),
  // nodes sampled.
  std::size_t sampledBlocks = 0;
  std::size_t keptBlocks = 0;
  std::size_t sampledNodes = 0;
  std::size_t peakBytes = 0; // the largest working memory of the extraction [bytes]
};

// A rank's share of a decomposed run's surface: the cells of the blocks whose lower x lies in
// [xMin, xMax) (its slab). Given its own particles and its neighbours' within surfaceGhostReach()
// of the slab, every rank's share is exactly the part of the whole surface in those blocks: the
// grid is anchored at the domain, and the particles of a cell are summed in the order of their
// positions, so the vertices where two shares meet are the same bits on both sides.
struct SurfaceShare
{
  double xMin = -HUGE_VAL;
  double xMax = HUGE_VAL;
};
// The solid obstacles where they stand at the frame's time (DistanceGrid::view, placed with the
// frame's poses; host memory): they clip the surface. The fluid ends at a solid's face, so the
// surface there is a cap lying on the face (closed, as everywhere), not a bulge into the solid:
// the colour is taken as min(phi, iso + d / cell) with d the signed distance to the solid.
struct SurfaceSolids
{
  std::vector<DistanceGridView<double>> views;
};

// How far beyond a share's x-range the particles it needs reach [m].
double surfaceGhostReach(const Parameters& parameters, const SurfaceOptions& options);

// The surface of n particles (positions x, velocities v, densities rho; v and rho may be null:
// their arrays are then left empty) under the parameters' domain, spacing, h, rest density and
// mass. `parallel`: OpenMP over the blocks (the same mesh either way). Throws InvalidInput for
// bad options or non-finite positions.
template <class Real>
SurfaceMesh extractSurface(const Vec3<Real>* x, const Vec3<Real>* v, const Real* rho,
  std::size_t n, const Parameters& parameters, const SurfaceOptions& options, bool parallel,
  const SurfaceShare& share = {}, const SurfaceSolids& solids = {});

} // namespace pbf
