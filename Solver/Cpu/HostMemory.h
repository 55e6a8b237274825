// What the host has to give: a CPU stepper's memory plan checks its arrays against it before it
// makes room for them, so that a rank too small for its share gets an error that names the count
// instead of the kernel's out-of-memory kill halfway through a step.
#pragma once

#include <cstddef>

namespace pbf
{

// The bytes the kernel reckons it can give without swapping (MemAvailable of /proc/meminfo, else
// the free pages); the largest size_t where neither can be read.
std::size_t availableHostBytes();

} // namespace pbf
