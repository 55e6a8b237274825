#include "vtkPBFSimulation.h"
#include "vtkPBFPageLocked.h"
#include "vtkPBFRankCommunicator.h"

#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOutlineSource.h"
#include "vtkOutputWindow.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"
#include "vtkTable.h"

#include "DeviceFault.h"
#include "Parameters.h"
#include "Scene.h"
#include "Simulation.h"
#include "Stepper.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cctype>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace
{

// Indexed by vtkPBFSimulation::PresetScenes; the names are pbf::presetScene's.
const char* const PresetNames[] = { "dam_break", "double_dam_break", "blob", "stream" };

// Everything that decides the frames from the initial state. Frames of two equal configurations
// are bit-identical, so the live simulation, the checkpoints and the diagnostics of one serve the
// other. NumberOfFrames, the checkpoint settings and display properties are deliberately absent:
// they change no frame.
struct Configuration
{
  std::string SceneKey; // the preset's name, or the file's name and contents
  pbf::Parameters Parameters;
  double FrameInterval = 0;
  int Substeps = 1;
  pbf::Backend Backend = pbf::Backend::OpenMP;
  pbf::Precision Precision = pbf::Precision::Single;
  bool HasInput = false;
  vtkMTimeType InputMTime = 0;
  int Ranks = 1; // > 1: this rank's share of a domain-decomposed run over the controller's ranks
};

bool SameBox(const pbf::Box& a, const pbf::Box& b)
{
  return a.min.x == b.min.x && a.min.y == b.min.y && a.min.z == b.min.z && a.max.x == b.max.x &&
    a.max.y == b.max.y && a.max.z == b.max.z;
}

// Field by field: a NaN never compares equal, which only costs a rebuild that then reports it.
// A field added to pbf::Parameters must be added here, or changing it would not invalidate the
// simulation (Testing/Python/pbf_parameters.py fails for a field without a property).
bool SameParameters(const pbf::Parameters& a, const pbf::Parameters& b)
{
  return a.restDensity == b.restDensity && a.particleSpacing == b.particleSpacing &&
    a.smoothingRatio == b.smoothingRatio && a.solverIterations == b.solverIterations &&
    a.densityErrorTolerance == b.densityErrorTolerance &&
    a.maxDensityErrorTolerance == b.maxDensityErrorTolerance && a.relaxation == b.relaxation &&
    a.sCorrK == b.sCorrK && a.sCorrN == b.sCorrN && a.sCorrDeltaQ == b.sCorrDeltaQ &&
    a.xsphViscosity == b.xsphViscosity && a.vorticityEpsilon == b.vorticityEpsilon &&
    a.unilateral == b.unilateral && a.mirrorWalls == b.mirrorWalls && a.gravity.x == b.gravity.x &&
    a.gravity.y == b.gravity.y && a.gravity.z == b.gravity.z && a.timeStep == b.timeStep &&
    a.timeStepping == b.timeStepping && a.cflNumber == b.cflNumber &&
    a.sceneSpeedHint == b.sceneSpeedHint && SameBox(a.domain, b.domain);
}

bool operator==(const Configuration& a, const Configuration& b)
{
  return a.SceneKey == b.SceneKey && SameParameters(a.Parameters, b.Parameters) &&
    a.FrameInterval == b.FrameInterval && a.Substeps == b.Substeps && a.Backend == b.Backend &&
    a.Precision == b.Precision && a.HasInput == b.HasInput && a.InputMTime == b.InputMTime &&
    a.Ranks == b.Ranks;
}

bool operator!=(const Configuration& a, const Configuration& b)
{
  return !(a == b);
}

std::string FormatPoint(const double x[3])
{
  std::ostringstream text;
  text << "(" << x[0] << ", " << x[1] << ", " << x[2] << ")";
  return text.str();
}

// The filter's input as the fluid's initial particles: point i becomes particle i.
pbf::ParticleBatch BatchFromInput(vtkPointSet* input)
{
  const vtkIdType n = input->GetNumberOfPoints();
  if (n < 2)
  {
    // One particle has no neighbour: no density to constrain, nothing that behaves as a fluid.
    throw pbf::InvalidInput("input number of points = " + std::to_string(n) +
      ": the filter needs at least 2 points to become the fluid (a particle alone has no "
      "neighbour within the smoothing length, so it only falls)");
  }
  vtkDataArray* velocity = input->GetPointData()->GetArray("velocity");
  if (velocity && velocity->GetNumberOfComponents() != 3)
  {
    throw pbf::InvalidInput("input point array \"velocity\" has " +
      std::to_string(velocity->GetNumberOfComponents()) +
      " components: an initial velocity needs 3 (rename the array to ignore it)");
  }
  pbf::ParticleBatch batch;
  batch.position.resize(static_cast<std::size_t>(n));
  batch.velocity.resize(static_cast<std::size_t>(n), pbf::Vec3d{ 0, 0, 0 });
  batch.id.resize(static_cast<std::size_t>(n));
  for (vtkIdType i = 0; i < n; ++i)
  {
    double x[3];
    input->GetPoint(i, x);
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
    {
      throw pbf::InvalidInput("input point " + std::to_string(i) + " = " + FormatPoint(x) +
        ": coordinates must be finite");
    }
    const auto k = static_cast<std::size_t>(i);
    batch.position[k] = pbf::Vec3d{ x[0], x[1], x[2] };
    if (velocity)
    {
      double v[3];
      velocity->GetTuple(i, v);
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
      {
        throw pbf::InvalidInput("input velocity of point " + std::to_string(i) + " = " +
          FormatPoint(v) + ": must be finite");
      }
      batch.velocity[k] = pbf::Vec3d{ v[0], v[1], v[2] };
    }
    batch.id[k] = static_cast<std::int64_t>(i);
  }
  return batch;
}

template <class Real>
using RealArray =
  typename std::conditional<std::is_same<Real, float>::value, vtkFloatArray, vtkDoubleArray>::type;

template <class Array>
vtkSmartPointer<Array> NewArray(const char* name, int components, vtkIdType tuples)
{
  auto array = vtkSmartPointer<Array>::New();
  if (name)
  {
    array->SetName(name);
  }
  array->SetNumberOfComponents(components);
  array->SetNumberOfTuples(tuples);
  return array;
}

// Vertex cells 0..n-1 depend on the particle count only: built once per count and shared by the
// frames (outputs are never modified downstream), instead of 16 bytes per particle per frame.
vtkSmartPointer<vtkCellArray> VertexCells(vtkIdType n)
{
  auto offsets = NewArray<vtkIdTypeArray>(nullptr, 1, n + 1);
  auto connectivity = NewArray<vtkIdTypeArray>(nullptr, 1, n);
  vtkIdType* o = offsets->GetPointer(0);
  vtkIdType* c = connectivity->GetPointer(0);
  for (vtkIdType i = 0; i < n; ++i)
  {
    o[i] = i;
    c[i] = i;
  }
  o[n] = n;
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  cells->SetData(offsets, connectivity);
  return cells;
}

// An output array of the given size, in page-locked memory when asked and available (the GPU
// then copies into it at the full bus speed); the array gives the memory back to the pool.
template <class Array>
vtkSmartPointer<Array> NewOutputArray(
  const char* name, int components, vtkIdType tuples, bool pinned)
{
  using Value = typename Array::ValueType;
  const auto values = static_cast<std::size_t>(tuples) * static_cast<std::size_t>(components);
  void* memory = pinned ? vtkPBFPageLocked::Allocate(values * sizeof(Value)) : nullptr;
  if (!memory)
  {
    return NewArray<Array>(name, components, tuples);
  }
  auto array = vtkSmartPointer<Array>::New();
  if (name)
  {
    array->SetName(name);
  }
  array->SetNumberOfComponents(components);
  array->SetArray(static_cast<Value*>(memory), static_cast<vtkIdType>(values), /*save=*/0,
    Array::VTK_DATA_ARRAY_USER_DEFINED);
  array->SetArrayFreeFunction(&vtkPBFPageLocked::Release);
  return array;
}

// The particles in the solver's (cell-sorted) order, read by the stepper straight into the VTK
// arrays' memory: pbf::Vec3 is three packed reals, as VTK's interleaved arrays are, and the ids
// are 64-bit like vtkIdType. No per-point call, no copy in between.
template <class Real>
void FillParticles(const pbf::Stepper& stepper, bool pinned,
  vtkSmartPointer<vtkCellArray>& vertices, vtkPolyData* output)
{
  static_assert(sizeof(pbf::Vec3<Real>) == 3 * sizeof(Real), "pbf::Vec3 must be 3 packed reals");
  static_assert(sizeof(vtkIdType) == sizeof(std::int64_t), "particle ids are 64-bit vtkIdTypes");
  const auto n = static_cast<vtkIdType>(stepper.size());
  auto coordinates = NewOutputArray<RealArray<Real>>(nullptr, 3, n, pinned);
  auto velocity = NewOutputArray<RealArray<Real>>("velocity", 3, n, pinned);
  auto density = NewOutputArray<RealArray<Real>>("density", 1, n, pinned);
  auto lambda = NewOutputArray<RealArray<Real>>("lambda", 1, n, pinned);
  auto id = NewOutputArray<vtkIdTypeArray>("id", 1, n, pinned);
  if (n > 0)
  {
    pbf::SnapshotView<Real> view;
    view.position = reinterpret_cast<pbf::Vec3<Real>*>(coordinates->GetPointer(0));
    view.velocity = reinterpret_cast<pbf::Vec3<Real>*>(velocity->GetPointer(0));
    view.density = density->GetPointer(0);
    view.lambda = lambda->GetPointer(0);
    view.id = reinterpret_cast<std::int64_t*>(id->GetPointer(0));
    stepper.readInto(view);
  }
  if (!vertices || vertices->GetNumberOfCells() != n)
  {
    vertices = VertexCells(n);
  }

  vtkNew<vtkPoints> points;
  points->SetData(coordinates);
  output->SetPoints(points);
  output->SetVerts(vertices);

  vtkPointData* pointData = output->GetPointData();
  pointData->AddArray(density);
  pointData->AddArray(lambda);
  // Active scalars and vectors, so that a view colors by |velocity| on first show.
  pointData->SetScalars(velocity);
  pointData->SetVectors(velocity);
  pointData->SetGlobalIds(id);
}

void AddValue(vtkFieldData* fieldData, const char* name, double value)
{
  vtkNew<vtkDoubleArray> array;
  array->SetName(name);
  array->SetNumberOfTuples(1);
  array->SetValue(0, value);
  fieldData->AddArray(array);
}

void AddInteger(vtkFieldData* fieldData, const char* name, vtkIdType value)
{
  vtkNew<vtkIdTypeArray> array;
  array->SetName(name);
  array->SetNumberOfTuples(1);
  array->SetValue(0, value);
  fieldData->AddArray(array);
}

void AddText(vtkFieldData* fieldData, const char* name, const std::string& value)
{
  vtkNew<vtkStringArray> array;
  array->SetName(name);
  array->SetNumberOfValues(1);
  array->SetValue(0, value);
  fieldData->AddArray(array);
}

// The parameters that produced the frame, as the solver saw them (domain included), so that a
// reader of the output alone can recompute the density with poly6 of h and the particle mass.
vtkSmartPointer<vtkFieldData> FrameFieldData(
  const pbf::Simulation& simulation, int frame, double frameInterval, int substeps)
{
  const pbf::Parameters& p = simulation.parameters();
  auto fieldData = vtkSmartPointer<vtkFieldData>::New();
  AddValue(fieldData, "SmoothingLength", p.smoothingLength());
  AddValue(fieldData, "RestDensity", p.restDensity);
  AddValue(fieldData, "ParticleMass", pbf::calibratedParticleMass(p));
  AddValue(fieldData, "ParticleSpacing", p.particleSpacing);
  AddValue(fieldData, "SmoothingRatio", p.smoothingRatio);
  AddInteger(fieldData, "SolverIterations", p.solverIterations);
  AddInteger(fieldData, "AdaptiveIterations", p.densityErrorTolerance > 0 ? 1 : 0);
  AddValue(fieldData, "DensityErrorTolerance", p.densityErrorTolerance);
  AddValue(fieldData, "MaxDensityErrorTolerance", p.maxDensityErrorTolerance);
  AddValue(fieldData, "RelaxationEpsilon", p.relaxation);
  AddValue(fieldData, "SCorrK", p.sCorrK);
  AddValue(fieldData, "SCorrN", p.sCorrN);
  AddValue(fieldData, "SCorrDeltaQ", p.sCorrDeltaQ);
  AddValue(fieldData, "XSPHViscosity", p.xsphViscosity);
  AddValue(fieldData, "XSPHKinematicViscosity", p.xsphNu());
  AddValue(fieldData, "VorticityEpsilon", p.vorticityEpsilon);
  AddInteger(fieldData, "Unilateral", p.unilateral ? 1 : 0);
  AddInteger(fieldData, "MirrorWalls", p.mirrorWalls ? 1 : 0);
  vtkNew<vtkDoubleArray> gravity;
  gravity->SetName("Gravity");
  gravity->SetNumberOfComponents(3);
  gravity->InsertNextTuple3(p.gravity.x, p.gravity.y, p.gravity.z);
  fieldData->AddArray(gravity);
  vtkNew<vtkDoubleArray> domain;
  domain->SetName("Domain");
  domain->SetNumberOfComponents(6);
  const double bounds[6] = { p.domain.min.x, p.domain.max.x, p.domain.min.y, p.domain.max.y,
    p.domain.min.z, p.domain.max.z };
  domain->InsertNextTuple(bounds);
  fieldData->AddArray(domain);
  const bool automatic = p.timeStepping == pbf::TimeStepping::Automatic;
  AddText(fieldData, "TimeStepping", automatic ? "Automatic" : "Fixed");
  AddValue(fieldData, "TimeStep", automatic ? simulation.stepper().timeStep() : p.timeStep);
  AddValue(fieldData, "MaxTimeStep", p.timeStep);
  AddValue(fieldData, "CFLNumber", p.cflNumber);
  AddValue(fieldData, "FrameInterval", frameInterval);
  AddInteger(fieldData, "SubstepsPerFrame", substeps);
  AddInteger(fieldData, "Frame", frame);
  AddInteger(fieldData, "StepCount", static_cast<vtkIdType>(simulation.stepCount()));
  AddValue(fieldData, "Time", simulation.time());
  AddText(fieldData, "Backend", simulation.stepper().description());
  AddText(fieldData, "Precision", pbf::toString(simulation.stepper().precision()));
  AddText(fieldData, "Scene", simulation.scene().name);
  return fieldData;
}

std::string ReadWholeFile(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

double Milliseconds(std::chrono::steady_clock::time_point since)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
    .count();
}

const double NaN = std::numeric_limits<double>::quiet_NaN();

// The solver's messages name its own fields (timeStep, cflNumber, solverIterations); a ParaView
// user sees properties. Advice about a field becomes advice about the properties that set it,
// then every remaining field name becomes its property's label.
std::string InUserTerms(std::string text)
{
  const std::pair<const char*, const char*> phrases[] = {
    { "lower timeStep (more substeps per frame) or use automatic time stepping",
      "raise Substeps Per Frame (or lower Frame Interval), or set Time Stepping to Automatic" },
    { "lower cflNumber or the largest time step", "lower CFL Number or Max Time Step" },
    { "lower timeStep first",
      "lower the time step first (Time Stepping Automatic, a smaller CFL Number or Max Time Step; "
      "with Fixed steps more Substeps Per Frame)" },
    { "raise relaxation", "raise Relaxation Epsilon" },
  };
  for (const auto& phrase : phrases)
  {
    for (std::size_t at = text.find(phrase.first); at != std::string::npos;
         at = text.find(phrase.first, at + std::strlen(phrase.second)))
    {
      text.replace(at, std::strlen(phrase.first), phrase.second);
    }
  }
  const std::pair<const char*, const char*> fields[] = {
    { "maxDensityErrorTolerance", "Max Density Error Tolerance" },
    { "densityErrorTolerance", "Density Error Tolerance" },
    { "particleSpacing", "Particle Spacing" },
    { "smoothingRatio", "Smoothing Ratio" },
    { "solverIterations", "Solver Iterations" },
    { "restDensity", "Rest Density" },
    { "cflNumber", "CFL Number" },
    { "xsphViscosity", "XSPH Viscosity" },
    { "vorticityEpsilon", "Vorticity Epsilon" },
    { "sCorrDeltaQ", "S Corr Delta Q" },
    { "sCorrK", "S Corr K" },
    { "sCorrN", "S Corr N" },
    { "timeStep", "the time step" },
  };
  auto isWordCharacter = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (const auto& field : fields)
  {
    const std::size_t length = std::strlen(field.first);
    for (std::size_t at = text.find(field.first); at != std::string::npos;
         at = text.find(field.first, at + 1))
    {
      const bool whole = (at == 0 || !isWordCharacter(text[at - 1])) &&
        (at + length == text.size() || !isWordCharacter(text[at + length]));
      if (whole)
      {
        text.replace(at, length, field.second);
      }
    }
  }
  return text;
}

// Collective over the ranks of a decomposed run: true on every rank when it is true on any.
bool AnyRank(pbf::distributed::Communicator& ranks, bool mine)
{
  for (const std::vector<double>& theirs : pbf::distributed::allGather(ranks, { mine ? 1.0 : 0.0 }))
  {
    if (theirs[0] != 0.0)
    {
      return true;
    }
  }
  return false;
}

// One row of the diagnostics table.
struct FrameRow
{
  double Time = 0;
  double AverageDensityError = 0; // percent
  double MaxDensityError = 0;     // percent
  double AverageNeighbors = 0;
  double SolverIterations = NaN;    // per step, averaged over the frame's substeps
  double MillisecondsPerStep = NaN; // likewise
  double Substeps = NaN;            // the frame's solver steps
  double MinTimeStep = NaN;         // the smallest and largest of their dt [s]
  double MaxTimeStep = NaN;
  double MaxSpeed = 0;
  double KineticEnergy = 0;
  vtkIdType Particles = 0;
  std::string Backend;
  double LoadImbalance = 0; // decomposed runs: the largest rank's particles over the mean - 1, %
};

} // namespace

