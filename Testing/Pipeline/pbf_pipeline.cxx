// pbf_pipeline: what the VTK layer costs on top of the solver. Drives vtkPBFSimulation as ParaView
// does (one UpdateTimeStep per animation frame) on a dam break scaled to N particles (the scene
// pbf_bench times) or on a scene file, and prints per frame the simulation time (the solver steps'
// AdvanceReport milliseconds, GPU synchronisation included) against the rest of the request:
// the diagnostics (Stepper::statistics), the checkpoints and the delivery (copy back from the
// device into the VTK arrays, output assembly). The target: delivery at most 10% of the
// frame's simulation time for 1M particles at 4 substeps per frame on the H200.
//
//   pbf_pipeline [--particles N] [--scene FILE] [--spacing S] [--frames F] [--warmup W]
//                [--substeps K] [--backend auto|cuda|openmp|serial] [--precision single|double]
//                [--checkpoint-interval C] [--pageable] [--compare-pageable F2] [--work DIR]
//
// Not a test (no pass/fail exit on speed): Utilities/gpu/pipeline-run.sh runs it on the GPU
// machine and Documentation/Performance.md records the figures. It does check that the frames
// it delivers are sane (ids a permutation, finite values) and exits non-zero if not.
#include "vtkPBFSimulation.h"

#include "vtkDataArray.h"
#include "vtkFieldData.h"
#include "vtkIdTypeArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkStringArray.h"
#include "vtkTable.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace
{

struct Options
{
  double particles = 1e6;
  std::string scene;
  double spacing = 0.02;
  int frames = 30;
  int warmup = 3;
  int substeps = 4;
  std::string backend = "cuda";
  std::string precision = "single";
  int checkpointInterval = 10;
  bool pageable = false;
  int comparePageable = 0;
  std::string work = "/tmp";
};

[[noreturn]] void Usage(const char* message)
{
  std::fprintf(stderr,
    "pbf_pipeline: %s\n"
    "usage: pbf_pipeline [--particles N] [--scene FILE] [--spacing S] [--frames F] [--warmup W]\n"
    "         [--substeps K] [--backend auto|cuda|openmp|serial] [--precision single|double]\n"
    "         [--checkpoint-interval C] [--pageable] [--compare-pageable F2] [--work DIR]\n",
    message);
  std::exit(2);
}

Options Parse(int argc, char* argv[])
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    auto value = [&]() -> std::string
    {
      if (i + 1 >= argc)
      {
        Usage(("missing value after " + a).c_str());
      }
      return argv[++i];
    };
    if (a == "--particles")
      o.particles = std::atof(value().c_str());
    else if (a == "--scene")
      o.scene = value();
    else if (a == "--spacing")
      o.spacing = std::atof(value().c_str());
    else if (a == "--frames")
      o.frames = std::atoi(value().c_str());
    else if (a == "--warmup")
      o.warmup = std::atoi(value().c_str());
    else if (a == "--substeps")
      o.substeps = std::atoi(value().c_str());
    else if (a == "--backend")
      o.backend = value();
    else if (a == "--precision")
      o.precision = value();
    else if (a == "--checkpoint-interval")
      o.checkpointInterval = std::atoi(value().c_str());
    else if (a == "--pageable")
      o.pageable = true;
    else if (a == "--compare-pageable")
      o.comparePageable = std::atoi(value().c_str());
    else if (a == "--work")
      o.work = value();
    else
      Usage(("unknown option " + a).c_str());
  }
  if (o.frames < 1 || o.warmup < 0 || o.warmup >= o.frames || o.substeps < 1 || o.particles < 1)
  {
    Usage("need frames >= 1, 0 <= warmup < frames, substeps >= 1, particles >= 1");
  }
  return o;
}

// The dam_break preset widened in x and z until the column holds about `particles` lattice sites,
// as pbf_bench scales it (the height, the flow and the time step stay the preset's), so that the
// simulation times here compare with pbf_bench's ms/step.
std::string WriteScaledDamBreak(const Options& o)
{
  const double s = o.spacing;
  const double layers = std::max(1.0, std::round(0.6 / s));
  const double cx = std::max(1.0, std::round(std::sqrt(o.particles / (1.5 * layers))));
  const double cz = std::max(1.0, std::round(o.particles / (layers * cx)));
  const double halfX = 2 * cx * s, halfZ = 0.5 * cz * s;
  const std::string path = o.work + "/pbf_pipeline_scene.json";
  std::ofstream out(path);
  out.precision(17);
  out << "{\n  \"name\": \"dam_break_wide\",\n"
      << "  \"description\": \"dam_break preset widened in x and z to the particle count\",\n"
      << "  \"domain\": { \"min\": [" << -halfX << ", 0, " << -halfZ << "], \"max\": [" << halfX
      << ", " << 4.0 / 3.0 * layers * s << ", " << halfZ << "] },\n"
      << "  \"fluid\": [ { \"type\": \"box\", \"min\": [" << -halfX << ", 0, " << -halfZ
      << "], \"max\": [" << -halfX + cx * s << ", " << layers * s << ", " << halfZ << "] } ]\n}\n";
  if (!out)
  {
    Usage(("cannot write " + path).c_str());
  }
  return path;
}

