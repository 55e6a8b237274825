// The shape maps built so far in this process, by the grid and kernels they were built for. A
// run's solids are built again whenever it starts over (Apply, a pvpython script's loop over
// parameters that leave the solids alone, a test that runs a scene twice); their maps are
// integrated once (seconds of the cores for a large solid, ShapeMap.h) and copied after that.
#pragma once

#include "ShapeMap.h"

namespace pbf
{

// Fills grid.shape as buildShapeMap does, from the cache where the same field (bit for bit, the
// same nodes) was mapped before with the same kernels, walls and rule. The cache keeps the most recent
// maps up to 512 MiB; it is safe to call from several threads.
void attachShapeMap(DistanceGrid& grid, const ShapeKernels& k, const ShapeWalls& walls = {},
  const ShapeRule& rule = {});

// How many maps this process has integrated (not copied from the cache).
std::size_t shapeMapsBuilt();

} // namespace pbf