class vtkPBFSimulation::vtkInternals
{
public:
  // What the live simulation, the checkpoints, the rows and the reusable output were computed
  // for; all of them are dropped together when it changes.
  Configuration Key;
  bool HasKey = false;

  // The simulation of Key at its current step (a whole step, not always a whole frame: an
  // aborted request leaves it where it stopped); null when none is valid.
  std::unique_ptr<pbf::Simulation> Live;
  // The solver steps already taken towards the next frame of Live, so that its row counts every
  // substep even when the frame was finished by a later request.
  long PendingIterations = 0;
  double PendingMilliseconds = 0;
  int PendingSteps = 0;
  double PendingMinTimeStep = 0;
  double PendingMaxTimeStep = 0;

  // Checkpoints by frame, and the interval new ones are taken at (CheckpointInterval, doubled
  // each time the budget forced a thinning).
  std::map<int, pbf::SimulationCheckpoint> Checkpoints;
  std::size_t CheckpointBytes = 0;
  int RequestedInterval = 0;
  int Stride = 0;

  // Diagnostics by frame, and the table last put on port 1.
  std::map<int, FrameRow> Rows;
  bool TableStale = true;
  vtkSmartPointer<vtkTable> Table = vtkSmartPointer<vtkTable>::New();
  vtkSmartPointer<vtkTable> EmptyTable = vtkSmartPointer<vtkTable>::New();

