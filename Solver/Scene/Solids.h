// The solid obstacles of a scene ("obstacles" in its JSON): boxes and spheres the fluid flows
// around, turned into signed distance fields at the run's resolution, and the initial fluid that
// lies inside them removed.
#pragma once

#include "Parameters.h"
#include "SignedDistance.h"
#include "Stepper.h"

#include <vector>

namespace pbf
{

struct SolidRegion
{
  enum class Kind
  {
    Box,
    Sphere
  };
  Kind kind = Kind::Box;
  Box box;         // Kind::Box
  Vec3d center;    // Kind::Sphere
  double radius = 0;
};

// The field of each solid: nodes s/2 apart (coarser only beyond 2^24 nodes) over the part of the
// solid within h of the domain, padded by h (the reach of the boundary's sums). Throws InvalidInput naming the solid when it
// lies wholly outside the domain.
std::vector<DistanceGrid> solidFields(const std::vector<SolidRegion>& solids, const Parameters& p);

// The particles whose centres are outside every solid (the field >= 0), in order, their ids
// renumbered 0..N-1; `removed` receives how many were inside.
ParticleBatch outsideSolids(
  const ParticleBatch& batch, const std::vector<DistanceGrid>& fields, std::size_t& removed);

} // namespace pbf
