// How the ranks of a domain-decomposed run talk. The solver needs only this interface;
// an implementation over MPI (ParaView's vtkMultiProcessController, or MPI itself in a
// solver-only driver) and one over threads (ThreadCluster.h, for tests on one machine) plug in.
#pragma once

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbf::distributed
{

using Bytes = std::vector<unsigned char>;

// What a failing rank tells the others (Communicator::abandon), so that they throw the same type.
enum class FailureKind : unsigned char
{
  Other = 0,        // std::runtime_error
  InvalidInput = 1, // pbf::InvalidInput (a rank's particles do not fit its device, say)
  DeviceFault = 2,  // pbf::DeviceFault (a rank's GPU faulted mid-step)
};

class Communicator
{
public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // Collective: sends outgoing[r] to rank r (empty for most ranks) and returns, for each rank r,
  // what r sent to this one.
  virtual std::vector<Bytes> exchange(const std::vector<Bytes>& outgoing) = 0;
  // The same into `incoming` (resized to size()), whose buffers an implementation may reuse from
  // call to call: a stepper that exchanges every iteration then stops allocating and touching
  // fresh pages once the buffers have grown. The default calls exchange().
  virtual void exchangeInto(const std::vector<Bytes>& outgoing, std::vector<Bytes>& incoming)
  {
    incoming = exchange(outgoing);
  }
  // As exchangeInto when every rank knows how many bytes each other rank sends it
  // (incomingSizes, size() entries): an implementation may then skip agreeing on the lengths and
  // talk to the ranks with messages only (a slab's neighbours) instead of all of them. The
  // default ignores the sizes; the caller checks what arrived.
  virtual void exchangeKnownSizes(const std::vector<Bytes>& outgoing, std::vector<Bytes>& incoming,
    const std::vector<std::size_t>& incomingSizes)
  {
    (void)incomingSizes;
    exchangeInto(outgoing, incoming);
  }
  // As exchangeKnownSizes with the messages in the caller's memory (page-locked staging of a
  // GPU, say): to rank r the sendSizes[r] bytes at send[r], from rank r exactly receiveSizes[r]
  // bytes into receive[r] (every entry size() long; both sides know the lengths; 0 sends or
  // receives nothing). An implementation over MPI then copies nothing on the host. Callers use it
  // where exchangesInPlace() says so (and exchangeKnownSizes otherwise). The default goes through
  // exchangeKnownSizes, allocating, and checks the lengths that arrived.
  virtual bool exchangesInPlace() const { return false; }
  virtual void exchangeKnownSizesInPlace(const std::vector<const unsigned char*>& send,
    const std::vector<std::size_t>& sendSizes, const std::vector<unsigned char*>& receive,
    const std::vector<std::size_t>& receiveSizes)
  {
    const std::size_t n = send.size();
    std::vector<Bytes> outgoing(n), incoming;
    for (std::size_t r = 0; r < n; ++r)
    {
      if (sendSizes[r] > 0)
      {
        outgoing[r].assign(send[r], send[r] + sendSizes[r]);
      }
    }
    exchangeKnownSizes(outgoing, incoming, receiveSizes);
    for (std::size_t r = 0; r < n; ++r)
    {
      const std::size_t got = r < incoming.size() ? incoming[r].size() : 0;
      if (got != receiveSizes[r])
      {
        throw std::runtime_error("exchange: " + std::to_string(got) + " bytes from rank " +
          std::to_string(r) + ", expected " + std::to_string(receiveSizes[r]));
      }
      if (got > 0)
      {
        std::copy(incoming[r].begin(), incoming[r].end(), receive[r]);
      }
    }
  }

  // Failing together (RankFailure.h). A rank whose share of the collective calls fails on its own
  // (its device faulted, its memory ran out) calls abandon() before it throws: every other rank
  // then throws the same error from the call it waits in, or the next one it enters, instead of
  // waiting forever for messages that will not come. failed() is then true on every rank, and
  // every call throws, until recover() (collective) opens a fresh channel for the next run. The
  // defaults, for one process, do nothing.
  virtual void abandon(FailureKind kind, const std::string& text)
  {
    (void)kind;
    (void)text;
  }
  virtual bool failed() const { return false; }
  virtual void recover() {}
};

// Collective: every rank's values, in rank order. Reductions sum them in that order, so every
// rank gets the same bits whatever the timing.
std::vector<std::vector<double>> allGather(Communicator& communicator, const std::vector<double>& mine);

// Collective: the values summed over the ranks in rank order (every rank sends as many).
std::vector<double> sumInRankOrder(Communicator& communicator, const std::vector<double>& mine);

// Appends and reads plain values (particle fields) in a byte buffer.
template <class T>
void put(Bytes& buffer, const T& value)
{
  const auto* bytes = reinterpret_cast<const unsigned char*>(&value);
  buffer.insert(buffer.end(), bytes, bytes + sizeof(T));
}

template <class T>
T take(const Bytes& buffer, std::size_t& offset)
{
  T value;
  std::copy(buffer.begin() + static_cast<std::ptrdiff_t>(offset),
    buffer.begin() + static_cast<std::ptrdiff_t>(offset + sizeof(T)),
    reinterpret_cast<unsigned char*>(&value));
  offset += sizeof(T);
  return value;
}

} // namespace pbf::distributed
