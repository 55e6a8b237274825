#include "MpiCommunicator.h"

#include "RankFailure.h"

#include <algorithm>
#include <climits>
#include <stdexcept>
#include <string>
#include <thread>

namespace pbf::distributed
{

namespace
{

// Tags apart from each other (a length is never taken for a message) and from other traffic.
constexpr int kLengthTag = 7006;
constexpr int kMessageTag = 7007;
constexpr int kNoticeTag = 7009;
// A notice is the failure's kind (one byte) and its text, cut to fit.
constexpr std::size_t kNoticeBytes = 4096;

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

int messageLength(std::size_t bytes)
{
  if (bytes > static_cast<std::size_t>(INT_MAX))
  {
    throw std::runtime_error("exchange: more than 2 GiB in one message");
  }
  return static_cast<int>(bytes);
}

void cancel(MPI_Request& request)
{
  if (request != MPI_REQUEST_NULL)
  {
    MPI_Cancel(&request);
    MPI_Request_free(&request);
  }
}

} // namespace

MpiCommunicator::MpiCommunicator(MPI_Comm communicator)
  : parent_(communicator)
{
  open();
}

MpiCommunicator::~MpiCommunicator()
{
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (finalized || failed_)
  {
    return; // a failed channel is left behind (see the header)
  }
  cancel(noticeRequest_);
  MPI_Comm_free(&communicator_);
}

void MpiCommunicator::open()
{
  check(MPI_Comm_dup(parent_, &communicator_), "MPI_Comm_dup");
  check(MPI_Comm_rank(communicator_, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(communicator_, &size_), "MPI_Comm_size");
  notice_.assign(kNoticeBytes, 0);
  check(MPI_Irecv(notice_.data(), static_cast<int>(kNoticeBytes), MPI_BYTE, MPI_ANY_SOURCE,
          kNoticeTag, communicator_, &noticeRequest_),
    "MPI_Irecv");
  failed_ = false;
  failureText_.clear();
}

void MpiCommunicator::recover()
{
  if (!failed_)
  {
    return;
  }
  // The failed duplicate and what is in flight on it stay behind; the next run talks on a new one.
  cancel(noticeRequest_);
  open();
}

void MpiCommunicator::throwIfFailed() const
{
  if (failed_)
  {
    throwRankFailure(failureKind_, failureText_);
  }
}

void MpiCommunicator::abandon(FailureKind kind, const std::string& text)
{
  if (failed_)
  {
    return;
  }
  failed_ = true;
  failureKind_ = kind;
  failureText_ = text;
  dropPending();
  cancel(noticeRequest_);
  // Kept by the object: MPI may read it after the sends are freed (a failed channel is never
  // reused, and the notice is small enough to go eagerly).
  announced_.assign(1, static_cast<unsigned char>(kind));
  announced_.insert(announced_.end(), text.begin(),
    text.begin() + static_cast<std::ptrdiff_t>(std::min(text.size(), kNoticeBytes - 1)));
  for (int r = 0; r < size_; ++r)
  {
    if (r != rank_)
    {
      MPI_Request request = MPI_REQUEST_NULL;
      if (MPI_Isend(announced_.data(), static_cast<int>(announced_.size()), MPI_BYTE, r,
            kNoticeTag, communicator_, &request) == MPI_SUCCESS)
      {
        MPI_Request_free(&request);
      }
    }
  }
}

void MpiCommunicator::dropPending()
{
  for (MPI_Request& request : requests_)
  {
    cancel(request);
  }
  requests_.clear();
  receivesAt_.clear();
}

void MpiCommunicator::waitAll()
{
  statuses_.resize(requests_.size());
  for (;;)
  {
    int done = 0;
    check(MPI_Testall(static_cast<int>(requests_.size()), requests_.data(), &done, statuses_.data()),
      "MPI_Testall");
    if (done)
    {
      return;
    }
    int noticed = 0;
    MPI_Status status;
    check(MPI_Test(&noticeRequest_, &noticed, &status), "MPI_Test");
    if (noticed)
    {
      int length = 0;
      MPI_Get_count(&status, MPI_BYTE, &length);
      failed_ = true;
      failureKind_ = length > 0 ? static_cast<FailureKind>(notice_[0]) : FailureKind::Other;
      failureText_ = length > 1
        ? std::string(notice_.begin() + 1, notice_.begin() + length)
        : "rank " + std::to_string(status.MPI_SOURCE) + " failed";
      dropPending();
      throwRankFailure(failureKind_, failureText_);
    }
    // The ranks of a run often share cores (and OpenMP threads): give them the core.
    std::this_thread::yield();
  }
}

void MpiCommunicator::post(const unsigned char* sendTo, std::size_t sendBytes,
  unsigned char* receiveFrom, std::size_t receiveBytes, int peer, int tag)
{
  if (receiveBytes > 0)
  {
    requests_.emplace_back();
    receivesAt_.push_back(peer);
    check(MPI_Irecv(receiveFrom, messageLength(receiveBytes), MPI_BYTE, peer, tag, communicator_,
            &requests_.back()),
      "MPI_Irecv");
  }
  if (sendBytes > 0)
  {
    requests_.emplace_back();
    receivesAt_.push_back(-1);
    check(MPI_Isend(sendTo, messageLength(sendBytes), MPI_BYTE, peer, tag, communicator_,
            &requests_.back()),
      "MPI_Isend");
  }
}

std::vector<Bytes> MpiCommunicator::exchange(const std::vector<Bytes>& outgoing)
{
  std::vector<Bytes> incoming;
  exchangeInto(outgoing, incoming);
  return incoming;
}

void MpiCommunicator::exchangeInto(const std::vector<Bytes>& outgoing, std::vector<Bytes>& incoming)
{
  throwIfFailed();
  const auto n = static_cast<std::size_t>(size_);
  if (outgoing.size() != n)
  {
    throw std::invalid_argument("exchange: one buffer per rank expected");
  }
  sendLengths_.resize(n);
  receiveLengths_.assign(n, 0);
  requests_.clear();
  receivesAt_.clear();
  for (std::size_t r = 0; r < n; ++r)
  {
    sendLengths_[r] = outgoing[r].size();
    post(reinterpret_cast<const unsigned char*>(&sendLengths_[r]), sizeof(unsigned long long),
      reinterpret_cast<unsigned char*>(&receiveLengths_[r]), sizeof(unsigned long long),
      static_cast<int>(r), kLengthTag);
  }
  waitAll();
  std::vector<std::size_t> sizes(receiveLengths_.begin(), receiveLengths_.end());
  exchangeKnownSizes(outgoing, incoming, sizes);
}

void MpiCommunicator::exchangeKnownSizes(const std::vector<Bytes>& outgoing,
  std::vector<Bytes>& incoming, const std::vector<std::size_t>& incomingSizes)
{
  const auto n = static_cast<std::size_t>(size_);
  if (outgoing.size() != n || incomingSizes.size() != n)
  {
    throw std::invalid_argument("exchange: one buffer and one size per rank expected");
  }
  incoming.resize(n);
  std::vector<const unsigned char*> send(n);
  std::vector<std::size_t> sendSizes(n);
  std::vector<unsigned char*> receive(n);
  for (std::size_t r = 0; r < n; ++r)
  {
    incoming[r].resize(incomingSizes[r]);
    send[r] = outgoing[r].data();
    sendSizes[r] = outgoing[r].size();
    receive[r] = incoming[r].data();
  }
  exchangeKnownSizesInPlace(send, sendSizes, receive, incomingSizes);
}

void MpiCommunicator::exchangeKnownSizesInPlace(const std::vector<const unsigned char*>& send,
  const std::vector<std::size_t>& sendSizes, const std::vector<unsigned char*>& receive,
  const std::vector<std::size_t>& receiveSizes)
{
  throwIfFailed();
  const auto n = static_cast<std::size_t>(size_);
  if (send.size() != n || sendSizes.size() != n || receive.size() != n || receiveSizes.size() != n)
  {
    throw std::invalid_argument("exchange: one buffer and one size per rank expected");
  }
  requests_.clear();
  receivesAt_.clear();
  for (std::size_t r = 0; r < n; ++r) // the receives first, then the sends
  {
    post(nullptr, 0, receive[r], receiveSizes[r], static_cast<int>(r), kMessageTag);
  }
  for (std::size_t r = 0; r < n; ++r)
  {
    post(send[r], sendSizes[r], nullptr, 0, static_cast<int>(r), kMessageTag);
  }
  waitAll();
  // A message longer than expected is an error (MPI_ERR_TRUNCATE above); a shorter one is one too.
  for (std::size_t k = 0; k < requests_.size(); ++k)
  {
    const int from = receivesAt_[k];
    if (from < 0)
    {
      continue;
    }
    int got = 0;
    check(MPI_Get_count(&statuses_[k], MPI_BYTE, &got), "MPI_Get_count");
    if (static_cast<std::size_t>(got) != receiveSizes[static_cast<std::size_t>(from)])
    {
      throw std::runtime_error("exchange: " + std::to_string(got) + " bytes from rank " +
        std::to_string(from) + ", expected " +
        std::to_string(receiveSizes[static_cast<std::size_t>(from)]));
    }
  }
  requests_.clear();
  receivesAt_.clear();
}

} // namespace pbf::distributed