  // What the last successful request produced (a failed or aborted request hands it out again)
  // and, when it is a frame of Key, which one (-1 otherwise).
  vtkSmartPointer<vtkPolyData> LastOutput = vtkSmartPointer<vtkPolyData>::New();
  int LastFrame = -1;

  // The outline of the domain last simulated (port 2), kept when a request fails.
  vtkSmartPointer<vtkPolyData> Domain = vtkSmartPointer<vtkPolyData>::New();

  // Reused from frame to frame while the particle count stays.
  vtkSmartPointer<vtkCellArray> Vertices;

  // The cost of the last request.
  double SimulationMilliseconds = 0;
  double DiagnosticsMilliseconds = 0;
  double CheckpointMilliseconds = 0;
  double DeliveryMilliseconds = 0;
  vtkIdType RequestSteps = 0;

  // The ranks of a decomposed run (Key.Ranks > 1), over ParaView's global controller: its MPI
  // communicator where it has one (pvbatch under mpiexec, a pvserver), so that a rank whose GPU
  // faults stops every rank with its error (Distributed/RankFailure.h).
  std::unique_ptr<pbf::distributed::Communicator> Ranks;

  // CUDA is probed once: a device does not come and go while ParaView runs.
  bool CudaProbed = false;
  bool CudaPresent = false;
  std::string CudaAbsence;
  bool FallbackReported = false;

  // Key's run met a device fault and went on (or may go on) on the CPU; the warning said so and
  // the frames computed since carry it in their field data ("DeviceFault").
  bool DeviceFaulted = false;
  std::string DeviceFaultText;

  bool HasCuda()
  {
    if (!this->CudaProbed)
    {
      this->CudaPresent = pbf::cudaAvailable(&this->CudaAbsence);
      this->CudaProbed = true;
    }
    return this->CudaPresent;
  }

  // Drops everything computed for another configuration; the last output stays, for failures.
  void Adopt(const Configuration& configuration)
  {
    if (this->HasKey && this->Key == configuration)
    {
      return;
    }
    // After a device fault, moving the same run off the GPU keeps its checkpoints and rows: they
    // are host copies, and losing them would lose the user's frames.
    if (this->HasKey && this->DeviceFaulted && this->Key.Backend == pbf::Backend::CUDA)
    {
      Configuration moved = this->Key;
      moved.Backend = configuration.Backend;
      if (moved == configuration)
      {
        this->Live.reset();
        this->ResetPending();
        this->Key = moved;
        return;
      }
    }
    // Free the old state first: two large simulations need not fit at once.
    this->Live.reset();
    this->ResetPending();
    this->Checkpoints.clear();
    this->CheckpointBytes = 0;
    this->Stride = this->RequestedInterval;
    this->Rows.clear();
    this->TableStale = true;
    this->LastFrame = -1;
    this->DeviceFaulted = false;
    this->DeviceFaultText.clear();
    this->Key = configuration;
    this->HasKey = true;
  }

  void ResetPending()
  {
    this->PendingIterations = 0;
    this->PendingMilliseconds = 0;
    this->PendingSteps = 0;
    this->PendingMinTimeStep = 0;
    this->PendingMaxTimeStep = 0;
  }

  // Counts the steps of `report` towards the next frame's row.
  void AddPending(const pbf::AdvanceReport& report)
  {
    if (report.steps == 0)
    {
      return;
    }
    this->PendingMinTimeStep = this->PendingSteps == 0
      ? report.minTimeStep
      : std::min(this->PendingMinTimeStep, report.minTimeStep);
    this->PendingMaxTimeStep = std::max(this->PendingMaxTimeStep, report.maxTimeStep);
    this->PendingIterations += report.iterations;
    this->PendingMilliseconds += report.milliseconds;
    this->PendingSteps += static_cast<int>(report.steps);
  }

