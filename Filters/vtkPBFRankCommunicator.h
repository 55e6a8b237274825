// The solver's Communicator (Solver/Distributed/Communicator.h) over ParaView's parallel engine:
// the ranks of `mpiexec -n N pvbatch` or of a pvserver, through their vtkMultiProcessController.
// Not a vtkObject: a private helper of vtkPBFSimulation.
#ifndef vtkPBFRankCommunicator_h
#define vtkPBFRankCommunicator_h

#include "Distributed/Communicator.h"

class vtkMultiProcessController;

class vtkPBFRankCommunicator final : public pbf::distributed::Communicator
{
public:
  explicit vtkPBFRankCommunicator(vtkMultiProcessController* controller);

  int rank() const override;
  int size() const override;
  // Two collectives: every rank's message lengths (AllGather), then every message (AllGatherV).
  // Each rank keeps what was sent to it. For the slab decomposition's few neighbours at a handful
  // of ranks that is the traffic point-to-point would carry; many ranks would want MPI_Alltoallv.
  std::vector<pbf::distributed::Bytes> exchange(
    const std::vector<pbf::distributed::Bytes>& outgoing) override;

private:
  vtkMultiProcessController* Controller;
};

#endif
