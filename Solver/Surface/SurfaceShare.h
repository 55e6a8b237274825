// The surface of a decomposed run (Distributed/SubdomainStepper.h): each rank extracts the share
// of its slab (SurfaceShare) from its own particles and the other ranks' within
// surfaceGhostReach() of the slab, which the ranks exchange here. The shares meet without a
// crack: the same vertices, to the bit, on both sides of every slab border.
#pragma once

#include "Communicator.h"
#include "Distributed/Slabs.h"
#include "SurfaceExtraction.h"

namespace pbf
{

// The x-range of rank r's slab: columns of h from the domain's lower x; the first and last
// ranks' ranges are open towards the walls.
SurfaceShare slabShare(const distributed::Slabs& slabs, int rank, const Parameters& parameters);

// Collective: this rank's share of the surface of all ranks' particles (x, v, rho: this rank's
// n; v and rho may be null on every rank, not on some).
template <class Real>
SurfaceMesh extractSurfaceShare(distributed::Communicator& communicator, const distributed::Slabs& slabs,
  const Vec3<Real>* x, const Vec3<Real>* v, const Real* rho, std::size_t n,
  const Parameters& parameters, const SurfaceOptions& options, bool parallel,
  const SurfaceSolids& solids = {});

} // namespace pbf
