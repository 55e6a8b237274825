// A solid's shape map: at each node of its distance grid (SignedDistance.h), the factors by which
// the solid's true shape changes the boundary's four sums (Boundary.h) from those of its tangent
// plane. The boundary table holds the sums of the lattice continued into a flat solid, exact at
// rest; a solid's edges and corners take away part of that half-space (a convex one) or add to it
// (a concave one). The factors are the kernels' integrals over the solid (ShapeIntegrals.h) over
// those over the half-space at the node's distance: the scalars of poly6 and |grad W|^2, and the
// vectors of the spiky gradient and s_corr over the half-space's normal component. On a flat face
// they are 1 and the outward normal, so the stages' sums there are the table's; the stages
// multiply the table at the particle's distance by them, trilinear between the nodes
// (SolidTerms.h, solidSample). This is the volume map of Bender et al. (2019) taken as a
// correction of the lattice's table instead of a replacement for it, so that a lattice at rest on
// a face reads rho_0 as before. (Measured on a lattice at rest around a cube, the ratio misses
// rho_0 by less than a difference of the same integrals added to the table: the table's layering
// near the particle scales with the solid's share.)
//
// A run's solids get their maps from solidFields (Solids.h) unless Parameters::exactBoundaries
// is off, through a cache (ShapeMapCache.h). A node costs about 0.14 ms of a core to integrate
// (256 rays); the nodes whose surroundings repeat another's (along a box's edges,
// RepeatedWindows.h) copy its factors instead, so a box costs about its eight corners.
//
// Nodes within h + 2 cells outside and 2 cells inside the surface are integrated (a node inside
// takes the factors of its nearest surface point, where the collision puts a particle), unless
// the field around them is a plane; the rest, on a flat face or never read within h of the solid,
// hold the flat factors.
#pragma once

#include "Parameters.h"
#include "ShapeIntegrals.h"
#include "SignedDistance.h"

#include <array>

namespace pbf
{

// The kernels of a run: h, s_corr's n and W(delta_q).
ShapeKernels shapeKernels(const Parameters& parameters);

// The domain's mirror walls as a fixed solid's map sees them (Parameters::mirrorWalls): the
// stages take the world beyond a wall as the mirror image of the inside, so a solid that meets a
// wall (a floor slab, a box standing on the floor) continues in its image there instead of
// ending at it, and the map integrates the field folded back into the domain. A moving solid's
// or a body's map is in its own frame, which the walls move through: none for them.
struct ShapeWalls
{
  bool mirror = false;
  Box domain{};
};
ShapeWalls shapeWalls(const Parameters& parameters, bool fixedSolid);

// The kShapeValues factors at x of the grid's frame, from the grid's field.
std::array<float, kShapeValues> shapeFactorsAt(const DistanceGrid& grid, const Vec3d& x,
  const ShapeKernels& k, const ShapeWalls& walls = {}, const ShapeRule& rule = {});

// Fills grid.shape: the nodes on a flat face or away from the solid take the flat factors, a node
// whose surroundings repeat an earlier node's copies that node's (RepeatedWindows.h), the rest
// are integrated (OpenMP threads; the same map whatever the threads). Returns how many nodes
// were integrated.
std::size_t buildShapeMap(DistanceGrid& grid, const ShapeKernels& k, const ShapeWalls& walls = {},
  const ShapeRule& rule = {});

} // namespace pbf
