// The Communicator over MPI (Distributed/MpiCommunicator.h) under mpiexec -n 3 (CTest
// pbf.mpi.rank_failure): its exchanges deliver what was sent, and a rank that fails stops every
// rank with its error instead of leaving them waiting, also mid-step in the decomposed CUDA
// stepper's algorithm (run on the host executor, so no GPU is needed). A hang, the failure this
// guards against, ends at CTest's timeout.
#include "HostExecutor.h"

#include "Cuda/DeviceSubdomainStepper.h"
#include "DeviceFault.h"
#include "Distributed/MpiCommunicator.h"
#include "Distributed/RankFailure.h"
#include "TestScenes.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <memory>
#include <string>

using namespace pbf;
using namespace pbf::test;

namespace
{

distributed::Bytes text(const std::string& s)
{
  return distributed::Bytes(s.begin(), s.end());
}

std::string text(const distributed::Bytes& b)
{
  return std::string(b.begin(), b.end());
}

// Every rank's text, in rank order, through an exchange (so also a check that it works).
std::vector<std::string> gatherTexts(distributed::Communicator& c, const std::string& mine)
{
  std::vector<std::string> all;
  for (const distributed::Bytes& b :
    c.exchange(std::vector<distributed::Bytes>(static_cast<std::size_t>(c.size()), text(mine))))
  {
    all.push_back(text(b));
  }
  return all;
}

} // namespace

TEST(MpiCommunicator, ExchangesDeliverWhatEachRankSent)
{
  distributed::MpiCommunicator c;
  ASSERT_GE(c.size(), 2) << "run under mpiexec -n 2 or more";
  const auto n = static_cast<std::size_t>(c.size());
  const int me = c.rank();
  auto message = [](int from, int to) { return "from " + std::to_string(from) + " to " + std::to_string(to); };
  std::vector<distributed::Bytes> out(n);
  for (std::size_t r = 0; r < n; ++r)
  {
    out[r] = text(message(me, static_cast<int>(r)));
  }
  out[(static_cast<std::size_t>(me) + 1) % n].clear(); // an empty message too
  std::vector<distributed::Bytes> in;
  c.exchangeInto(out, in);
  std::vector<std::size_t> sizes(n);
  for (std::size_t r = 0; r < n; ++r)
  {
    const bool empty = (r + 1) % n == static_cast<std::size_t>(me);
    EXPECT_EQ(text(in[r]), empty ? "" : message(static_cast<int>(r), me)) << "exchangeInto";
    sizes[r] = in[r].size();
  }
  std::vector<distributed::Bytes> known;
  c.exchangeKnownSizes(out, known, sizes);
  EXPECT_EQ(known, in) << "exchangeKnownSizes";
  // In place, and a length that does not match is an error, not a silent truncation.
  std::vector<distributed::Bytes> landing(n);
  std::vector<const unsigned char*> send(n);
  std::vector<std::size_t> sendSizes(n);
  std::vector<unsigned char*> receive(n);
  for (std::size_t r = 0; r < n; ++r)
  {
    landing[r].resize(sizes[r]);
    send[r] = out[r].data();
    sendSizes[r] = out[r].size();
    receive[r] = landing[r].data();
  }
  c.exchangeKnownSizesInPlace(send, sendSizes, receive, sizes);
  EXPECT_EQ(landing, in) << "exchangeKnownSizesInPlace";
}

TEST(MpiCommunicator, AFailedRankStopsTheOthersWithItsErrorAndRecoverOpensAFreshChannel)
{
  distributed::MpiCommunicator c;
  const auto n = static_cast<std::size_t>(c.size());
  std::string seen = "no error";
  try
  {
    if (c.rank() == 1)
    {
      throw DeviceFault("an illegal memory access", true);
    }
    c.exchange(std::vector<distributed::Bytes>(n)); // would wait forever for rank 1
  }
  catch (...)
  {
    try
    {
      distributed::failTogether(c, std::current_exception());
    }
    catch (const DeviceFault& fault)
    {
      seen = fault.what();
      // Only the rank whose device failed says its context is lost.
      EXPECT_EQ(fault.contextLost(), c.rank() == 1);
    }
    catch (const std::exception& other)
    {
      seen = std::string("not a DeviceFault: ") + other.what();
    }
  }
  EXPECT_EQ(seen, "rank 1 of " + std::to_string(n) + ": an illegal memory access");
  EXPECT_TRUE(c.failed());
  EXPECT_THROW(c.exchange(std::vector<distributed::Bytes>(n)), DeviceFault) << "failed stays failed";
  c.recover();
  EXPECT_FALSE(c.failed());
  for (const std::string& other : gatherTexts(c, seen))
  {
    EXPECT_EQ(other, seen) << "every rank reports the same error";
  }
}

TEST(MpiCommunicator, ADeviceFaultMidStepStopsEveryRankOfTheDecomposedStepper)
{
  distributed::MpiCommunicator c;
  const PresetFluid setup = presetFluid("dam_break", 0.08);
  auto policy = std::make_unique<HostDevicePolicy>();
  HostDevicePolicy* device = policy.get();
  std::string seen = "no error";
  int steps = 0;
  {
    cuda::DeviceSubdomainStepper<double, HostDevicePolicy> stepper(
      c, setup.parameters, setup.fluid, std::move(policy));
    faultMidNextStep(stepper, *device, c.rank() == c.size() - 1);
    try
    {
      for (int s = 0; s < 3; ++s)
      {
        stepper.step();
        ++steps;
      }
    }
    catch (const DeviceFault& fault)
    {
      seen = fault.what();
    }
    catch (const std::exception& other)
    {
      seen = std::string("not a DeviceFault: ") + other.what();
    }
  }
  EXPECT_EQ(steps, 0);
  const std::string expected = "rank " + std::to_string(c.size() - 1) + " of " +
    std::to_string(c.size()) + ": injected device fault";
  EXPECT_EQ(seen.rfind(expected, 0), 0u) << seen;
  // The ranks go on together: a fresh channel, then a new stepper from the same state.
  c.recover();
  for (const std::string& other : gatherTexts(c, seen))
  {
    EXPECT_EQ(other, seen);
  }
  cuda::DeviceSubdomainStepper<double, HostDevicePolicy> again(
    c, setup.parameters, setup.fluid, std::make_unique<HostDevicePolicy>());
  again.step();
  EXPECT_TRUE(again.statistics().finite);
}

int main(int argc, char** argv)
{
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  const int result = RUN_ALL_TESTS(); // every rank reports; mpiexec fails if any rank does
  MPI_Finalize();
  return result;
}
