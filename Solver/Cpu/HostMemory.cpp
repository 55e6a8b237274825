#include "HostMemory.h"

#include <fstream>
#include <limits>
#include <string>

#include <unistd.h>

namespace pbf
{

std::size_t availableHostBytes()
{
  std::ifstream meminfo("/proc/meminfo");
  std::string field;
  std::size_t kilobytes = 0;
  std::string unit;
  while (meminfo >> field >> kilobytes >> unit)
  {
    if (field == "MemAvailable:")
    {
      return kilobytes * 1024;
    }
  }
  const long pages = sysconf(_SC_AVPHYS_PAGES);
  const long size = sysconf(_SC_PAGESIZE);
  if (pages > 0 && size > 0)
  {
    return static_cast<std::size_t>(pages) * static_cast<std::size_t>(size);
  }
  return std::numeric_limits<std::size_t>::max();
}

} // namespace pbf
