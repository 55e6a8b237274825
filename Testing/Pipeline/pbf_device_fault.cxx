// pbf_device_fault: a GPU that fails in the middle of a run, seen from the VTK layer as ParaView
// drives it. The CUDA backend's test hook (PBF_CUDA_FAULT_AT_STEP) makes one step launch
// a kernel that traps, which CUDA reports as an unspecified launch failure and which loses the
// context for the rest of the process, as a device that fell off the bus does.
//
//   pbf_device_fault auto   Backend Auto: the request that meets the fault still delivers its
//                           frame, computed on the CPU from the latest checkpoint, with one warning
//                           and a "DeviceFault" field; later requests, backwards too, work.
//   pbf_device_fault cuda   Backend CUDA: that request fails with an error saying how to go on,
//                           the previous output stays, CUDA requests keep failing clearly, and
//                           switching to Auto goes on from the checkpoints taken on the GPU.
//
// One mode per process, since the context stays lost. Exit 0 when every check holds, 1 otherwise;
// without a usable CUDA device it prints SKIPPED (CTest's skip pattern) and exits 0. Run by CTest
// (where there is no GPU it skips) and by Utilities/gpu/pipeline-run.sh on the GPU machine.
#include "vtkPBFSimulation.h"

#include "vtkCommand.h"
#include "vtkDataArray.h"
#include "vtkFieldData.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace
{

int Failures = 0;

void Check(bool ok, const std::string& what)
{
  std::printf("%s %s\n", ok ? "ok  " : "FAIL", what.c_str());
  if (!ok)
  {
    ++Failures;
  }
}

bool Contains(const std::string& text, const char* part)
{
  return text.find(part) != std::string::npos;
}

// Keeps the errors and warnings the filter raises (they go to its observers, not the terminal).
class MessageLog : public vtkCommand
{
public:
  static MessageLog* New() { return new MessageLog; }
  void Execute(vtkObject*, unsigned long event, void* data) override
  {
    const std::string text = data ? static_cast<const char*>(data) : "";
    (event == vtkCommand::ErrorEvent ? this->Errors : this->Warnings).push_back(text);
    std::printf("     [%s] %.400s\n", event == vtkCommand::ErrorEvent ? "error" : "warning",
      text.c_str());
  }
  std::vector<std::string> Errors;
  std::vector<std::string> Warnings;
};

std::string Text(vtkPolyData* output, const char* name)
{
  vtkAbstractArray* array = output->GetFieldData()->GetAbstractArray(name);
  return array ? array->GetVariantValue(0).ToString() : std::string();
}

// Ids a permutation of 0..n-1 and every coordinate finite: a frame that is whole.
bool Whole(vtkPolyData* output, vtkIdType expected)
{
  const vtkIdType n = output->GetNumberOfPoints();
  auto* ids = vtkIdTypeArray::SafeDownCast(output->GetPointData()->GetArray("id"));
  if (n != expected || !ids || ids->GetNumberOfTuples() != n)
  {
    return false;
  }
  std::vector<char> seen(static_cast<std::size_t>(n), 0);
  for (vtkIdType i = 0; i < n; ++i)
  {
    const vtkIdType id = ids->GetValue(i);
    if (id < 0 || id >= n || seen[static_cast<std::size_t>(id)]++)
    {
      return false;
    }
    double x[3];
    output->GetPoint(i, x);
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
    {
      return false;
    }
  }
  return true;
}

// Asked through the filter, as a user would: Backend CUDA without a device is an error. Returns
// the exit code when there is no usable device (0: SKIPPED; 1: the wrong reason, or
// PBF_GPU_REQUIRED=1), -1 when there is one.
int SkipWithoutGpu()
{
  vtkNew<vtkPBFSimulation> probe;
  vtkNew<MessageLog> quiet;
  probe->AddObserver(vtkCommand::ErrorEvent, quiet);
  probe->SetParameter("ParticleSpacing", 0.1);
  probe->SetBackend(vtkPBFSimulation::BACKEND_CUDA);
  if (!probe->UpdateTimeStep(0.0))
  {
    const std::string why = quiet->Errors.empty() ? "" : quiet->Errors[0];
    // CTest's skip pattern overrides the exit code, so SKIPPED is printed only for a skip:
    // a wrong reason, or no GPU where one must be (PBF_GPU_REQUIRED=1), is a failure.
    const char* required = std::getenv("PBF_GPU_REQUIRED");
    if (required && std::strcmp(required, "1") == 0)
    {
      std::printf("FAILED: no usable CUDA device, and PBF_GPU_REQUIRED=1: %s\n", why.c_str());
      return 1;
    }
    if (!Contains(why, "CUDA backend unavailable"))
    {
      std::printf("FAILED: Backend CUDA without a device gave an unexpected error: %s\n",
        why.c_str());
      return 1;
    }
    std::printf("  SKIPPED  no usable CUDA device: %s\n", why.c_str());
    return 0;
  }
  return -1;
}

// Backend Auto: frame 12 comes from the CPU after the fault, with one warning.
void CheckAutoFallback(vtkPBFSimulation* simulation, MessageLog* log, int delivered,
  vtkIdType particles, double interval)
{
  auto output = [&]() { return vtkPolyData::SafeDownCast(simulation->GetOutputDataObject(0)); };
  Check(delivered == 1, "frame 12 delivered although the GPU failed on the way");
  Check(log->Errors.empty(), "no error");
  Check(log->Warnings.size() == 1, "one warning");
  const std::string warning = log->Warnings.empty() ? "" : log->Warnings[0];
  Check(Contains(warning, "cudaErrorLaunchFailure") && Contains(warning, "frame 12") &&
      Contains(warning, "falling back to CPU") && Contains(warning, "frame 6 (a checkpoint)"),
    "the warning names the error, the frame, the fallback and the checkpoint");
  Check(Contains(Text(output(), "Backend"), "OpenMP"),
    "frame 12's Backend: " + Text(output(), "Backend"));
  Check(Text(output(), "ResumedFrom") == "checkpoint", "frame 12 resumed from a checkpoint");
  Check(Contains(Text(output(), "DeviceFault"), "cudaErrorLaunchFailure"),
    "frame 12 carries the DeviceFault field");
  Check(Whole(output(), particles), "frame 12 whole");
  const double shown = output()->GetInformation()->Get(vtkDataObject::DATA_TIME_STEP());
  Check(std::abs(shown - 12 * interval) < 1e-12, "frame 12's time");

  // Going back and forth works, on the CPU, without another warning.
  Check(simulation->UpdateTimeStep(3 * interval) == 1, "frame 3 after the fault");
  Check(Whole(output(), particles), "frame 3 whole");
  Check(simulation->UpdateTimeStep(15 * interval) == 1, "frame 15 after the fault");
  Check(Contains(Text(output(), "Backend"), "OpenMP"), "frame 15 on the CPU");
  Check(log->Warnings.size() == 1 && log->Errors.empty(), "still one warning and no error");
}

// Backend CUDA: the fault is an error, the previous output stays, Auto then goes on on the CPU.
void CheckCudaError(vtkPBFSimulation* simulation, MessageLog* log, int delivered,
  vtkIdType particles, double interval, const std::vector<double>& frame5)
{
  auto output = [&]() { return vtkPolyData::SafeDownCast(simulation->GetOutputDataObject(0)); };
  Check(delivered == 0, "frame 12 fails");
  const std::string error = log->Errors.empty() ? "" : log->Errors[0];
  Check(log->Errors.size() == 1 && Contains(error, "cudaErrorLaunchFailure") &&
      Contains(error, "frame 12") && Contains(error, "choose Backend Auto or CPU"),
    "one error naming the CUDA error, the frame and how to go on");
  bool same = output()->GetNumberOfPoints() == particles;
  for (vtkIdType i = 0; same && i < particles; ++i)
  {
    double x[3];
    output()->GetPoint(i, x);
    same = std::memcmp(x, &frame5[static_cast<std::size_t>(3 * i)], sizeof(x)) == 0;
  }
  Check(same, "the previous output (frame 5) stays, bit for bit");

  Check(simulation->UpdateTimeStep(13 * interval) == 0, "a later CUDA request fails too");
  const std::string again = log->Errors.size() > 1 ? log->Errors[1] : "";
  Check(Contains(again, "CUDA backend unavailable") && Contains(again, "restart"),
    "and says why: " + again.substr(0, 200));

  simulation->SetBackend(vtkPBFSimulation::BACKEND_AUTO);
  Check(simulation->UpdateTimeStep(12 * interval) == 1, "Backend Auto: frame 12 on the CPU");
  Check(Text(output(), "ResumedFrom") == "checkpoint",
    "from a checkpoint the GPU took: " + Text(output(), "ResumedFrom"));
  Check(Contains(Text(output(), "Backend"), "OpenMP"), "on the CPU");
  Check(Whole(output(), particles), "frame 12 whole");
}

} // namespace