  // Applies CheckpointInterval and CheckpointMemoryMB; checkpoints already taken stay valid.
  void ConfigureCheckpoints(int interval, std::size_t budget)
  {
    if (interval != this->RequestedInterval)
    {
      this->RequestedInterval = interval;
      this->Stride = interval;
    }
    if (interval <= 0)
    {
      this->Checkpoints.clear();
      this->CheckpointBytes = 0;
      return;
    }
    this->FitBudget(budget);
  }

  // The bytes the budget is compared with. Decomposed, each rank holds its slab's share of a
  // checkpoint, so the ranks would thin at different frames and resume from different ones
  // (wrong particles, no error): the largest rank's bytes decide for every rank. Collective:
  // every rank fits its budget at the same requests and frames.
  double BudgetedBytes()
  {
    double largest = static_cast<double>(this->CheckpointBytes);
    if (this->Key.Ranks > 1 && this->Ranks)
    {
      for (const std::vector<double>& r : pbf::distributed::allGather(*this->Ranks, { largest }))
      {
        largest = std::max(largest, r[0]);
      }
    }
    return largest;
  }

  // The thinning policy: while over budget, double the interval and drop the checkpoints off it.
  // The earliest checkpoint (frame 0 unless checkpoints were switched on late) always stays.
  void FitBudget(std::size_t budget)
  {
    while (this->Checkpoints.size() > 1 && this->BudgetedBytes() > static_cast<double>(budget))
    {
      this->Stride *= 2;
      const int earliest = this->Checkpoints.begin()->first;
      for (auto it = this->Checkpoints.begin(); it != this->Checkpoints.end();)
      {
        if (it->first != earliest && it->first % this->Stride != 0)
        {
          this->CheckpointBytes -= it->second.bytes();
          it = this->Checkpoints.erase(it);
        }
        else
        {
          ++it;
        }
      }
    }
  }

  void TakeCheckpoint(int frame, std::size_t budget)
  {
    if (this->Stride <= 0 || frame % this->Stride != 0 || this->Checkpoints.count(frame))
    {
      return;
    }
    const auto start = std::chrono::steady_clock::now();
    pbf::SimulationCheckpoint checkpoint = this->Live->checkpoint();
    this->CheckpointBytes += checkpoint.bytes();
    this->Checkpoints.emplace(frame, std::move(checkpoint));
    this->FitBudget(budget);
    this->CheckpointMilliseconds += Milliseconds(start);
  }

  // The row of the frame the live simulation has just reached. A frame computed again (after
  // going back) keeps its first row: the same state, so only the timing could differ, and a
  // plotted curve should not jitter while scrubbing.
  void RecordFrame(int frame)
  {
    if (this->Rows.count(frame))
    {
      this->ResetPending();
      return;
    }
    const auto start = std::chrono::steady_clock::now();
    const pbf::Stepper& stepper = this->Live->stepper();
    const pbf::Statistics statistics = stepper.statistics();
    FrameRow row;
    row.Time = this->Live->time();
    row.AverageDensityError = 100.0 * statistics.averageDensityError;
    row.MaxDensityError = 100.0 * statistics.maxDensityError;
    row.AverageNeighbors = statistics.averageNeighbors;
    if (this->PendingSteps > 0)
    {
      row.SolverIterations = static_cast<double>(this->PendingIterations) / this->PendingSteps;
      row.MillisecondsPerStep = this->PendingMilliseconds / this->PendingSteps;
      row.Substeps = this->PendingSteps;
      row.MinTimeStep = this->PendingMinTimeStep;
      row.MaxTimeStep = this->PendingMaxTimeStep;
    }
    row.MaxSpeed = statistics.maxSpeed;
    row.KineticEnergy = statistics.kineticEnergy;
    row.Particles = static_cast<vtkIdType>(statistics.particles);
    if (this->Key.Ranks > 1)
    {
      // Collective, as statistics() is: every rank records the same frames.
      double largest = 0, total = 0;
      for (const std::vector<double>& r :
        pbf::distributed::allGather(*this->Ranks, { double(stepper.size()) }))
      {
        largest = std::max(largest, r[0]);
        total += r[0];
      }
      row.LoadImbalance = total > 0 ? 100.0 * (largest * this->Key.Ranks / total - 1.0) : 0.0;
    }
    row.Backend = stepper.description();
    this->Rows[frame] = row;
    this->TableStale = true;
    this->ResetPending();
    this->DiagnosticsMilliseconds += Milliseconds(start);
  }

  vtkTable* DiagnosticsTable()
  {
    // A decomposed run's rows are reduced over the ranks and the same on each: rank 0 shows them.
    if (this->HasKey && this->Key.Ranks > 1 && this->Ranks && this->Ranks->rank() != 0)
    {
      return this->EmptyTable;
    }
    if (!this->TableStale)
    {
      return this->Table;
    }
    const auto rows = static_cast<vtkIdType>(this->Rows.size());
    auto time = NewArray<vtkDoubleArray>("Time", 1, rows);
    auto frame = NewArray<vtkIdTypeArray>("Frame", 1, rows);
    auto averageError = NewArray<vtkDoubleArray>("AverageDensityError", 1, rows);
    auto maxError = NewArray<vtkDoubleArray>("MaxDensityError", 1, rows);
    auto neighbors = NewArray<vtkDoubleArray>("AverageNeighbors", 1, rows);
    auto iterations = NewArray<vtkDoubleArray>("SolverIterations", 1, rows);
    auto milliseconds = NewArray<vtkDoubleArray>("MillisecondsPerStep", 1, rows);
    auto substeps = NewArray<vtkDoubleArray>("Substeps", 1, rows);
    auto minTimeStep = NewArray<vtkDoubleArray>("MinTimeStep", 1, rows);
    auto maxTimeStep = NewArray<vtkDoubleArray>("MaxTimeStep", 1, rows);
    auto maxSpeed = NewArray<vtkDoubleArray>("MaxSpeed", 1, rows);
    auto kinetic = NewArray<vtkDoubleArray>("KineticEnergy", 1, rows);
    auto particles = NewArray<vtkIdTypeArray>("Particles", 1, rows);
    vtkNew<vtkStringArray> backend;
    backend->SetName("Backend");
    backend->SetNumberOfValues(rows);
    vtkIdType r = 0;
    for (const auto& entry : this->Rows)
    {
      const FrameRow& row = entry.second;
      time->SetValue(r, row.Time);
      frame->SetValue(r, entry.first);
      averageError->SetValue(r, row.AverageDensityError);
      maxError->SetValue(r, row.MaxDensityError);
      neighbors->SetValue(r, row.AverageNeighbors);
      iterations->SetValue(r, row.SolverIterations);
      milliseconds->SetValue(r, row.MillisecondsPerStep);
      substeps->SetValue(r, row.Substeps);
      minTimeStep->SetValue(r, row.MinTimeStep);
      maxTimeStep->SetValue(r, row.MaxTimeStep);
      maxSpeed->SetValue(r, row.MaxSpeed);
      kinetic->SetValue(r, row.KineticEnergy);
      particles->SetValue(r, row.Particles);
      backend->SetValue(r, row.Backend);
      ++r;
    }
    this->Table = vtkSmartPointer<vtkTable>::New();
    for (vtkAbstractArray* column :
      std::initializer_list<vtkAbstractArray*>{ time, frame, averageError, maxError, neighbors,
        iterations, milliseconds, substeps, minTimeStep, maxTimeStep, maxSpeed, kinetic,
        particles, backend })
    {
      this->Table->AddColumn(column);
    }
    if (this->Key.Ranks > 1)
    {
      auto imbalance = NewArray<vtkDoubleArray>("LoadImbalance", 1, rows);
      r = 0;
      for (const auto& entry : this->Rows)
      {
        imbalance->SetValue(r++, entry.second.LoadImbalance);
      }
      this->Table->AddColumn(imbalance);
    }
    this->TableStale = false;
    return this->Table;
  }
};

