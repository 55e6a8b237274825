// The solver's Communicator over MPI itself, for the solver-only tools that run where ParaView is
// not (the GPU machines): one MPI_Alltoall of the message lengths and one MPI_Alltoallv of the
// messages per exchange. Built when CMake finds MPI.
#pragma once

#include "Communicator.h"

#include <mpi.h>

namespace pbf::distributed
{

class MpiCommunicator final : public Communicator
{
public:
  explicit MpiCommunicator(MPI_Comm communicator = MPI_COMM_WORLD);
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  std::vector<Bytes> exchange(const std::vector<Bytes>& outgoing) override;
  // Packs into and receives through buffers kept between calls, and fills `incoming` in place.
  void exchangeInto(const std::vector<Bytes>& outgoing, std::vector<Bytes>& incoming) override;
  // Non-blocking point-to-point with the ranks that send or receive something, no collective:
  // a rank waits for its neighbours only, not for the slowest rank of the run.
  void exchangeKnownSizes(const std::vector<Bytes>& outgoing, std::vector<Bytes>& incoming,
    const std::vector<std::size_t>& incomingSizes) override;
  // The same straight from and into the caller's memory (MPI_Irecv posted into it before the
  // sends): no host copy of the messages.
  bool exchangesInPlace() const override { return true; }
  void exchangeKnownSizesInPlace(const std::vector<const unsigned char*>& send,
    const std::vector<std::size_t>& sendSizes, const std::vector<unsigned char*>& receive,
    const std::vector<std::size_t>& receiveSizes) override;

private:
  Bytes send_, receive_;
  std::vector<MPI_Request> requests_;
  std::vector<MPI_Status> statuses_;
  std::vector<int> sendCounts_, receiveCounts_, sendOffsets_, receiveOffsets_;
  MPI_Comm communicator_;
  int rank_ = 0;
  int size_ = 1;
};

} // namespace pbf::distributed
