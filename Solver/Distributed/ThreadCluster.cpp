#include "ThreadCluster.h"

#include "RankFailure.h"

#include <condition_variable>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace pbf::distributed
{

std::vector<std::vector<double>> allGather(Communicator& communicator, const std::vector<double>& mine)
{
  Bytes packed;
  for (double value : mine)
  {
    put(packed, value);
  }
  const std::vector<Bytes> received =
    communicator.exchange(std::vector<Bytes>(static_cast<std::size_t>(communicator.size()), packed));
  std::vector<std::vector<double>> all;
  for (const Bytes& bytes : received)
  {
    std::vector<double> values;
    for (std::size_t offset = 0; offset < bytes.size();)
    {
      values.push_back(take<double>(bytes, offset));
    }
    all.push_back(std::move(values));
  }
  return all;
}

std::vector<double> sumInRankOrder(Communicator& communicator, const std::vector<double>& mine)
{
  std::vector<double> total(mine.size(), 0.0);
  for (const std::vector<double>& r : allGather(communicator, mine))
  {
    if (r.size() != total.size())
    {
      throw std::runtime_error("sumInRankOrder: a rank sent " + std::to_string(r.size()) +
        " values, this one " + std::to_string(total.size()));
    }
    for (std::size_t k = 0; k < total.size(); ++k)
    {
      total[k] += r[k];
    }
  }
  return total;
}

namespace
{

// Shared by the threads: mailbox[from][to], and a reusable barrier that an exception breaks.
struct Shared
{
  explicit Shared(int n)
    : ranks(n)
    , mailbox(static_cast<std::size_t>(n), std::vector<Bytes>(static_cast<std::size_t>(n)))
  {
  }
  int ranks;
  std::vector<std::vector<Bytes>> mailbox;
  std::mutex mutex;
  std::condition_variable changed;
  int arrived = 0;
  long generation = 0;
  bool broken = false;
  // A rank's announced failure (Communicator::abandon): what the others throw.
  bool noticed = false;
  FailureKind noticeKind = FailureKind::Other;
  std::string noticeText;

  // Throws, with the lock held, what a broken barrier means: the notice when a rank announced
  // its failure, an echo otherwise (runThreadCluster then reports the rank's own error).
  [[noreturn]] void throwBroken(bool& failed)
  {
    failed = true;
    if (noticed)
    {
      throwRankFailure(noticeKind, noticeText);
    }
    throw std::runtime_error("thread cluster: another rank failed");
  }

  void wait(bool& failed)
  {
    std::unique_lock<std::mutex> lock(mutex);
    if (broken)
    {
      throwBroken(failed);
    }
    const long mine = generation;
    if (++arrived == ranks)
    {
      arrived = 0;
      ++generation;
      changed.notify_all();
      return;
    }
    changed.wait(lock, [&] { return generation != mine || broken; });
    if (broken)
    {
      throwBroken(failed);
    }
  }

  void breakBarrier()
  {
    std::lock_guard<std::mutex> lock(mutex);
    broken = true;
    changed.notify_all();
  }

  void announce(FailureKind kind, const std::string& text)
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (!noticed)
    {
      noticed = true;
      noticeKind = kind;
      noticeText = text;
    }
    broken = true;
    changed.notify_all();
  }
};

class ThreadCommunicator final : public Communicator
{
public:
  ThreadCommunicator(Shared& shared, int rank)
    : shared_(shared)
    , rank_(rank)
  {
  }
  int rank() const override { return rank_; }
  int size() const override { return shared_.ranks; }
  // The base class's in-place exchange (through exchange()), so that the tests run the callers'
  // in-place path too.
  bool exchangesInPlace() const override { return true; }

  std::vector<Bytes> exchange(const std::vector<Bytes>& outgoing) override
  {
    if (outgoing.size() != static_cast<std::size_t>(shared_.ranks))
    {
      throw std::invalid_argument("exchange: one buffer per rank expected");
    }
    for (int to = 0; to < shared_.ranks; ++to)
    {
      shared_.mailbox[static_cast<std::size_t>(rank_)][static_cast<std::size_t>(to)] =
        outgoing[static_cast<std::size_t>(to)];
    }
    shared_.wait(failed_); // everything posted
    std::vector<Bytes> incoming(static_cast<std::size_t>(shared_.ranks));
    for (int from = 0; from < shared_.ranks; ++from)
    {
      incoming[static_cast<std::size_t>(from)] =
        shared_.mailbox[static_cast<std::size_t>(from)][static_cast<std::size_t>(rank_)];
    }
    shared_.wait(failed_); // everything read: the mailboxes may be reused
    return incoming;
  }

  void abandon(FailureKind kind, const std::string& text) override
  {
    failed_ = true;
    shared_.announce(kind, text);
  }
  bool failed() const override { return failed_; }

private:
  Shared& shared_;
  int rank_;
  bool failed_ = false;
};

} // namespace

void runThreadCluster(int ranks, const std::function<void(Communicator&)>& body)
{
  if (ranks < 1)
  {
    throw std::invalid_argument("thread cluster: ranks = " + std::to_string(ranks) +
      ": must be at least 1");
  }
  Shared shared(ranks);
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(ranks));
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r)
  {
    threads.emplace_back([&, r]() {
      try
      {
        ThreadCommunicator communicator(shared, r);
        body(communicator);
      }
      catch (...)
      {
        errors[static_cast<std::size_t>(r)] = std::current_exception();
        shared.breakBarrier();
      }
    });
  }
  for (std::thread& t : threads)
  {
    t.join();
  }
  // The first failure that is not merely the echo of another rank's.
  std::exception_ptr echo;
  for (const std::exception_ptr& error : errors)
  {
    if (!error)
    {
      continue;
    }
    try
    {
      std::rethrow_exception(error);
    }
    catch (const std::runtime_error& e)
    {
      if (std::string(e.what()) == "thread cluster: another rank failed")
      {
        echo = error;
        continue;
      }
      throw;
    }
  }
  if (echo)
  {
    std::rethrow_exception(echo);
  }
}

} // namespace pbf::distributed
