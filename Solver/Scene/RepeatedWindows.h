// Nodes of a grid whose surroundings repeat. A quantity computed at a node from the grid's
// values within a window of nodes around it alone is the same, to rounding, at every node whose
// window holds the same values: along a box's edge, every node of one cross-section; along a
// face, every node of one depth. Grouping them lets the quantity be computed once per group
// (ShapeMap.cpp integrates one node of each).
#pragma once

#include "SignedDistance.h"

#include <cstdint>
#include <vector>

namespace pbf
{

// A node's indices along x, y and z from its index in phi's order.
struct GridNode
{
  int i, j, k;
};
GridNode gridNode(const DistanceGrid& g, std::int64_t index);

// For each node marked in `marked` (one flag per node of g, in phi's order), the first marked
// node in index order whose window of `radius` nodes on each side holds bit for bit the same
// values (beyond the grid's edge: the same pattern of missing nodes); -1 for unmarked nodes.
// Candidates are grouped by a hash of their windows and checked value by value, so a hash that
// collides costs a comparison, never a wrong group. The result does not depend on the threads.
std::vector<std::int64_t> repeatedWindows(
  const DistanceGrid& g, const std::vector<std::uint8_t>& marked, int radius);

} // namespace pbf
