// The solver's Communicator over MPI itself: the solver-only tools that run where ParaView is not
// (the GPU machines) and the filter under mpiexec pvbatch or a pvserver (on the MPI communicator
// of ParaView's controller). Built when CMake finds MPI.
//
// Every exchange is point-to-point (MPI_Isend, MPI_Irecv) on a duplicate of the given
// communicator, so that no other traffic matches its messages, and every wait polls one more
// receive: the notice a failing rank sends (abandon). A rank waiting for a rank that failed then
// throws the failure's error instead of waiting forever; its pending requests are cancelled, and
// the duplicate is left behind (messages in flight to a failed rank may never be received, and
// must not be matched by the next run's): recover() makes a fresh one.
#pragma once

#include "Communicator.h"

#include <mpi.h>

namespace pbf::distributed
{

class MpiCommunicator final : public Communicator
{
public:
  // Collective over `communicator` (MPI_Comm_dup).
  explicit MpiCommunicator(MPI_Comm communicator = MPI_COMM_WORLD);
  ~MpiCommunicator() override;
  MpiCommunicator(const MpiCommunicator&) = delete;
  MpiCommunicator& operator=(const MpiCommunicator&) = delete;

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  std::vector<Bytes> exchange(const std::vector<Bytes>& outgoing) override;
  // The lengths first (one integer to and from every rank), then the messages.
  void exchangeInto(const std::vector<Bytes>& outgoing, std::vector<Bytes>& incoming) override;
  // Messages only, with the ranks that send or receive something: a rank waits for its
  // neighbours only, not for the slowest rank of the run.
  void exchangeKnownSizes(const std::vector<Bytes>& outgoing, std::vector<Bytes>& incoming,
    const std::vector<std::size_t>& incomingSizes) override;
  // The same straight from and into the caller's memory (MPI_Irecv posted into it before the
  // sends): no host copy of the messages.
  bool exchangesInPlace() const override { return true; }
  void exchangeKnownSizesInPlace(const std::vector<const unsigned char*>& send,
    const std::vector<std::size_t>& sendSizes, const std::vector<unsigned char*>& receive,
    const std::vector<std::size_t>& receiveSizes) override;

  void abandon(FailureKind kind, const std::string& text) override;
  bool failed() const override { return failed_; }
  void recover() override;

private:
  void open();
  void throwIfFailed() const;
  // Waits for requests_ (statuses into statuses_), or throws another rank's failure.
  void waitAll();
  void dropPending();
  void post(const unsigned char* sendTo, std::size_t sendBytes, unsigned char* receiveFrom,
    std::size_t receiveBytes, int peer, int tag);

  MPI_Comm parent_;
  MPI_Comm communicator_ = MPI_COMM_NULL;
  int rank_ = 0;
  int size_ = 1;
  std::vector<MPI_Request> requests_;
  std::vector<int> receivesAt_; // the requests_ that are receives, and from which rank
  std::vector<MPI_Status> statuses_;
  std::vector<unsigned long long> sendLengths_, receiveLengths_;

  // The failure notice: one receive from any rank, posted while the channel is open.
  std::vector<unsigned char> notice_;
  MPI_Request noticeRequest_ = MPI_REQUEST_NULL;
  std::vector<unsigned char> announced_; // what this rank sent, kept until it is delivered
  bool failed_ = false;
  FailureKind failureKind_ = FailureKind::Other;
  std::string failureText_;
};

} // namespace pbf::distributed
