#include "vtkPBFRankCommunicator.h"

#include "vtkMultiProcessController.h"

#ifdef PBF_WITH_MPI
#include "Distributed/MpiCommunicator.h"
#include "vtkMPI.h"
#include "vtkMPICommunicator.h"
#endif

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

std::unique_ptr<pbf::distributed::Communicator> MakeRankCommunicator(
  vtkMultiProcessController* controller)
{
#ifdef PBF_WITH_MPI
  if (auto* mpi = vtkMPICommunicator::SafeDownCast(controller->GetCommunicator()))
  {
    return std::make_unique<pbf::distributed::MpiCommunicator>(*mpi->GetMPIComm()->GetHandle());
  }
#endif
  return std::make_unique<vtkPBFRankCommunicator>(controller);
}

std::vector<pbf::distributed::Bytes> vtkPBFRankCommunicator::exchange(
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
