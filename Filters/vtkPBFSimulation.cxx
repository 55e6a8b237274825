#include "vtkPBFSimulation.h"

#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOutputWindow.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"

#include "Parameters.h"
#include "Scene.h"
#include "Simulation.h"
#include "Stepper.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <memory>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace
{

// Indexed by vtkPBFSimulation::PresetScenes; the names are pbf::presetScene's.
const char* const PresetNames[] = { "dam_break", "double_dam_break", "blob", "stream" };

// Everything that shapes the motion from the initial state. Frames of two equal configurations
// are bit-identical, so a live simulation of an equal configuration may be stepped on instead of
// rebuilt. NumberOfFrames is deliberately absent: more frames do not change earlier ones.
struct Configuration
{
  std::string SceneKey; // the preset's name, or the file's name and contents
  pbf::Parameters Parameters;
  pbf::Backend Backend = pbf::Backend::OpenMP;
  pbf::Precision Precision = pbf::Precision::Single;
  bool HasInput = false;
  vtkMTimeType InputMTime = 0;
};

bool SameBox(const pbf::Box& a, const pbf::Box& b)
{
  return a.min.x == b.min.x && a.min.y == b.min.y && a.min.z == b.min.z && a.max.x == b.max.x &&
    a.max.y == b.max.y && a.max.z == b.max.z;
}

// Field by field: a NaN never compares equal, which only costs a rebuild that then reports it.
// A field added to pbf::Parameters must be added here, or changing it would not restart the
// simulation (Testing/Python/pbf_parameters.py fails for a field without a property).
bool SameParameters(const pbf::Parameters& a, const pbf::Parameters& b)
{
  return a.restDensity == b.restDensity && a.particleSpacing == b.particleSpacing &&
    a.smoothingRatio == b.smoothingRatio && a.solverIterations == b.solverIterations &&
    a.relaxation == b.relaxation && a.sCorrK == b.sCorrK && a.sCorrN == b.sCorrN &&
    a.sCorrDeltaQ == b.sCorrDeltaQ && a.xsphC == b.xsphC &&
    a.vorticityEpsilon == b.vorticityEpsilon && a.unilateral == b.unilateral &&
    a.mirrorWalls == b.mirrorWalls && a.gravity.x == b.gravity.x && a.gravity.y == b.gravity.y &&
    a.gravity.z == b.gravity.z && a.timeStep == b.timeStep && SameBox(a.domain, b.domain);
}

bool operator==(const Configuration& a, const Configuration& b)
{
  return a.SceneKey == b.SceneKey && SameParameters(a.Parameters, b.Parameters) &&
    a.Backend == b.Backend && a.Precision == b.Precision && a.HasInput == b.HasInput &&
    a.InputMTime == b.InputMTime;
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
  if (n == 0)
  {
    throw pbf::InvalidInput("input number of points = 0: the filter needs at least one point to "
                            "become the fluid");
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

// Particles in the solver's (cell-sorted) order, one vertex cell each.
template <class Real>
void FillParticles(const pbf::Stepper& stepper, vtkPolyData* output)
{
  pbf::Snapshot<Real> snapshot;
  stepper.read(snapshot);
  const auto n = static_cast<vtkIdType>(snapshot.position.size());

  vtkNew<RealArray<Real>> coordinates;
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(n);
  vtkNew<RealArray<Real>> velocity;
  velocity->SetName("velocity");
  velocity->SetNumberOfComponents(3);
  velocity->SetNumberOfTuples(n);
  vtkNew<RealArray<Real>> density;
  density->SetName("density");
  density->SetNumberOfTuples(n);
  vtkNew<RealArray<Real>> lambda;
  lambda->SetName("lambda");
  lambda->SetNumberOfTuples(n);
  vtkNew<vtkIdTypeArray> id;
  id->SetName("id");
  id->SetNumberOfTuples(n);
  vtkNew<vtkIdTypeArray> offsets;
  offsets->SetNumberOfTuples(n + 1);
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->SetNumberOfTuples(n);

  for (vtkIdType i = 0; i < n; ++i)
  {
    const auto k = static_cast<std::size_t>(i);
    const auto& x = snapshot.position[k];
    const auto& v = snapshot.velocity[k];
    const Real xyz[3] = { x.x, x.y, x.z };
    const Real uvw[3] = { v.x, v.y, v.z };
    coordinates->SetTypedTuple(i, xyz);
    velocity->SetTypedTuple(i, uvw);
    density->SetValue(i, snapshot.density[k]);
    lambda->SetValue(i, snapshot.lambda[k]);
    id->SetValue(i, static_cast<vtkIdType>(snapshot.id[k]));
    offsets->SetValue(i, i);
    connectivity->SetValue(i, i);
  }
  offsets->SetValue(n, n);

  vtkNew<vtkPoints> points;
  points->SetData(coordinates);
  vtkNew<vtkCellArray> vertices;
  vertices->SetData(offsets, connectivity);
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
void FillParameters(const pbf::Simulation& simulation, int frame, double frameInterval,
  int substeps, vtkPolyData* output)
{
  const pbf::Parameters& p = simulation.parameters();
  vtkNew<vtkFieldData> fieldData;
  AddValue(fieldData, "SmoothingLength", p.smoothingLength());
  AddValue(fieldData, "RestDensity", p.restDensity);
  AddValue(fieldData, "ParticleMass", pbf::calibratedParticleMass(p));
  AddValue(fieldData, "ParticleSpacing", p.particleSpacing);
  AddValue(fieldData, "SmoothingRatio", p.smoothingRatio);
  AddInteger(fieldData, "SolverIterations", p.solverIterations);
  AddValue(fieldData, "RelaxationEpsilon", p.relaxation);
  AddValue(fieldData, "SCorrK", p.sCorrK);
  AddValue(fieldData, "SCorrN", p.sCorrN);
  AddValue(fieldData, "SCorrDeltaQ", p.sCorrDeltaQ);
  AddValue(fieldData, "XSPHViscosity", p.xsphC);
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
  AddValue(fieldData, "TimeStep", p.timeStep);
  AddValue(fieldData, "FrameInterval", frameInterval);
  AddInteger(fieldData, "SubstepsPerFrame", substeps);
  AddInteger(fieldData, "Frame", frame);
  AddInteger(fieldData, "StepCount", static_cast<vtkIdType>(simulation.stepCount()));
  AddValue(fieldData, "Time", simulation.time());
  AddText(fieldData, "Backend", simulation.stepper().description());
  AddText(fieldData, "Precision", pbf::toString(simulation.stepper().precision()));
  AddText(fieldData, "Scene", simulation.scene().name);
  output->SetFieldData(fieldData);
}

std::string ReadWholeFile(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

} // namespace

class vtkPBFSimulation::vtkInternals
{
public:
  // The simulation of LiveConfiguration at its current step; null when none is valid.
  std::unique_ptr<pbf::Simulation> Live;
  Configuration LiveConfiguration;

  // What the last successful request produced: a failed request hands it out again.
  vtkSmartPointer<vtkPolyData> LastOutput = vtkSmartPointer<vtkPolyData>::New();

  // CUDA is probed once: a device does not come and go while ParaView runs.
  bool CudaProbed = false;
  bool CudaPresent = false;
  std::string CudaAbsence;
  bool FallbackReported = false;

  bool HasCuda()
  {
    if (!this->CudaProbed)
    {
      this->CudaPresent = pbf::cudaAvailable(&this->CudaAbsence);
      this->CudaProbed = true;
    }
    return this->CudaPresent;
  }

  // True when the live simulation is of this configuration and not past targetStep: stepping on
  // from it gives what a run from the initial state would, bit for bit.
  bool CanStepTo(const Configuration& configuration, std::uint64_t targetStep) const
  {
    return this->Live && this->LiveConfiguration == configuration &&
      this->Live->stepCount() <= targetStep;
  }

  // Positions the live simulation at targetStep of the configuration: steps on when it can,
  // otherwise starts over from the initial state (scene, or initial when the input gives it). A
  // checkpoint cache slots in here: restore the latest checkpoint of this configuration at or
  // before targetStep instead of step 0; stepping is deterministic, so frames stay bit-identical.
  pbf::Simulation& Seek(const Configuration& configuration, const pbf::Scene& scene,
    const pbf::ParticleBatch* initial, std::uint64_t targetStep, vtkPBFSimulation* self)
  {
    if (!this->CanStepTo(configuration, targetStep))
    {
      // Free the old state first: two large simulations need not fit at once.
      this->Live.reset();
      const Configuration& c = configuration;
      if (initial)
      {
        this->Live =
          std::make_unique<pbf::Simulation>(scene, c.Parameters, c.Backend, c.Precision, *initial);
      }
      else
      {
        this->Live = std::make_unique<pbf::Simulation>(scene, c.Parameters, c.Backend, c.Precision);
      }
      this->LiveConfiguration = configuration;
    }
    const std::uint64_t first = this->Live->stepCount();
    const double total = static_cast<double>(targetStep - first);
    while (this->Live->stepCount() < targetStep)
    {
      this->Live->advance(1);
      self->UpdateProgress(static_cast<double>(this->Live->stepCount() - first) / total);
    }
    return *this->Live;
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
  this->XSPHViscosity = defaults.xsphC;
  this->VorticityEpsilon = defaults.vorticityEpsilon;
  this->Unilateral = defaults.unilateral;
  this->MirrorWalls = defaults.mirrorWalls;
  this->Gravity[0] = defaults.gravity.x;
  this->Gravity[1] = defaults.gravity.y;
  this->Gravity[2] = defaults.gravity.z;
  this->FrameInterval = 1.0 / 60.0;
  this->SubstepsPerFrame = 4;
  this->NumberOfFrames = 120;
  this->Backend = BACKEND_AUTO;
  this->Precision = PRECISION_SINGLE;

  // Port 0 is optional: without an input the algorithm is a source.
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(1);
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
int vtkPBFSimulation::FrameForTime(double time) const
{
  if (!std::isfinite(time) || time <= 0.0)
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
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  // The time steps are this algorithm's frames, whatever the input's were.
  std::vector<double> times(static_cast<std::size_t>(this->NumberOfFrames) + 1);
  for (std::size_t k = 0; k < times.size(); ++k)
  {
    times[k] = static_cast<double>(k) * this->FrameInterval;
  }
  outInfo->Set(
    vtkStreamingDemandDrivenPipeline::TIME_STEPS(), times.data(), static_cast<int>(times.size()));
  const double range[2] = { times.front(), times.back() };
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  // One piece only until the fluid is partitioned: the executive then runs a source on piece 0.
  outInfo->Remove(vtkAlgorithm::CAN_HANDLE_PIECE_REQUEST());
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
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(outInfo);

  double requested = 0.0;
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
  {
    requested = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
  }
  const int frame = this->FrameForTime(requested);
  const double frameTime = static_cast<double>(frame) * this->FrameInterval;

  const int piece = outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER())
    ? outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER())
    : 0;
  if (piece > 0)
  {
    // Piece 0 holds the whole fluid; see the class documentation.
    output->Initialize();
    output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frameTime);
    return 1;
  }

  vtkPointSet* input = this->GetNumberOfInputConnections(0) > 0
    ? vtkPointSet::GetData(inputVector[0]->GetInformationObject(0))
    : nullptr;

  try
  {
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
    p.relaxation = this->RelaxationEpsilon;
    p.sCorrK = this->SCorrK;
    p.sCorrN = this->SCorrN;
    p.sCorrDeltaQ = this->SCorrDeltaQ;
    p.xsphC = this->XSPHViscosity;
    p.vorticityEpsilon = this->VorticityEpsilon;
    p.unilateral = this->Unilateral;
    p.mirrorWalls = this->MirrorWalls;
    p.gravity = pbf::Vec3d{ this->Gravity[0], this->Gravity[1], this->Gravity[2] };
    p.timeStep = this->FrameInterval / this->SubstepsPerFrame;

    configuration.Precision =
      this->Precision == PRECISION_DOUBLE ? pbf::Precision::Double : pbf::Precision::Single;
    switch (this->Backend)
    {
      case BACKEND_CUDA:
        if (!this->Internals->HasCuda())
        {
          throw std::runtime_error("Backend = CUDA: CUDA backend unavailable: " +
            this->Internals->CudaAbsence + " (choose Auto or CPU (OpenMP))");
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
        if (this->Internals->HasCuda())
        {
          configuration.Backend = pbf::Backend::CUDA;
        }
        else
        {
          configuration.Backend = pbf::Backend::OpenMP;
          if (!this->Internals->FallbackReported)
          {
            this->Internals->FallbackReported = true;
            std::ostringstream text;
            text << this->GetClassName() << " (" << this << "): Backend Auto: no CUDA ("
                 << this->Internals->CudaAbsence << "); falling back to CPU (OpenMP).\n";
            vtkOutputWindowDisplayText(text.str().c_str());
          }
        }
        break;
    }

    configuration.HasInput = input != nullptr;
    configuration.InputMTime = input ? input->GetMTime() : 0;

    const std::uint64_t targetStep =
      static_cast<std::uint64_t>(frame) * static_cast<std::uint64_t>(this->SubstepsPerFrame);

    // The scene and the input are read only when the simulation is rebuilt.
    pbf::Scene scene;
    pbf::ParticleBatch initial;
    if (!this->Internals->CanStepTo(configuration, targetStep))
    {
      scene =
        sceneFile.empty() ? pbf::presetScene(this->GetPresetName()) : pbf::loadSceneFile(sceneFile);
      if (input)
      {
        initial = BatchFromInput(input);
      }
    }

    pbf::Simulation& simulation =
      this->Internals->Seek(configuration, scene, input ? &initial : nullptr, targetStep, this);

    vtkNew<vtkPolyData> result;
    if (simulation.stepper().precision() == pbf::Precision::Double)
    {
      FillParticles<double>(simulation.stepper(), result);
    }
    else
    {
      FillParticles<float>(simulation.stepper(), result);
    }
    FillParameters(simulation, frame, this->FrameInterval, this->SubstepsPerFrame, result);
    output->ShallowCopy(result);
    output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frameTime);
    this->Internals->LastOutput->ShallowCopy(output);
    return 1;
  }
  catch (const pbf::InvalidInput& error)
  {
    vtkErrorMacro(<< error.what());
  }
  catch (const std::bad_alloc&)
  {
    vtkErrorMacro(<< "out of memory: try a larger ParticleSpacing or a smaller scene");
  }
  catch (const std::exception& error)
  {
    vtkErrorMacro(<< error.what());
  }
  // A failed request may have stopped a simulation half way: never step on from it.
  this->Internals->Live.reset();
  output->ShallowCopy(this->Internals->LastOutput);
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
  os << indent << "NumberOfFrames: " << this->NumberOfFrames << "\n";
  os << indent << "Backend: " << this->Backend << "\n";
  os << indent << "Precision: " << this->Precision << "\n";
}