vtkStandardNewMacro(vtkPBFSimulation);

//------------------------------------------------------------------------------
vtkPBFSimulation::vtkPBFSimulation()
  : Internals(new vtkInternals)
{
  // The physics defaults are the solver's, so the two cannot drift.
  const pbf::Parameters defaults;
  this->Preset = PRESET_DAM_BREAK;
  this->SceneFile = nullptr;
  this->RestDensity = defaults.restDensity;
  this->ParticleSpacing = defaults.particleSpacing;
  this->SmoothingRatio = defaults.smoothingRatio;
  this->SolverIterations = defaults.solverIterations;
  this->RelaxationEpsilon = defaults.relaxation;
  this->SCorrK = defaults.sCorrK;
  this->SCorrN = defaults.sCorrN;
  this->SCorrDeltaQ = defaults.sCorrDeltaQ;
  this->XSPHViscosity = defaults.xsphViscosity;
  this->VorticityEpsilon = defaults.vorticityEpsilon;
  this->Unilateral = defaults.unilateral;
  this->MirrorWalls = defaults.mirrorWalls;
  this->Gravity[0] = defaults.gravity.x;
  this->Gravity[1] = defaults.gravity.y;
  this->Gravity[2] = defaults.gravity.z;
  // The solver's default is adaptive (its tolerance, with SolverIterations as the cap).
  this->AdaptiveIterations = defaults.densityErrorTolerance > 0;
  this->DensityErrorTolerance =
    defaults.densityErrorTolerance > 0 ? defaults.densityErrorTolerance : 0.2;
  this->MaxDensityErrorTolerance = defaults.maxDensityErrorTolerance;
  this->FrameInterval = 1.0 / 60.0;
  this->SubstepsPerFrame = 4;
  this->TimeStepping =
    defaults.timeStepping == pbf::TimeStepping::Automatic ? TIME_STEPPING_AUTOMATIC : TIME_STEPPING_FIXED;
  this->CFLNumber = defaults.cflNumber;
  this->MaxTimeStep = defaults.timeStep;
  this->NumberOfFrames = 120;
  this->CheckpointInterval = 10;
  this->CheckpointMemoryMB = 1024.0;
  this->PageLockedOutput = true;
  this->Backend = BACKEND_AUTO;
  this->DecomposeAcrossRanks = true;
  this->Precision = PRECISION_SINGLE;

  // Port 0 is optional: without an input the algorithm is a source.
  this->SetNumberOfInputPorts(1);
  // Port 0: the particles of the frame; port 1: the diagnostics table; port 2: the outline of
  // the domain (the tank), so that a view shows and frames the whole of it from frame 0 on.
  this->SetNumberOfOutputPorts(3);
}

//------------------------------------------------------------------------------
vtkPBFSimulation::~vtkPBFSimulation()
{
  this->SetSceneFile(nullptr);
}

//------------------------------------------------------------------------------
const char* vtkPBFSimulation::GetPresetName() const
{
  return PresetNames[this->Preset];
}

//------------------------------------------------------------------------------
double vtkPBFSimulation::GetLastSimulationMilliseconds() const
{
  return this->Internals->SimulationMilliseconds;
}

//------------------------------------------------------------------------------
double vtkPBFSimulation::GetLastDiagnosticsMilliseconds() const
{
  return this->Internals->DiagnosticsMilliseconds;
}

//------------------------------------------------------------------------------
double vtkPBFSimulation::GetLastCheckpointMilliseconds() const
{
  return this->Internals->CheckpointMilliseconds;
}

//------------------------------------------------------------------------------
double vtkPBFSimulation::GetLastDeliveryMilliseconds() const
{
  return this->Internals->DeliveryMilliseconds;
}

