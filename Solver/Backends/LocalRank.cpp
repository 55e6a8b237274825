#include "LocalRank.h"

#include <unistd.h>

#include <cstdint>
#include <vector>

namespace pbf::distributed
{

namespace
{

// FNV-1a, cut to 52 bits so that it survives allGather's doubles exactly. Two hosts whose names
// collide would share a numbering: their ranks then spread over more device indices than each
// host has, and the modulo by the device count still gives every rank a valid device.
double hostHash(const std::string& name)
{
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : name)
  {
    h ^= c;
    h *= 1099511628211ull;
  }
  return static_cast<double>(h & ((std::uint64_t(1) << 52) - 1));
}

std::string thisHost()
{
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0)
  {
    return "unknown";
  }
  return name;
}

} // namespace

int localRank(Communicator& communicator, const std::string& hostName)
{
  const double mine = hostHash(hostName.empty() ? thisHost() : hostName);
  const std::vector<std::vector<double>> all = allGather(communicator, { mine });
  int local = 0;
  for (int r = 0; r < communicator.rank(); ++r)
  {
    if (all[static_cast<std::size_t>(r)][0] == mine)
    {
      ++local;
    }
  }
  return local;
}

} // namespace pbf::distributed
