#include "MpiCommunicator.h"

#include <algorithm>
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
  std::vector<Bytes> incoming;
  exchangeInto(outgoing, incoming);
  return incoming;
}

void MpiCommunicator::exchangeInto(const std::vector<Bytes>& outgoing, std::vector<Bytes>& incoming)
{
  const auto n = static_cast<std::size_t>(size_);
  if (outgoing.size() != n)
  {
    throw std::invalid_argument("exchange: one buffer per rank expected");
  }
  sendCounts_.resize(n);
  receiveCounts_.resize(n);
  sendOffsets_.resize(n);
  receiveOffsets_.resize(n);
  std::size_t total = 0;
  for (std::size_t r = 0; r < n; ++r)
  {
    if (outgoing[r].size() > static_cast<std::size_t>(INT_MAX) - total)
    {
      throw std::runtime_error("exchange: more than 2 GiB for one rank's messages");
    }
    sendOffsets_[r] = static_cast<int>(total);
    sendCounts_[r] = static_cast<int>(outgoing[r].size());
    total += outgoing[r].size();
  }
  send_.resize(total + 1); // never a null buffer
  for (std::size_t r = 0; r < n; ++r)
  {
    std::copy(outgoing[r].begin(), outgoing[r].end(),
      send_.begin() + static_cast<std::ptrdiff_t>(sendOffsets_[r]));
  }
  check(MPI_Alltoall(sendCounts_.data(), 1, MPI_INT, receiveCounts_.data(), 1, MPI_INT, communicator_),
    "MPI_Alltoall");
  long long received = 0;
  for (std::size_t r = 0; r < n; ++r)
  {
    receiveOffsets_[r] = static_cast<int>(received);
    received += receiveCounts_[r];
  }
  if (received > INT_MAX)
  {
    throw std::runtime_error("exchange: more than 2 GiB of messages for one rank");
  }
  receive_.resize(static_cast<std::size_t>(received) + 1);
  check(MPI_Alltoallv(send_.data(), sendCounts_.data(), sendOffsets_.data(), MPI_BYTE,
          receive_.data(), receiveCounts_.data(), receiveOffsets_.data(), MPI_BYTE, communicator_),
    "MPI_Alltoallv");
  incoming.resize(n);
  for (std::size_t r = 0; r < n; ++r)
  {
    incoming[r].assign(receive_.begin() + receiveOffsets_[r],
      receive_.begin() + receiveOffsets_[r] + receiveCounts_[r]);
  }
}

void MpiCommunicator::exchangeKnownSizes(const std::vector<Bytes>& outgoing,
  std::vector<Bytes>& incoming, const std::vector<std::size_t>& incomingSizes)
{
  const auto n = static_cast<std::size_t>(size_);
  if (outgoing.size() != n || incomingSizes.size() != n)
  {
    throw std::invalid_argument("exchange: one buffer and one size per rank expected");
  }
  constexpr int tag = 7007; // apart from any other traffic on the communicator
  incoming.resize(n);
  requests_.clear();
  for (std::size_t r = 0; r < n; ++r)
  {
    if (incomingSizes[r] > static_cast<std::size_t>(INT_MAX) ||
      outgoing[r].size() > static_cast<std::size_t>(INT_MAX))
    {
      throw std::runtime_error("exchange: more than 2 GiB in one message");
    }
    incoming[r].resize(incomingSizes[r]);
    if (incomingSizes[r] > 0)
    {
      requests_.emplace_back();
      check(MPI_Irecv(incoming[r].data(), static_cast<int>(incomingSizes[r]), MPI_BYTE,
              static_cast<int>(r), tag, communicator_, &requests_.back()),
        "MPI_Irecv");
    }
  }
  for (std::size_t r = 0; r < n; ++r)
  {
    if (!outgoing[r].empty())
    {
      requests_.emplace_back();
      check(MPI_Isend(outgoing[r].data(), static_cast<int>(outgoing[r].size()), MPI_BYTE,
              static_cast<int>(r), tag, communicator_, &requests_.back()),
        "MPI_Isend");
    }
  }
  check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE),
    "MPI_Waitall");
}

} // namespace pbf::distributed