//------------------------------------------------------------------------------
vtkIdType vtkPBFSimulation::GetLastRequestSteps() const
{
  return this->Internals->RequestSteps;
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::FillInputPortInformation(int port, vtkInformation* info)
{
  if (port != 0)
  {
    return 0;
  }
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPointSet");
  info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::FillOutputPortInformation(int port, vtkInformation* info)
{
  if (port == 1)
  {
    info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkTable");
    return 1;
  }
  return this->Superclass::FillOutputPortInformation(port, info);
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::FrameForTime(double time) const
{
  if (!std::isfinite(time) || time <= 0.0 || !this->InvalidTimeProperty().empty())
  {
    return 0;
  }
  const double frame = std::round(time / this->FrameInterval);
  return static_cast<int>(std::min(frame, static_cast<double>(this->NumberOfFrames)));
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  // The time steps are this algorithm's frames, whatever the input's were. Both ports announce
  // them: the table grows as frames are computed.
  // Invalid time properties announce frame 0 only; RequestData then names the property.
  const bool valid = this->InvalidTimeProperty().empty();
  std::vector<double> times(valid ? static_cast<std::size_t>(this->NumberOfFrames) + 1 : 1, 0.0);
  for (std::size_t k = 0; k < times.size(); ++k)
  {
    times[k] = static_cast<double>(k) * this->FrameInterval;
  }
  const double range[2] = { times.front(), times.back() };
  for (int port = 0; port < this->GetNumberOfOutputPorts(); ++port)
  {
    vtkInformation* outInfo = outputVector->GetInformationObject(port);
    outInfo->Set(
      vtkStreamingDemandDrivenPipeline::TIME_STEPS(), times.data(), static_cast<int>(times.size()));
    outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
    // Each rank of a parallel run owns a slab of the fluid (piece = rank); see RequestData.
    outInfo->Set(vtkAlgorithm::CAN_HANDLE_PIECE_REQUEST(), 1);
  }
  return 1;
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector*)
{
  if (this->GetNumberOfInputConnections(0) == 0)
  {
    return 1;
  }
  vtkInformation* inInfo = inputVector[0]->GetInformationObject(0);
  // The whole input in one piece, on every rank alike so that a collective upstream filter sees
  // the same request everywhere; only piece 0 simulates it.
  inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), 0);
  inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(), 1);
  inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_GHOST_LEVELS(), 0);
  // The input is the initial state: ask for its first time, not for the frame being computed,
  // so that playing the animation does not re-execute the input.
  if (inInfo->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) &&
    inInfo->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) > 0)
  {
    inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(),
      inInfo->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS())[0]);
  }
  else
  {
    inInfo->Remove(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
  }
  return 1;
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  const int result = this->RequestFrame(request, inputVector, outputVector);
  this->RequestDomain(outputVector);
  return result;
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::RequestDomain(vtkInformationVector* outputVector)
{
  vtkInternals& internals = *this->Internals;
  vtkPolyData* domain = vtkPolyData::GetData(outputVector, 2);
  vtkPolyData* particles = vtkPolyData::GetData(outputVector, 0);
  if (internals.Live)
  {
    const pbf::Box& box = internals.Live->parameters().domain;
    vtkNew<vtkOutlineSource> outline;
    outline->SetBounds(box.min.x, box.max.x, box.min.y, box.max.y, box.min.z, box.max.z);
    outline->Update();
    internals.Domain = outline->GetOutput();
    vtkNew<vtkStringArray> scene;
    scene->SetName("Scene");
    scene->InsertNextValue(internals.Live->scene().name);
    internals.Domain->GetFieldData()->AddArray(scene);
  }
  // One outline for the whole run: rank 0's (the others would only draw it again).
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  const bool mine = !controller || controller->GetLocalProcessId() == 0;
  if (mine)
  {
    domain->ShallowCopy(internals.Domain);
  }
  else
  {
    domain->Initialize();
  }
  vtkInformation* shown = particles->GetInformation();
  if (shown->Has(vtkDataObject::DATA_TIME_STEP()))
  {
    domain->GetInformation()->Set(
      vtkDataObject::DATA_TIME_STEP(), shown->Get(vtkDataObject::DATA_TIME_STEP()));
  }
}

//------------------------------------------------------------------------------
std::string vtkPBFSimulation::InvalidTimeProperty() const
{
  std::ostringstream text;
  if (!std::isfinite(this->FrameInterval) || this->FrameInterval <= 0.0)
  {
    text << "Frame Interval = " << this->FrameInterval << ": must be > 0 (seconds between frames)";
  }
  else if (this->NumberOfFrames < 0)
  {
    text << "Number Of Frames = " << this->NumberOfFrames << ": must be >= 0";
  }
  else if (this->TimeStepping == TIME_STEPPING_FIXED && this->SubstepsPerFrame < 1)
  {
    text << "Substeps Per Frame = " << this->SubstepsPerFrame << ": must be >= 1";
  }
  else if (this->TimeStepping == TIME_STEPPING_AUTOMATIC &&
    (!std::isfinite(this->MaxTimeStep) || this->MaxTimeStep <= 0.0))
  {
    text << "Max Time Step = " << this->MaxTimeStep << ": must be > 0 (seconds)";
  }
  return text.str();
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::RequestFrame(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(outInfo);
  vtkTable* table = vtkTable::GetData(outputVector, 1);
  vtkInternals& internals = *this->Internals;
  internals.SimulationMilliseconds = 0;
  internals.DiagnosticsMilliseconds = 0;
  internals.CheckpointMilliseconds = 0;
  internals.DeliveryMilliseconds = 0;
  internals.RequestSteps = 0;

  // The request may come through either port; both carry the same time.
  int requestPort = request->Has(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    ? request->Get(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    : 0;
  if (requestPort < 0 || requestPort >= this->GetNumberOfOutputPorts())
  {
    requestPort = 0;
  }
  vtkInformation* requestInfo = outputVector->GetInformationObject(requestPort);
  double requested = 0.0;
  if (requestInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
  {
    requested = requestInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
  }
  const int frame = this->FrameForTime(requested);
  const double frameTime = static_cast<double>(frame) * this->FrameInterval;

  const int piece = requestInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER())
    ? requestInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER())
    : 0;
  const int pieces =
    requestInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES())
    ? requestInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES())
    : 1;
  // One piece per rank of ParaView's parallel engine: a domain-decomposed run, in which every
  // rank takes part in every request. Any other split (streaming pieces in one process) gets the
  // whole fluid on piece 0.
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  const bool decomposed = this->DecomposeAcrossRanks && pieces > 1 && controller &&
    controller->GetNumberOfProcesses() == pieces && controller->GetLocalProcessId() == piece;
  if (piece > 0 && !decomposed)
  {
    // Piece 0 holds the whole fluid; see the class documentation.
    output->Initialize();
    output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frameTime);
    table->Initialize();
    table->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frameTime);
    return 1;
  }

  // Hands out the last good output (with its own time) and the diagnostics known so far.
  auto deliverPrevious = [&]()
  {
    output->ShallowCopy(internals.LastOutput);
    table->ShallowCopy(internals.DiagnosticsTable());
    vtkInformation* last = internals.LastOutput->GetInformation();
    if (last->Has(vtkDataObject::DATA_TIME_STEP()))
    {
      const double shown = last->Get(vtkDataObject::DATA_TIME_STEP());
      output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), shown);
      table->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), shown);
    }
  };

  if (this->GetAbortOutput())
  {
    // An upstream algorithm aborted: the executive empties the outputs and marks them aborted.
    return 1;
  }

  vtkPointSet* input = this->GetNumberOfInputConnections(0) > 0
    ? vtkPointSet::GetData(inputVector[0]->GetInformationObject(0))
    : nullptr;

  try
  {
    const std::string invalidTime = this->InvalidTimeProperty();
    if (!invalidTime.empty())
    {
      throw pbf::InvalidInput(invalidTime);
    }
    Configuration configuration;
    const std::string sceneFile = this->SceneFile ? this->SceneFile : "";
    configuration.SceneKey = sceneFile.empty()
      ? std::string("preset ") + this->GetPresetName()
      : "file " + sceneFile + "\n" + ReadWholeFile(sceneFile);

    pbf::Parameters& p = configuration.Parameters;
    p.restDensity = this->RestDensity;
    p.particleSpacing = this->ParticleSpacing;
    p.smoothingRatio = this->SmoothingRatio;
    p.solverIterations = this->SolverIterations;
    p.densityErrorTolerance = this->AdaptiveIterations ? this->DensityErrorTolerance : 0.0;
    p.maxDensityErrorTolerance = this->MaxDensityErrorTolerance;
    p.relaxation = this->RelaxationEpsilon;
    p.sCorrK = this->SCorrK;
    p.sCorrN = this->SCorrN;
    p.sCorrDeltaQ = this->SCorrDeltaQ;
    p.xsphViscosity = this->XSPHViscosity;
    p.vorticityEpsilon = this->VorticityEpsilon;
    p.unilateral = this->Unilateral;
    p.mirrorWalls = this->MirrorWalls;
    p.gravity = pbf::Vec3d{ this->Gravity[0], this->Gravity[1], this->Gravity[2] };
    // Fixed: SubstepsPerFrame equal steps per frame. Automatic: steps chosen from the state, at
    // most MaxTimeStep, landing on every frame; SubstepsPerFrame then changes nothing.
    const bool automatic = this->TimeStepping == TIME_STEPPING_AUTOMATIC;
    p.timeStepping = automatic ? pbf::TimeStepping::Automatic : pbf::TimeStepping::Fixed;
    p.timeStep = automatic ? this->MaxTimeStep : this->FrameInterval / this->SubstepsPerFrame;
    p.cflNumber = automatic ? this->CFLNumber : pbf::Parameters().cflNumber;
    configuration.FrameInterval = this->FrameInterval;
    configuration.Substeps = automatic ? 0 : this->SubstepsPerFrame;

    configuration.Precision =
      this->Precision == PRECISION_DOUBLE ? pbf::Precision::Double : pbf::Precision::Single;
    if (decomposed && !internals.Ranks)
    {
      internals.Ranks = MakeRankCommunicator(controller);
    }
    if (internals.Ranks && internals.Ranks->failed())
    {
      // Every rank failed together (the same error on each), so every rank comes here and opens
      // a fresh channel before the next collective call, leaving the failed one's messages behind.
      internals.Ranks->recover();
    }
    // Whether CUDA can run. In a decomposed run every rank takes its local rank's GPU, and the
    // ranks must agree before the first exchange (a rank whose host has no GPU must not fail
    // alone while the others wait for it), so CUDA runs there only when every rank has a GPU.
    bool cuda = internals.HasCuda();
    std::string noCuda = internals.CudaAbsence;
    if (decomposed && (this->Backend == BACKEND_CUDA || this->Backend == BACKEND_AUTO))
    {
      const bool everyRank = !AnyRank(*internals.Ranks, !cuda);
      if (cuda && !everyRank)
      {
        noCuda = "another rank of the " + std::to_string(pieces) + " has no usable GPU";
      }
      else if (!cuda)
      {
        noCuda = "rank " + std::to_string(piece) + ": " + noCuda;
      }
      cuda = everyRank;
    }
    switch (this->Backend)
    {
      case BACKEND_CUDA:
        if (!cuda)
        {
          throw std::runtime_error(
            "Backend = CUDA: CUDA backend unavailable: " + noCuda + " (choose Auto or CPU (OpenMP))");
        }
        configuration.Backend = pbf::Backend::CUDA;
        break;
      case BACKEND_OPENMP:
        configuration.Backend = pbf::Backend::OpenMP;
        break;
      case BACKEND_SERIAL:
        configuration.Backend = pbf::Backend::Serial;
        break;
      default:
        if (cuda)
        {
          configuration.Backend = pbf::Backend::CUDA;
        }
        else
        {
          configuration.Backend = pbf::Backend::OpenMP;
          if (!internals.FallbackReported)
          {
            internals.FallbackReported = true;
            std::ostringstream text;
            text << this->GetClassName() << " (" << this << "): Backend Auto: no CUDA ("
                 << noCuda << "); falling back to CPU (OpenMP).\n";
            vtkOutputWindowDisplayText(text.str().c_str());
          }
        }
        break;
    }

    if (decomposed)
    {
      // Every rank gets here for the same request and makes the same choices. Both decomposed
      // steppers run adaptive iterations and automatic steps (they reduce over the ranks).
      configuration.Ranks = pieces;
    }
    configuration.HasInput = input != nullptr;
    configuration.InputMTime = input ? input->GetMTime() : 0;

    const int substeps = this->SubstepsPerFrame;
    const std::size_t budget =
      static_cast<std::size_t>(std::min(this->CheckpointMemoryMB * 1048576.0, 1e18));
    internals.Adopt(configuration);
    internals.ConfigureCheckpoints(this->CheckpointInterval, budget);

    // The frame just delivered: hand it out again, arrays shared, nothing stepped or copied.
    if (internals.LastFrame == frame)
    {
      output->ShallowCopy(internals.LastOutput);
      vtkNew<vtkFieldData> fieldData;
      fieldData->ShallowCopy(internals.LastOutput->GetFieldData());
      AddInteger(fieldData, "RequestSteps", 0);
      AddText(fieldData, "ResumedFrom", "output");
      vtkDataArray* steps = internals.LastOutput->GetFieldData()->GetArray("StepCount");
      AddInteger(fieldData, "ResumedFromStep",
        steps ? static_cast<vtkIdType>(steps->GetTuple1(0)) : vtkIdType(0));
      output->SetFieldData(fieldData);
      output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frameTime);
      table->ShallowCopy(internals.DiagnosticsTable());
      table->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frameTime);
      return 1;
    }

    // Frame k is at k * FrameInterval exactly: the simulation lands on it (Simulation::advanceTo).
    const double interval = this->FrameInterval;
    const double targetTime = static_cast<double>(frame) * interval;

    // Builds the live simulation at step 0 (the scene and the input are read only then).
    auto build = [&]()
    {
      internals.Live.reset();
      internals.ResetPending();
      const pbf::Scene scene =
        sceneFile.empty() ? pbf::presetScene(this->GetPresetName()) : pbf::loadSceneFile(sceneFile);
      const Configuration& c = configuration;
      // Decomposed, every rank builds the whole fluid (from the whole input, which
      // RequestUpdateExtent asks for on every rank) and keeps its slab.
      pbf::distributed::Communicator* ranks = c.Ranks > 1 ? internals.Ranks.get() : nullptr;
      if (ranks && ranks->failed())
      {
        // Every rank failed together (the same error on each): every rank comes here and opens
        // a fresh channel, leaving the failed one's messages behind.
        ranks->recover();
      }
      if (input)
      {
        internals.Live = std::make_unique<pbf::Simulation>(
          scene, c.Parameters, c.Backend, c.Precision, BatchFromInput(input), ranks);
      }
      else
      {
        internals.Live =
          std::make_unique<pbf::Simulation>(scene, c.Parameters, c.Backend, c.Precision, ranks);
      }
      internals.RecordFrame(0);
      internals.TakeCheckpoint(0, budget);
    };

    // The GPU failed (a lost device, a kernel that faulted): its copy of the state is gone, while
    // the checkpoints and the diagnostics rows are host copies of whole frames and stay. CUDA is
    // not tried again (a lost context stays lost until the process ends). Backend Auto goes on
    // on the CPU; Backend CUDA stops with an error that says how to go on.
    auto handleDeviceFault = [&](const pbf::DeviceFault& fault)
    {
      const std::uint64_t failedAt = internals.Live ? internals.Live->stepCount() : 0;
      internals.Live.reset();
      internals.ResetPending();
      internals.CudaProbed = true;
      internals.CudaPresent = false;
      internals.CudaAbsence = std::string("the GPU failed earlier: ") + fault.what();
      internals.DeviceFaulted = true;
      internals.FallbackReported = true; // this message says it; the Auto notice need not
      auto kept = internals.Checkpoints.upper_bound(frame);
      const std::string resumable = kept == internals.Checkpoints.begin()
        ? std::string("the initial state")
        : "frame " + std::to_string(std::prev(kept)->first) + " (a checkpoint)";
      std::ostringstream text;
      text << "CUDA device fault near step " << failedAt << ", on the way to frame " << frame
           << ": " << fault.what() << ". ";
      if (this->Backend != BACKEND_AUTO || configuration.Backend != pbf::Backend::CUDA)
      {
        text << "The previous output stays and so do the checkpoints: choose Backend Auto or CPU "
                "(OpenMP) to go on from "
             << resumable << " on the CPU.";
        throw std::runtime_error(text.str());
      }
      text << "Backend Auto: falling back to CPU (OpenMP) from " << resumable
           << "; the frames from there on are computed on the CPU (they agree with the GPU's to "
              "rounding, not bit for bit).";
      configuration.Backend = pbf::Backend::OpenMP;
      internals.Key.Backend = pbf::Backend::OpenMP;
      internals.DeviceFaultText = text.str();
      vtkWarningMacro(<< internals.DeviceFaultText);
    };

    // A device fault with Backend Auto moves the run to the CPU; the loop then goes round once
    // more, from the checkpoints.
    for (;;)
    {
      try
      {
        // Where to start: the live simulation when it is not past the frame, unless a checkpoint is
        // nearer; otherwise the latest checkpoint at or before the frame; otherwise step 0.
        std::string resumedFrom = "live";
        const pbf::SimulationCheckpoint* checkpoint = nullptr;
        auto after = internals.Checkpoints.upper_bound(frame);
        if (after != internals.Checkpoints.begin())
        {
          checkpoint = &std::prev(after)->second;
        }
        const bool liveUsable = internals.Live && internals.Live->time() <= targetTime;
        if (!(liveUsable && (!checkpoint || checkpoint->time <= internals.Live->time())))
        {
          if (checkpoint)
          {
            if (!internals.Live)
            {
              build();
            }
            internals.Live->restore(*checkpoint);
            internals.ResetPending();
            resumedFrom = "checkpoint";
          }
          else
          {
            build();
            resumedFrom = "initial";
          }
        }
        pbf::Simulation& simulation = *internals.Live;
        const std::uint64_t resumedFromStep = simulation.stepCount();
        const double resumedFromTime = simulation.time();
        // The next frame the live simulation lands on: it is on frame k (time k * interval
        // exactly) or between k and k + 1 after an abort.
        int next = static_cast<int>(std::floor(resumedFromTime / interval));
        while (static_cast<double>(next + 1) * interval <= resumedFromTime)
        {
          ++next;
        }
        while (next > 0 && static_cast<double>(next) * interval > resumedFromTime)
        {
          --next;
        }
        ++next;

        // Step to the frame, frame by frame (the steps of a frame depend only on the state at its
        // start, so every way of reaching a frame takes the same steps), one solver step at a
        // time: progress and abort are checked after each.
        const double total = targetTime - resumedFromTime;
        bool aborted = false;
        while (simulation.time() < targetTime)
        {
          pbf::AdvanceReport report;
          const bool landed =
            simulation.stepToward(static_cast<double>(next) * interval, report);
          internals.AddPending(report);
          internals.SimulationMilliseconds += report.milliseconds;
          internals.RequestSteps += static_cast<vtkIdType>(report.steps);
          if (landed)
          {
            internals.RecordFrame(next);
            internals.TakeCheckpoint(next, budget);
            ++next;
          }
          this->UpdateProgress((simulation.time() - resumedFromTime) / total);
          // AbortExecute stays set, as VTK has it: whoever set it clears it (SetAbortExecute(0)
          // also marks this algorithm modified, so that the same time asked again re-executes).
          bool stop = this->GetAbortExecute() && simulation.time() < targetTime;
          if (configuration.Ranks > 1 && simulation.time() < targetTime)
          {
            // A rank that left alone would leave the others waiting for it in the next step's
            // exchange: the ranks agree after every step, and any rank's abort stops them all at
            // the same step (so their slabs stay consistent and the next request resumes).
            stop = AnyRank(*internals.Ranks, stop);
          }
          if (stop)
          {
            aborted = true;
            break;
          }
        }
        if (aborted)
        {
          std::ostringstream text;
          text << this->GetClassName() << " (" << this << "): aborted at step "
               << simulation.stepCount() << " (t = " << simulation.time()
               << " s) on the way to frame " << frame << " (t = " << targetTime
               << " s); the previous output stays.\n";
          vtkOutputWindowDisplayText(text.str().c_str());
          deliverPrevious();
          return 1;
        }

        const auto deliveryStart = std::chrono::steady_clock::now();
        vtkNew<vtkPolyData> result;
        const bool pinned =
          this->PageLockedOutput && simulation.stepper().backend() == pbf::Backend::CUDA;
        if (simulation.stepper().precision() == pbf::Precision::Double)
        {
          FillParticles<double>(simulation.stepper(), pinned, internals.Vertices, result);
        }
        else
        {
          FillParticles<float>(simulation.stepper(), pinned, internals.Vertices, result);
        }
        vtkSmartPointer<vtkFieldData> fieldData =
          FrameFieldData(simulation, frame, this->FrameInterval, substeps);
        AddInteger(fieldData, "RequestSteps", internals.RequestSteps);
        AddText(fieldData, "ResumedFrom", resumedFrom);
        if (configuration.Ranks > 1)
        {
          // Collective, like every step: all ranks deliver the same frame.
          AddInteger(fieldData, "Rank", piece);
          AddInteger(fieldData, "Ranks", configuration.Ranks);
          vtkNew<vtkIdTypeArray> perRank;
          perRank->SetName("ParticlesPerRank");
          for (const std::vector<double>& r :
            pbf::distributed::allGather(*internals.Ranks, { double(simulation.stepper().size()) }))
          {
            perRank->InsertNextValue(static_cast<vtkIdType>(r[0]));
          }
          fieldData->AddArray(perRank);
        }
        if (!internals.DeviceFaultText.empty())
        {
          AddText(fieldData, "DeviceFault", internals.DeviceFaultText);
        }
        AddInteger(fieldData, "ResumedFromStep", static_cast<vtkIdType>(resumedFromStep));
        vtkNew<vtkIdTypeArray> held;
        held->SetName("CheckpointFrames");
        held->SetNumberOfTuples(static_cast<vtkIdType>(internals.Checkpoints.size()));
        vtkIdType k = 0;
        for (const auto& entry : internals.Checkpoints)
        {
          held->SetValue(k++, entry.first);
        }
        fieldData->AddArray(held);
        AddValue(fieldData, "CheckpointMemoryMB", internals.CheckpointBytes / 1048576.0);
        result->SetFieldData(fieldData);
        result->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frameTime);
        internals.LastOutput = result;
        internals.LastFrame = frame;
        output->ShallowCopy(result);
        output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frameTime);
        table->ShallowCopy(internals.DiagnosticsTable());
        table->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frameTime);
        internals.DeliveryMilliseconds = Milliseconds(deliveryStart);
        return 1;
      }
      catch (const pbf::DeviceFault& fault)
      {
        handleDeviceFault(fault);
      }
    }
  }
  catch (const pbf::InvalidInput& error)
  {
    std::string text = InUserTerms(error.what());
    if (text.find("domain") != std::string::npos)
    {
      // The user set no domain: say where it comes from and what changes it.
      const bool file = this->SceneFile && *this->SceneFile;
      text += file ? std::string(". The domain is the one of Scene File \"") + this->SceneFile + "\""
                   : std::string(". The domain is the tank of Preset \"") + this->GetPresetName() +
          "\"; a Scene File with its own \"domain\" changes it";
    }
    vtkErrorMacro(<< text);
  }
  catch (const std::bad_alloc&)
  {
    vtkErrorMacro(<< "out of memory: try a larger ParticleSpacing or a smaller scene");
  }
  catch (const std::exception& error)
  {
    vtkErrorMacro(<< InUserTerms(error.what()));
  }
  // A failed request may have stopped a simulation half way through a step: never step on from
  // it. Checkpoints and rows are of whole frames and stay.
  internals.Live.reset();
  internals.ResetPending();
  internals.LastFrame = -1;
  deliverPrevious();
  return 0;
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Preset: " << this->Preset << " (" << this->GetPresetName() << ")\n";
  os << indent << "SceneFile: " << (this->SceneFile ? this->SceneFile : "(none)") << "\n";
  os << indent << "RestDensity: " << this->RestDensity << "\n";
  os << indent << "ParticleSpacing: " << this->ParticleSpacing << "\n";
  os << indent << "SmoothingRatio: " << this->SmoothingRatio << "\n";
  os << indent << "SolverIterations: " << this->SolverIterations << "\n";
  os << indent << "AdaptiveIterations: " << (this->AdaptiveIterations ? "On" : "Off") << "\n";
  os << indent << "DensityErrorTolerance: " << this->DensityErrorTolerance << "\n";
  os << indent << "MaxDensityErrorTolerance: " << this->MaxDensityErrorTolerance << "\n";
  os << indent << "RelaxationEpsilon: " << this->RelaxationEpsilon << "\n";
  os << indent << "SCorrK: " << this->SCorrK << "\n";
  os << indent << "SCorrN: " << this->SCorrN << "\n";
  os << indent << "SCorrDeltaQ: " << this->SCorrDeltaQ << "\n";
  os << indent << "XSPHViscosity: " << this->XSPHViscosity << "\n";
  os << indent << "VorticityEpsilon: " << this->VorticityEpsilon << "\n";
  os << indent << "Unilateral: " << (this->Unilateral ? "On" : "Off") << "\n";
  os << indent << "MirrorWalls: " << (this->MirrorWalls ? "On" : "Off") << "\n";
  os << indent << "Gravity: (" << this->Gravity[0] << ", " << this->Gravity[1] << ", "
     << this->Gravity[2] << ")\n";
  os << indent << "FrameInterval: " << this->FrameInterval << "\n";
  os << indent << "SubstepsPerFrame: " << this->SubstepsPerFrame << "\n";
  os << indent << "TimeStepping: "
     << (this->TimeStepping == TIME_STEPPING_AUTOMATIC ? "Automatic" : "Fixed") << "\n";
  os << indent << "CFLNumber: " << this->CFLNumber << "\n";
  os << indent << "MaxTimeStep: " << this->MaxTimeStep << "\n";
  os << indent << "NumberOfFrames: " << this->NumberOfFrames << "\n";
  os << indent << "CheckpointInterval: " << this->CheckpointInterval << "\n";
  os << indent << "CheckpointMemoryMB: " << this->CheckpointMemoryMB << "\n";
  os << indent << "PageLockedOutput: " << (this->PageLockedOutput ? "On" : "Off") << "\n";
  os << indent << "Backend: " << this->Backend << "\n";
  os << indent << "DecomposeAcrossRanks: " << (this->DecomposeAcrossRanks ? "On" : "Off") << "\n";
  os << indent << "Precision: " << this->Precision << "\n";
}
