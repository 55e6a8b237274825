// The solver's Communicator (Solver/Distributed/Communicator.h) over ParaView's parallel engine:
// the ranks of `mpiexec -n N pvbatch` or of a pvserver, through their vtkMultiProcessController.
// Not a vtkObject: a private helper of vtkPBFSimulation.
#ifndef vtkPBFRankCommunicator_h
#define vtkPBFRankCommunicator_h

#include "Distributed/Communicator.h"

class vtkMPICommunicator;
class vtkMultiProcessController;

class vtkPBFRankCommunicator final : public pbf::distributed::Communicator
{
public:
  explicit vtkPBFRankCommunicator(vtkMultiProcessController* controller);

  int rank() const override;
  int size() const override;
  // Over MPI (mpiexec pvbatch, pvserver): each rank tells every other how many bytes it sends,
  // then non-blocking sends and receives carry the messages, so a slab's bytes go only to its
  // neighbours. Under another controller: two collectives, every rank's lengths (AllGather) and
  // every message (AllGatherV), each rank keeping what was sent to it.
  std::vector<pbf::distributed::Bytes> exchange(
    const std::vector<pbf::distributed::Bytes>& outgoing) override;

private:
  std::vector<pbf::distributed::Bytes> ExchangePointToPoint(
    vtkMPICommunicator* mpi, const std::vector<pbf::distributed::Bytes>& outgoing);
  std::vector<pbf::distributed::Bytes> ExchangeGathered(
    const std::vector<pbf::distributed::Bytes>& outgoing);

  vtkMultiProcessController* Controller;
};

#endif