double Median(std::vector<double> v)
{
  if (v.empty())
  {
    return std::nan("");
  }
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

struct Sample
{
  int frame;
  double wall, simulation, diagnostics, checkpoint, delivery;
  long steps;
};

// Ids a permutation of 0..n-1 (the dam break has no emitters) and every value finite: the copy
// from the device landed where the arrays are.
bool Sane(vtkPolyData* data, std::string& why)
{
  const vtkIdType n = data->GetNumberOfPoints();
  auto* ids = vtkIdTypeArray::SafeDownCast(data->GetPointData()->GetArray("id"));
  if (n == 0 || !ids || ids->GetNumberOfTuples() != n)
  {
    why = "no particles or no id array";
    return false;
  }
  std::vector<char> seen(static_cast<std::size_t>(n), 0);
  for (vtkIdType i = 0; i < n; ++i)
  {
    const vtkIdType id = ids->GetValue(i);
    if (id < 0 || id >= n || seen[static_cast<std::size_t>(id)]++)
    {
      why = "id " + std::to_string(id) + " at " + std::to_string(i) + " is not a permutation";
      return false;
    }
  }
  for (vtkDataArray* array :
    { data->GetPoints()->GetData(), data->GetPointData()->GetArray("velocity"),
      data->GetPointData()->GetArray("density"), data->GetPointData()->GetArray("lambda"),
      data->GetPointData()->GetArray("pressure") })
  {
    const vtkIdType values = array->GetNumberOfValues();
    for (vtkIdType k = 0; k < values; ++k)
    {
      if (!std::isfinite(array->GetComponent(k / array->GetNumberOfComponents(),
            static_cast<int>(k % array->GetNumberOfComponents()))))
      {
        why =
          std::string("non-finite value in ") + (array->GetName() ? array->GetName() : "points");
        return false;
      }
    }
  }
  double range[2];
  data->GetPointData()->GetArray("density")->GetRange(range, 0);
  if (!(range[1] > 0))
  {
    why = "density range [" + std::to_string(range[0]) + ", " + std::to_string(range[1]) + "]";
    return false;
  }
  return true;
}

void Report(const char* title, const std::vector<Sample>& samples, int warmup, int substeps)
{
  std::vector<double> simulation, rest, diagnostics, checkpoint, delivery, restRatio, deliveryRatio;
  for (const Sample& s : samples)
  {
    if (s.frame <= warmup)
    {
      continue;
    }
    simulation.push_back(s.simulation);
    rest.push_back(s.wall - s.simulation);
    diagnostics.push_back(s.diagnostics);
    checkpoint.push_back(s.checkpoint);
    delivery.push_back(s.delivery);
    restRatio.push_back((s.wall - s.simulation) / s.simulation);
    deliveryRatio.push_back(s.delivery / s.simulation);
  }
  double checkpointMean = 0;
  for (double c : checkpoint)
  {
    checkpointMean += c / checkpoint.size();
  }
  std::printf("%s: median over %zu frames (frame %d on)\n", title, simulation.size(), warmup + 1);
  std::printf("  simulation   %8.3f ms/frame (%.3f ms/step, %d steps)\n", Median(simulation),
    Median(simulation) / substeps, substeps);
  std::printf("  delivery     %8.3f ms/frame  = %5.1f%% of the simulation (target <= 10%%)\n",
    Median(delivery), 100 * Median(deliveryRatio));
  std::printf("  diagnostics  %8.3f ms/frame\n", Median(diagnostics));
  std::printf("  checkpoints  %8.3f ms/frame on average\n", checkpointMean);
  std::printf(
    "  rest of the request (wall - simulation) %8.3f ms/frame = %5.1f%% of the simulation\n",
    Median(rest), 100 * Median(restRatio));
  std::fflush(stdout);
}

// The filter as the options say, its information updated.
void Configure(vtkPBFSimulation* simulation, const Options& o, const std::string& scene)
{
  simulation->SetSceneFile(scene.c_str());
  simulation->SetParameter("ParticleSpacing", o.spacing);
  simulation->SetSubstepsPerFrame(o.substeps);
  simulation->SetNumberOfFrames(o.frames + o.comparePageable + 1);
  simulation->SetCheckpointInterval(o.checkpointInterval);
  simulation->SetPageLockedOutput(!o.pageable);
  simulation->SetPrecision(o.precision == "double" ? vtkPBFSimulation::PRECISION_DOUBLE
                                                   : vtkPBFSimulation::PRECISION_SINGLE);
  if (o.backend == "cuda")
    simulation->SetBackend(vtkPBFSimulation::BACKEND_CUDA);
  else if (o.backend == "openmp")
    simulation->SetBackend(vtkPBFSimulation::BACKEND_OPENMP);
  else if (o.backend == "serial")
    simulation->SetBackend(vtkPBFSimulation::BACKEND_SERIAL);
  else if (o.backend == "auto")
    simulation->SetBackend(vtkPBFSimulation::BACKEND_AUTO);
  else
    Usage(("unknown backend " + o.backend).c_str());
  simulation->UpdateInformation();

}

// Scrubbing, as a user dragging the time slider back would: an earlier frame resumes from the
// latest checkpoint at or before it; the frame just shown again costs nothing.
template <class Request, class Output>
void Scrub(vtkPBFSimulation* simulation, const Options& o, Request& request, Output& output)
{
  auto resumedFrom = [&]() {
    return output()->GetFieldData()->GetAbstractArray("ResumedFrom")->GetVariantValue(0).ToString();
  };
  const int last = o.frames + (o.pageable ? 0 : o.comparePageable);
  const int back = std::max(1, last / 2 + 1);
  const Sample scrub = request(back);
  std::printf("scrub back to frame %d: %.1f ms wall, %ld steps (from %s)\n", back, scrub.wall,
    scrub.steps, resumedFrom().c_str());
  simulation->SetNumberOfFrames(last + 10); // re-executes the algorithm, changes no frame
  const Sample again = request(back);
  std::printf("same frame after a NumberOfFrames change: %.3f ms wall, %ld steps (from %s)\n",
    again.wall, again.steps, resumedFrom().c_str());
}

} // namespace

