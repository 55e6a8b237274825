#include "vtkPBFRankCommunicator.h"

#include "vtkMPICommunicator.h"
#include "vtkMultiProcessController.h"

#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

vtkPBFRankCommunicator::vtkPBFRankCommunicator(vtkMultiProcessController* controller)
  : Controller(controller)
{
}

int vtkPBFRankCommunicator::rank() const
{
  return this->Controller->GetLocalProcessId();
}

int vtkPBFRankCommunicator::size() const
{
  return this->Controller->GetNumberOfProcesses();
}

namespace
{
// Tags of this exchange's messages, away from those ParaView's own remote calls use.
constexpr int LengthTag = 31471;
constexpr int MessageTag = 31472;
}

std::vector<pbf::distributed::Bytes> vtkPBFRankCommunicator::exchange(
  const std::vector<pbf::distributed::Bytes>& outgoing)
{
  if (auto* mpi = vtkMPICommunicator::SafeDownCast(this->Controller->GetCommunicator()))
  {
    return this->ExchangePointToPoint(mpi, outgoing);
  }
  return this->ExchangeGathered(outgoing);
}

std::vector<pbf::distributed::Bytes> vtkPBFRankCommunicator::ExchangePointToPoint(
  vtkMPICommunicator* mpi, const std::vector<pbf::distributed::Bytes>& outgoing)
{
  const int ranks = this->size();
  const int me = this->rank();
  const auto n = static_cast<std::size_t>(ranks);
  if (outgoing.size() != n)
  {
    throw std::invalid_argument("exchange: one buffer per rank expected");
  }
  // Every rank tells every other how much it sends (often nothing), then the messages go only
  // where there is something to send: a slab's neighbours.
  std::vector<int> sendLength(n), receiveLength(n);
  for (std::size_t r = 0; r < n; ++r)
  {
    if (outgoing[r].size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    {
      throw std::runtime_error("exchange: a message of more than 2 GiB");
    }
    sendLength[r] = static_cast<int>(outgoing[r].size());
  }
  std::vector<vtkMPICommunicator::Request> requests;
  requests.reserve(2 * n);
  auto wait = [&]() {
    if (!requests.empty() &&
      !mpi->WaitAll(static_cast<int>(requests.size()), requests.data()))
    {
      throw std::runtime_error("exchange: MPI wait failed");
    }
    requests.clear();
  };
  for (int peer = 0; peer < ranks; ++peer)
  {
    if (peer == me)
    {
      continue;
    }
    const auto p = static_cast<std::size_t>(peer);
    requests.emplace_back();
    mpi->NoBlockReceive(&receiveLength[p], 1, peer, LengthTag, requests.back());
    requests.emplace_back();
    mpi->NoBlockSend(&sendLength[p], 1, peer, LengthTag, requests.back());
  }
  wait();
  std::vector<pbf::distributed::Bytes> incoming(n);
  incoming[static_cast<std::size_t>(me)] = outgoing[static_cast<std::size_t>(me)];
  for (int peer = 0; peer < ranks; ++peer)
  {
    const auto p = static_cast<std::size_t>(peer);
    if (peer == me)
    {
      continue;
    }
    if (receiveLength[p] > 0)
    {
      incoming[p].resize(static_cast<std::size_t>(receiveLength[p]));
      requests.emplace_back();
      mpi->NoBlockReceive(reinterpret_cast<char*>(incoming[p].data()), receiveLength[p], peer,
        MessageTag, requests.back());
    }
    if (sendLength[p] > 0)
    {
      requests.emplace_back();
      mpi->NoBlockSend(reinterpret_cast<const char*>(outgoing[p].data()), sendLength[p], peer,
        MessageTag, requests.back());
    }
  }
  wait();
  return incoming;
}

std::vector<pbf::distributed::Bytes> vtkPBFRankCommunicator::ExchangeGathered(
  const std::vector<pbf::distributed::Bytes>& outgoing)
{
  const int ranks = this->size();
  const auto n = static_cast<std::size_t>(ranks);
  if (outgoing.size() != n)
  {
    throw std::invalid_argument("exchange: one buffer per rank expected");
  }
  // lengths[from * n + to]: what each rank sends to each.
  std::vector<long long> mine(n), lengths(n * n);
  pbf::distributed::Bytes packed;
  for (std::size_t to = 0; to < n; ++to)
  {
    mine[to] = static_cast<long long>(outgoing[to].size());
    packed.insert(packed.end(), outgoing[to].begin(), outgoing[to].end());
  }
  if (!this->Controller->AllGather(mine.data(), lengths.data(), static_cast<vtkIdType>(n)))
  {
    throw std::runtime_error("exchange: AllGather of the message lengths failed");
  }
  std::vector<vtkIdType> received(n), offsets(n);
  for (std::size_t from = 0; from < n; ++from)
  {
    vtkIdType total = 0;
    for (std::size_t to = 0; to < n; ++to)
    {
      total += static_cast<vtkIdType>(lengths[from * n + to]);
    }
    received[from] = total;
    offsets[from] = from == 0 ? 0 : offsets[from - 1] + received[from - 1];
  }
  pbf::distributed::Bytes all(static_cast<std::size_t>(offsets[n - 1] + received[n - 1]) + 1);
  pbf::distributed::Bytes send = packed;
  send.push_back(0); // never a null pointer, even when nothing is sent
  if (!this->Controller->AllGatherV(send.data(), all.data(),
        static_cast<vtkIdType>(packed.size()), received.data(), offsets.data()))
  {
    throw std::runtime_error("exchange: AllGatherV of the messages failed");
  }
  const std::size_t me = static_cast<std::size_t>(this->rank());
  std::vector<pbf::distributed::Bytes> incoming(n);
  for (std::size_t from = 0; from < n; ++from)
  {
    std::size_t at = static_cast<std::size_t>(offsets[from]);
    for (std::size_t to = 0; to < me; ++to)
    {
      at += static_cast<std::size_t>(lengths[from * n + to]);
    }
    const auto length = static_cast<std::size_t>(lengths[from * n + me]);
    incoming[from].assign(all.begin() + static_cast<std::ptrdiff_t>(at),
      all.begin() + static_cast<std::ptrdiff_t>(at + length));
  }
  return incoming;
}
