// Which GPU a rank takes: each rank picks its GPU by its local rank; ranks on the
// same host are numbered 0, 1, ... in rank order. Found through the Communicator alone (an
// allGather of a hash of the host name), so it works the same under any MPI launcher and with
// ThreadCluster, without reading launcher-specific environment variables.
#pragma once

#include "Communicator.h"

#include <string>

namespace pbf::distributed
{

// Collective. hostName defaults to this machine's (gethostname); the tests pass their own.
int localRank(Communicator& communicator, const std::string& hostName = {});

} // namespace pbf::distributed
