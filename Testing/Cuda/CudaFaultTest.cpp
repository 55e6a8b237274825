// Faults of the CUDA backend in the middle of a run (label "gpu"): a device that fails, memory that
// runs out. Each test runs in a process of its own (gtest_discover_tests), because a trapped
// kernel loses the CUDA context for the rest of the process, as a lost device does. Without a
// usable CUDA device every test reports SKIPPED.
#include "Backends.h"
#include "DeviceFault.h"
#include "Scene.h"
#include "Simulation.h"
#include "RequireGpu.h"
#include "Stepper.h"

#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

// Fixed steps and projections: the faults are injected at a step number, and the runs are
// compared step for step.
Parameters withSpacing(double spacing)
{
  Parameters p;
  p.particleSpacing = spacing;
  p.timeStepping = TimeStepping::Fixed;
  p.densityErrorTolerance = 0;
  p.solverIterations = 4;
  return p;
}

bool contains(const std::string& text, const std::string& part)
{
  return text.find(part) != std::string::npos;
}

// Takes all but about 40 MiB of the device's free memory until destroyed.
class MemoryHog
{
public:
  MemoryHog()
  {
    std::size_t chunk = std::size_t(1) << 30;
    while (chunk >= (std::size_t(1) << 20))
    {
      std::size_t freeBytes = 0, totalBytes = 0;
      if (cudaMemGetInfo(&freeBytes, &totalBytes) != cudaSuccess ||
        freeBytes < (std::size_t(48) << 20))
      {
        break;
      }
      void* p = nullptr;
      if (chunk < freeBytes - (std::size_t(40) << 20) && cudaMalloc(&p, chunk) == cudaSuccess)
      {
        blocks_.push_back(p);
      }
      else
      {
        cudaGetLastError();
        chunk /= 2;
      }
    }
  }
  ~MemoryHog() { release(); }
  void release()
  {
    for (void* p : blocks_)
    {
      cudaFree(p);
    }
    blocks_.clear();
  }

private:
  std::vector<void*> blocks_;
};

} // namespace

TEST(CudaFault, ATrappedKernelIsADeviceFaultAndTheRunResumesOnTheCpuFromACheckpoint)
{
  PBF_REQUIRE_GPU();
  // The hook makes step 6 launch a kernel that traps: CUDA's unspecified launch failure, sticky
  // like a device that fell off the bus. Set before the stepper is made, which reads it.
  ASSERT_EQ(setenv("PBF_CUDA_FAULT_AT_STEP", "6", 1), 0);
  const Scene scene = presetScene("dam_break");
  const Parameters p = withSpacing(0.04);
  Simulation gpu(scene, p, Backend::CUDA, Precision::Single);
  unsetenv("PBF_CUDA_FAULT_AT_STEP");
  gpu.advance(4);
  const SimulationCheckpoint checkpoint = gpu.checkpoint(); // on the host, as the filter keeps it
  const std::size_t particles = gpu.stepper().size();

  std::string message;
  bool contextLost = false;
  try
  {
    gpu.advance(6); // returns after synchronising: the trap of step 6 surfaces here at the latest
    ADD_FAILURE() << "the trapped kernel went unreported";
  }
  catch (const DeviceFault& fault)
  {
    message = fault.what();
    contextLost = fault.contextLost();
  }
  EXPECT_TRUE(contextLost);
  EXPECT_TRUE(contains(message, "cudaErrorLaunchFailure")) << message;
  EXPECT_TRUE(contains(message, "context of this process is lost")) << message;

  // From now on the backend says why it is unavailable instead of failing later and obscurely.
  std::string why;
  EXPECT_FALSE(cudaAvailable(&why));
  EXPECT_TRUE(contains(why, "cudaErrorLaunchFailure")) << why;
  EXPECT_TRUE(contains(why, "restart")) << why;
  try
  {
    Simulation again(scene, p, Backend::CUDA, Precision::Single);
    ADD_FAILURE() << "a CUDA simulation was made on a lost context";
  }
  catch (const std::runtime_error& error)
  {
    EXPECT_TRUE(contains(error.what(), "CUDA backend unavailable")) << error.what();
  }

  // The checkpoint holds everything: the CPU continues from step 4 to step 10.
  Simulation cpu(scene, p, Backend::OpenMP, Precision::Single);
  cpu.restore(checkpoint);
  cpu.advance(6);
  EXPECT_EQ(cpu.stepCount(), 10u);
  Snapshot<double> resumed;
  cpu.stepper().read(resumed);
  EXPECT_EQ(resumed.id.size(), particles);
  const Health health = cpu.stepper().health();
  EXPECT_EQ(health.nonFinite, 0u);
  EXPECT_EQ(health.outside, 0u);

  // Against ten serial steps from the start: the GPU's first four steps round differently
  // (1e-5 relative after one step in single precision, Testing/Cuda/CudaStepperTest.cpp), and
  // six more calm steps grow that far less than to 1e-3, while a particle out of place is off by
  // a spacing, 0.04 m in coordinates of order 0.5 m (8e-2).
  Simulation serial(scene, p, Backend::Serial, Precision::Single);
  serial.advance(10);
  Snapshot<double> reference;
  serial.stepper().read(reference);
  ASSERT_EQ(reference.id, resumed.id);
  double worst = 0;
  for (std::size_t i = 0; i < reference.id.size(); ++i)
  {
    const double error =
      length(resumed.position[i] - reference.position[i]) / length(reference.position[i]);
    worst = std::isnan(error) ? INFINITY : std::max(worst, error);
  }
  EXPECT_LE(worst, 1e-3);
}

TEST(CudaFault, OutOfMemoryWhileEmittersGrowIsInvalidInputAndACheckpointResumes)
{
  PBF_REQUIRE_GPU();
  // The stream emits about 125 particles a step at this spacing; the device arrays start with room
  // for 1024 and must grow within 20 steps. Take the memory away before they do.
  const Scene scene = presetScene("stream");
  const Parameters p = withSpacing(0.01);
  Simulation gpu(scene, p, Backend::CUDA, Precision::Single);
  gpu.advance(2);
  const SimulationCheckpoint checkpoint = gpu.checkpoint();
  const std::size_t before = gpu.stepper().size();

  MemoryHog hog;
  std::string message;
  try
  {
    gpu.advance(40);
    ADD_FAILURE() << "the emitters grew past the device's free memory without an error";
  }
  catch (const InvalidInput& error)
  {
    message = error.what();
  }
  catch (const std::exception& error)
  {
    ADD_FAILURE() << "expected InvalidInput, got: " << error.what();
  }
  // The message has the numbers: what is needed and what is free.
  EXPECT_TRUE(contains(message, "particle count = ")) << message;
  EXPECT_TRUE(contains(message, "MiB free")) << message;
  // The stepper kept the particles it had; the memory error is not a lost context.
  EXPECT_GE(gpu.stepper().size(), before);
  std::string why;
  EXPECT_TRUE(cudaAvailable(&why)) << why;

  // With the memory back, a fresh CUDA simulation resumes from the checkpoint and runs on.
  hog.release();
  Simulation resumed(scene, p, Backend::CUDA, Precision::Single);
  resumed.restore(checkpoint);
  resumed.advance(30);
  EXPECT_EQ(resumed.stepCount(), 32u);
  EXPECT_GT(resumed.stepper().size(), 1024u);
  EXPECT_TRUE(resumed.stepper().statistics().finite);
}
