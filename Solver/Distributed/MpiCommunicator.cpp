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

void MpiCommunicator::exchangeKnownSizesInPlace(const std::vector<const unsigned char*>& send,
  const std::vector<std::size_t>& sendSizes, const std::vector<unsigned char*>& receive,
  const std::vector<std::size_t>& receiveSizes)
{
  const auto n = static_cast<std::size_t>(size_);
  if (send.size() != n || sendSizes.size() != n || receive.size() != n || receiveSizes.size() != n)
  {
    throw std::invalid_argument("exchange: one buffer and one size per rank expected");
  }
  constexpr int tag = 7008; // apart from any other traffic on the communicator
  requests_.clear();
  for (std::size_t r = 0; r < n; ++r)
  {
    if (receiveSizes[r] > static_cast<std::size_t>(INT_MAX) ||
      sendSizes[r] > static_cast<std::size_t>(INT_MAX))
    {
      throw std::runtime_error("exchange: more than 2 GiB in one message");
    }
    if (receiveSizes[r] > 0)
    {
      requests_.emplace_back();
      check(MPI_Irecv(receive[r], static_cast<int>(receiveSizes[r]), MPI_BYTE,
              static_cast<int>(r), tag, communicator_, &requests_.back()),
        "MPI_Irecv");
    }
  }
  for (std::size_t r = 0; r < n; ++r)
  {
    if (sendSizes[r] > 0)
    {
      requests_.emplace_back();
      check(MPI_Isend(send[r], static_cast<int>(sendSizes[r]), MPI_BYTE, static_cast<int>(r), tag,
              communicator_, &requests_.back()),
        "MPI_Isend");
    }
  }
  statuses_.resize(requests_.size());
  check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), statuses_.data()),
    "MPI_Waitall");
  // A message longer than expected is an error (MPI_ERR_TRUNCATE above); a shorter one is one too.
  std::size_t k = 0;
  for (std::size_t r = 0; r < n; ++r)
  {
    if (receiveSizes[r] > 0)
    {
      int got = 0;
      check(MPI_Get_count(&statuses_[k], MPI_BYTE, &got), "MPI_Get_count");
      if (static_cast<std::size_t>(got) != receiveSizes[r])
      {
        throw std::runtime_error("exchange: " + std::to_string(got) + " bytes from rank " +
          std::to_string(r) + ", expected " + std::to_string(receiveSizes[r]));
      }
      ++k;
    }
  }
}

} // namespace pbf::distributed
