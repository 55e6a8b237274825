// The surface's inputs and outputs as plain types: its options, the mesh, a rank's share and the
// solids that clip it. The CPU extractor (SurfaceExtraction.h), the pieces it shares with the GPU
// (SurfaceCells.h) and the GPU's (Cuda/CudaSurface.h) all read them.
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

} // namespace pbf
