#include "MpiCommunicator.h"

#include <climits>
#include <stdexcept>
#include <string>

namespace pbf::distributed
{

namespace
{

void check(int error, const char* what)
{
  if (error != MPI_SUCCESS)
  {
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(error, text, &length);
    throw std::runtime_error(std::string(what) + ": " + std::string(text, static_cast<std::size_t>(length)));
  }
}

} // namespace

MpiCommunicator::MpiCommunicator(MPI_Comm communicator)
  : communicator_(communicator)
{
  check(MPI_Comm_rank(communicator_, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(communicator_, &size_), "MPI_Comm_size");
}

std::vector<Bytes> MpiCommunicator::exchange(const std::vector<Bytes>& outgoing)
{
  const auto n = static_cast<std::size_t>(size_);
  if (outgoing.size() != n)
  {
    throw std::invalid_argument("exchange: one buffer per rank expected");
  }
  std::vector<int> sendCounts(n), receiveCounts(n), sendOffsets(n), receiveOffsets(n);
  Bytes packed;
  for (std::size_t r = 0; r < n; ++r)
  {
    if (outgoing[r].size() > static_cast<std::size_t>(INT_MAX) - packed.size())
    {
      throw std::runtime_error("exchange: more than 2 GiB for one rank's messages");
    }
    sendOffsets[r] = static_cast<int>(packed.size());
    sendCounts[r] = static_cast<int>(outgoing[r].size());
    packed.insert(packed.end(), outgoing[r].begin(), outgoing[r].end());
  }
  check(MPI_Alltoall(sendCounts.data(), 1, MPI_INT, receiveCounts.data(), 1, MPI_INT, communicator_),
    "MPI_Alltoall");
  long long total = 0;
  for (std::size_t r = 0; r < n; ++r)
  {
    receiveOffsets[r] = static_cast<int>(total);
    total += receiveCounts[r];
  }
  Bytes all(static_cast<std::size_t>(total) + 1), send = packed;
  send.push_back(0); // never a null buffer
  check(MPI_Alltoallv(send.data(), sendCounts.data(), sendOffsets.data(), MPI_BYTE, all.data(),
          receiveCounts.data(), receiveOffsets.data(), MPI_BYTE, communicator_),
    "MPI_Alltoallv");
  std::vector<Bytes> incoming(n);
  for (std::size_t r = 0; r < n; ++r)
  {
    incoming[r].assign(all.begin() + receiveOffsets[r],
      all.begin() + receiveOffsets[r] + receiveCounts[r]);
  }
  return incoming;
}

} // namespace pbf::distributed
