// What each structure of a neighbour pass would cost on a given state, counted rather than
// timed: the lane slots a GPU warp spends per particle and how many of them hold a pair within h.
// Issue 21 asked for a structure chosen by measurement; these counts compare the one the CUDA
// backend runs (a lane per particle walking its row masks, NeighborMasks.h) with cluster-pair
// tiles as molecular-dynamics codes run them on GPUs (GROMACS: i-clusters of M particles against
// j-clusters of N, a warp per tile of M x N pairs, each pair once). A slot is one lane of one
// warp instruction stream visiting one candidate: a lane that has finished, or whose candidate
// lies beyond h, still occupies its slot while the others work.
#pragma once

#include "Grid.h"
#include "Vec3.h"

#include <cstdint>
#include <vector>

namespace pbf
{

// Particles in cell order, as the steppers sort them (a stable sort by cell key).
struct CellSortedParticles
{
  GridGeometry<double> geometry;
  std::vector<Vec3d> position;
  std::vector<CellKey> key;
  std::vector<std::uint32_t> cellOffsets; // cellCount + 1 entries
};

CellSortedParticles sortByCell(const std::vector<Vec3d>& position, const GridGeometry<double>& g);

struct ClusterShape
{
  int i = 8; // particles per i-cluster (consecutive in cell order)
  int j = 8; // particles per j-cluster
};

struct ClusterPairCensus
{
  ClusterShape shape;
  double slotsPerParticle = 0;     // M x N per cluster pair in the list, over the particles
  double slotsOncePerParticle = 0; // the same with each pair of clusters once (Newton's third law)
  double hitFraction = 0;          // pairs within h over slots (both sides)
  double clusterPairsPerCluster = 0;
};

struct PairCensus
{
  std::size_t particles = 0;
  double withinH = 0;       // candidates within h per particle, itself included
  double cellWalk = 0;      // candidates in the 27 cells per particle
  double maskVisits = 0;    // candidates a mask walk visits per particle (h + skin, tails)
  // A warp of 32 consecutive particles runs as long as its busiest lane: 32 times its largest
  // count, per particle.
  double cellWalkSlots = 0;
  double maskSlots = 0;
  // The masks walked for j > i only (each pair once, its other half scattered to j): the lanes'
  // side of "each pair once" without tiles.
  double maskOnceSlots = 0;
  double maskHitFraction = 0; // withinH / maskSlots: the lanes doing a pair's arithmetic
  std::vector<ClusterPairCensus> clusters;
};

// Counts on particles sorted by cell (cells of size h). skin: the masks' and the cluster pair
// list's margin beyond h [m]; both are built once per step with it.
PairCensus countPairs(const CellSortedParticles& particles, double h, double skin,
  const std::vector<ClusterShape>& shapes);

} // namespace pbf
