// N ranks as N threads of one process, passing messages through shared memory: the same
// Communicator the MPI runs use, so the decomposition can be tested on any machine.
#pragma once

#include "Communicator.h"

#include <functional>

namespace pbf::distributed
{

// Runs body(communicator) on `ranks` threads and waits for them. An exception on one rank stops
// the others at their next exchange and is rethrown here (the first one, by rank).
void runThreadCluster(int ranks, const std::function<void(Communicator&)>& body);

} // namespace pbf::distributed
