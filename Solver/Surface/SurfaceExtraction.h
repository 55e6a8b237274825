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

#include "SurfaceTypes.h"

#include <cstddef>

namespace pbf
{

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