int main(int argc, char* argv[])
{
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode != "auto" && mode != "cuda")
  {
    std::fprintf(stderr, "usage: pbf_device_fault auto|cuda\n");
    return 2;
  }
  const int skipped = SkipWithoutGpu();
  if (skipped >= 0)
  {
    return skipped;
  }
  // 4 substeps a frame and a checkpoint every 2 frames: step 30 is in frame 8, after the
  // checkpoints of frames 0, 2, 4 and 6.
  setenv("PBF_CUDA_FAULT_AT_STEP", "30", 1);

  vtkNew<vtkPBFSimulation> simulation;
  vtkNew<MessageLog> log;
  simulation->AddObserver(vtkCommand::ErrorEvent, log);
  simulation->AddObserver(vtkCommand::WarningEvent, log);
  simulation->SetPreset(vtkPBFSimulation::PRESET_DAM_BREAK);
  simulation->SetParameter("ParticleSpacing", 0.04);
  simulation->SetSubstepsPerFrame(4);
  simulation->SetCheckpointInterval(2);
  simulation->SetNumberOfFrames(20);
  simulation->SetBackend(
    mode == "auto" ? vtkPBFSimulation::BACKEND_AUTO : vtkPBFSimulation::BACKEND_CUDA);
  simulation->UpdateInformation();
  const double interval = simulation->GetFrameInterval();
  auto output = [&]() { return vtkPolyData::SafeDownCast(simulation->GetOutputDataObject(0)); };

  Check(simulation->UpdateTimeStep(5 * interval) == 1, "frame 5 on the GPU");
  Check(Contains(Text(output(), "Backend"), "CUDA"), "frame 5's Backend: " + Text(output(), "Backend"));
  const vtkIdType particles = output()->GetNumberOfPoints();
  Check(particles > 0 && Whole(output(), particles), "frame 5 whole");
  std::vector<double> frame5(static_cast<std::size_t>(3 * particles));
  for (vtkIdType i = 0; i < particles; ++i)
  {
    output()->GetPoint(i, &frame5[static_cast<std::size_t>(3 * i)]);
  }

  const int delivered = simulation->UpdateTimeStep(12 * interval);
  if (mode == "auto")
  {
    CheckAutoFallback(simulation, log, delivered, particles, interval);
  }
  else
  {
    CheckCudaError(simulation, log, delivered, particles, interval, frame5);
  }
  std::printf("%s: %d failure(s)\n", mode.c_str(), Failures);
  return Failures == 0 ? 0 : 1;
}