int main(int argc, char* argv[])
{
  const Options o = Parse(argc, argv);
  const std::string scene = o.scene.empty() ? WriteScaledDamBreak(o) : o.scene;

  vtkNew<vtkPBFSimulation> simulation;
  Configure(simulation, o, scene);
  const double interval = simulation->GetFrameInterval();
  auto request = [&](int frame)
  {
    const auto start = std::chrono::steady_clock::now();
    if (!simulation->UpdateTimeStep(frame * interval))
    {
      std::fprintf(stderr, "pbf_pipeline: the request for frame %d failed\n", frame);
      std::exit(1);
    }
    const double wall =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return Sample{ frame, wall, simulation->GetLastSimulationMilliseconds(),
      simulation->GetLastDiagnosticsMilliseconds(), simulation->GetLastCheckpointMilliseconds(),
      simulation->GetLastDeliveryMilliseconds(),
      static_cast<long>(simulation->GetLastRequestSteps()) };
  };
  auto output = [&]() { return vtkPolyData::SafeDownCast(simulation->GetOutputDataObject(0)); };

  const Sample first = request(0);
  vtkFieldData* fields = output()->GetFieldData();
  std::printf(
    "pbf_pipeline: %lld particles, backend %s, %s precision, spacing %g m, %d substeps per "
    "frame of %g s, checkpoints every %d frames, %s output memory\n",
    static_cast<long long>(output()->GetNumberOfPoints()),
    fields->GetAbstractArray("Backend")->GetVariantValue(0).ToString().c_str(),
    fields->GetAbstractArray("Precision")->GetVariantValue(0).ToString().c_str(), o.spacing,
    o.substeps, interval, o.checkpointInterval,
    o.pageable ? "pageable" : "page-locked (with CUDA)");
  std::printf("  frame 0 (scene, setup, first delivery): %.1f ms\n", first.wall);
  std::printf("  %5s %10s %10s %10s %10s %10s %8s\n", "frame", "wall ms", "sim ms", "deliver ms",
    "diag ms", "ckpt ms", "deliv %");

  auto run = [&](int from, int to, std::vector<Sample>& samples)
  {
    for (int frame = from; frame <= to; ++frame)
    {
      const Sample s = request(frame);
      samples.push_back(s);
      std::printf("  %5d %10.3f %10.3f %10.3f %10.3f %10.3f %7.1f%%\n", s.frame, s.wall,
        s.simulation, s.delivery, s.diagnostics, s.checkpoint, 100 * s.delivery / s.simulation);
      std::fflush(stdout);
    }
  };
  std::vector<Sample> samples;
  run(1, o.frames, samples);
  std::string why;
  if (!Sane(output(), why))
  {
    std::fprintf(stderr, "pbf_pipeline: frame %d is wrong: %s\n", o.frames, why.c_str());
    return 1;
  }
  Report(o.pageable ? "page-able output" : "page-locked output", samples, o.warmup, o.substeps);

  if (o.comparePageable > 0 && !o.pageable)
  {
    // The same simulation goes on; only where the arrays live changes.
    simulation->SetPageLockedOutput(false);
    std::vector<Sample> pageable;
    run(o.frames + 1, o.frames + o.comparePageable, pageable);
    for (Sample& s : pageable)
    {
      s.frame -= o.frames; // so that the warm-up skips the first frames of this run too
    }
    if (!Sane(output(), why))
    {
      std::fprintf(stderr, "pbf_pipeline: pageable frame is wrong: %s\n", why.c_str());
      return 1;
    }
    Report("pageable output", pageable, std::min(o.warmup, o.comparePageable - 1), o.substeps);
  }

  Scrub(simulation, o, request, output);
  auto* table = vtkTable::SafeDownCast(simulation->GetOutputDataObject(1));
  std::printf("diagnostics: %lld rows\n", static_cast<long long>(table->GetNumberOfRows()));
  return 0;
}
