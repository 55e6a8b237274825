// The solver's Communicator (Solver/Stepper/Communicator.h) over ParaView's parallel engine:
// the ranks of `mpiexec -n N pvbatch` or of a pvserver, through their vtkMultiProcessController.
#ifndef vtkPBFRankCommunicator_h
#define vtkPBFRankCommunicator_h

#include "Communicator.h"

#include <memory>

class vtkMultiProcessController;

// The communicator of a decomposed run over the controller's ranks: the solver's MPI one
// (pbf::distributed::MpiCommunicator, on a duplicate of the controller's MPI communicator) where
// the controller runs over MPI, as under mpiexec pvbatch or a pvserver; vtkPBFRankCommunicator
// otherwise.
std::unique_ptr<pbf::distributed::Communicator> MakeRankCommunicator(
  vtkMultiProcessController* controller);

// Over a controller without MPI: two collectives per exchange, every rank's lengths (AllGather)
// and every message (AllGatherV), each rank keeping what was sent to it. Not a vtkObject: a
// private helper of vtkPBFSimulation.
class vtkPBFRankCommunicator final : public pbf::distributed::Communicator
{
public:
  explicit vtkPBFRankCommunicator(vtkMultiProcessController* controller);

  int rank() const override;
  int size() const override;
  std::vector<pbf::distributed::Bytes> exchange(
    const std::vector<pbf::distributed::Bytes>& outgoing) override;

private:
  vtkMultiProcessController* Controller;
};

#endif
