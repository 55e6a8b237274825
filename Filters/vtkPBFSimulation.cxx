#include "vtkPBFSimulation.h"
#include "vtkPBFSimulationInternals.h"
#include "vtkPBFTranslate.h"

#include "vtkDataSet.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"
#include "vtkPointSet.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkTable.h"

#include "vtkPBFOutput.h"
#include "vtkPBFPortDemand.h"
#include "vtkPBFProbes.h"

#include "ParameterTable.h"
#include "Parameters.h"
#include "Playback.h"
#include "SurfaceExtraction.h"

#include <algorithm>
#include <cmath>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{

// Indexed by vtkPBFSimulation::PresetScenes; the names are pbf::presetScene's.
const char* const PresetNames[] = { "dam_break", "double_dam_break", "blob", "stream",
  "marin_dam_break", "channel" };

} // namespace

vtkStandardNewMacro(vtkPBFSimulation);

namespace
{
// The Surface output's port (the XML's OutputPort "Surface").
constexpr int SurfacePort = 3;
} // namespace

//------------------------------------------------------------------------------
vtkPBFSimulation::vtkPBFSimulation()
  : Internals(new vtkPBFSimulationInternals)
{
  // The physics parameters live in the internals (vtkPBFSimulationInternals::Physics) with the solver's
  // defaults, so the two cannot drift.
  const pbf::Parameters defaults;
  this->Preset = PRESET_DAM_BREAK;
  this->SceneFile = nullptr;
  const pbf::SurfaceOptions surface;
  this->SurfaceResolution = surface.resolution;
  this->SurfaceIsoValue = surface.isoValue;
  this->SurfaceSmoothing = surface.smoothing;
  this->SurfaceAnisotropic = surface.anisotropic;
  this->GenerateSurface = false;
  this->ObstacleThickness = 0.0;
  // The solver's default is adaptive (its tolerance, with SolverIterations as the cap).
  this->AdaptiveIterations = defaults.densityErrorTolerance > 0;
  this->FrameInterval = 1.0 / 60.0;
  this->SubstepsPerFrame = 4;
  this->TimeStepping =
    defaults.timeStepping == pbf::TimeStepping::Automatic ? TIME_STEPPING_AUTOMATIC : TIME_STEPPING_FIXED;
  this->NumberOfFrames = 120;
  this->CheckpointInterval = 10;
  this->CheckpointMemoryMB = 1024.0;
  this->PageLockedOutput = true;
  this->Backend = BACKEND_AUTO;
  this->DecomposeAcrossRanks = true;
  this->Precision = PRECISION_SINGLE;

  // Port 0 is optional: without an input the algorithm is a source. Port 1: the obstacles;
  // port 2: the probes.
  this->SetNumberOfInputPorts(3);
  // Port 0: the particles of the frame; port 1: the diagnostics table; port 2: the outline of
  // the domain (the tank) with the solids where they stand, so that a view shows and frames the
  // whole of it from frame 0 on; port 3: the fluid's surface, when asked for; port 4: the
  // probes' table.
  this->SetNumberOfOutputPorts(5);
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
  return this->Internals->Costs.simulationMilliseconds;
}

//------------------------------------------------------------------------------
double vtkPBFSimulation::GetLastDiagnosticsMilliseconds() const
{
  return this->Internals->Costs.diagnosticsMilliseconds;
}

//------------------------------------------------------------------------------
double vtkPBFSimulation::GetLastCheckpointMilliseconds() const
{
  return this->Internals->Costs.checkpointMilliseconds;
}

//------------------------------------------------------------------------------
double vtkPBFSimulation::GetLastDeliveryMilliseconds() const
{
  return this->Internals->DeliveryMilliseconds;
}

//------------------------------------------------------------------------------
vtkIdType vtkPBFSimulation::GetLastRequestSteps() const
{
  return static_cast<vtkIdType>(this->Internals->Costs.steps);
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::FillInputPortInformation(int port, vtkInformation* info)
{
  if (port == 1)
  {
    // Any dataset whose surface bounds a solid, as many as the user connects.
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataSet");
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
    info->Set(vtkAlgorithm::INPUT_IS_REPEATABLE(), 1);
    return 1;
  }
  if (port == 2)
  {
    // The probes: the points of any dataset.
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataSet");
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
    return 1;
  }
  if (port != 0)
  {
    return 0;
  }
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPointSet");
  info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::RemoveAllObstacles()
{
  this->SetInputConnection(1, nullptr);
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::FillOutputPortInformation(int port, vtkInformation* info)
{
  if (port == 1 || port == 4)
  {
    info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkTable");
    return 1;
  }
  return this->Superclass::FillOutputPortInformation(port, info);
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::FrameForTime(double time) const
{
  return this->Settings().FrameForTime(time);
}

//------------------------------------------------------------------------------
vtkPBFSettings vtkPBFSimulation::Settings() const
{
  // GetNumberOfOutputPorts is not const in VTK; nothing here changes the algorithm.
  auto* self = const_cast<vtkPBFSimulation*>(this);
  vtkPBFSettings s;
  s.Owner = self;
  s.SceneFile = this->SceneFile ? this->SceneFile : "";
  s.PresetName = this->GetPresetName();
  s.OutputPorts = self->GetNumberOfOutputPorts();
  s.FrameInterval = this->FrameInterval;
  s.NumberOfFrames = this->NumberOfFrames;
  s.SubstepsPerFrame = this->SubstepsPerFrame;
  s.Automatic = this->TimeStepping == TIME_STEPPING_AUTOMATIC;
  s.AdaptiveIterations = this->AdaptiveIterations;
  s.Precision =
    this->Precision == PRECISION_DOUBLE ? pbf::Precision::Double : pbf::Precision::Single;
  // The property's values are the solver's (vtkSetClampMacro keeps it in their range).
  static_assert(static_cast<int>(pbf::BackendRequest::Auto) == BACKEND_AUTO &&
      static_cast<int>(pbf::BackendRequest::CUDA) == BACKEND_CUDA &&
      static_cast<int>(pbf::BackendRequest::OpenMP) == BACKEND_OPENMP &&
      static_cast<int>(pbf::BackendRequest::Serial) == BACKEND_SERIAL,
    "vtkPBFSimulation::Backends and pbf::BackendRequest name the same values");
  s.Backend = static_cast<pbf::BackendRequest>(this->Backend);
  s.ObstacleThickness = this->ObstacleThickness;
  s.DecomposeAcrossRanks = this->DecomposeAcrossRanks;
  s.CheckpointInterval = this->CheckpointInterval;
  s.CheckpointMemoryMB = this->CheckpointMemoryMB;
  s.PageLockedOutput = this->PageLockedOutput;
  s.InvalidTime = this->InvalidTimeProperty();
  return s;
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
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // The obstacles and probes whole, in one piece, on every rank alike so that a collective
  // upstream filter sees the same request everywhere. The fluid's points likewise, except in a
  // decomposed run: there each rank asks for its own piece of them, as ParaView's parallel
  // engine asks every filter, and no rank holds the whole input (RequestData sends each piece's
  // particles to the ranks that own them). Without decomposition only piece 0 simulates.
  // The fluid's points are the initial state, read at their first time, so playing the animation
  // does not re-execute them; the obstacles are read at the frame's time, so that one that moves
  // with time (a reader's time steps) is seen where it is (vtkPBFObstacleMotion.h); the probes
  // likewise.
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  const bool timed = outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
  const double frameTime =
    timed ? outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()) : 0.0;
  const FrameRequest r = this->Internals->ParseRequest(this->Settings(), request, outputVector);
  for (int port = 0; port < 3; ++port)
  {
    for (int c = 0; c < this->GetNumberOfInputConnections(port); ++c)
    {
      vtkInformation* inInfo = inputVector[port]->GetInformationObject(c);
      const bool piece = port == 0 && r.Decomposed;
      inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), piece ? r.Piece : 0);
      inInfo->Set(
        vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(), piece ? r.Pieces : 1);
      inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_GHOST_LEVELS(), 0);
      if (inInfo->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) &&
        inInfo->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) > 0)
      {
        inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(),
          port > 0 && timed ? frameTime
                             : inInfo->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS())[0]);
      }
      else
      {
        inInfo->Remove(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
      }
    }
  }
  return 1;
}

//------------------------------------------------------------------------------
vtkTypeBool vtkPBFSimulation::ProcessRequest(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  if (request->Has(vtkDemandDrivenPipeline::REQUEST_DATA_NOT_GENERATED()))
  {
    vtkPBFSimulationInternals& internals = *this->Internals;
    const FrameRequest r = internals.ParseRequest(this->Settings(), request, outputVector);
    internals.Demand = vtkPBFPortDemand::Of(this, request, outputVector, SurfacePort,
      this->GenerateSurface, internals.LastFrame == r.Frame, r.Time);
    internals.Demand.MarkNotGenerated(outputVector, SurfacePort);
    internals.SurfaceStale =
      !internals.Demand.Surface && (internals.SurfaceStale || internals.Demand.LeftStale);
    return 1;
  }
  return this->Superclass::ProcessRequest(request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::ComputePipelineMTime(vtkInformation* request,
  vtkInformationVector** inInfoVec, vtkInformationVector* outInfoVec, int requestFromOutputPort,
  vtkMTimeType* mtime)
{
  const int result = this->Superclass::ComputePipelineMTime(
    request, inInfoVec, outInfoVec, requestFromOutputPort, mtime);
  if (requestFromOutputPort == SurfacePort && this->Internals->SurfaceStale)
  {
    this->Internals->SurfaceStamp.Modified();
    *mtime = std::max(*mtime, this->Internals->SurfaceStamp.GetMTime());
  }
  return result;
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  const vtkPBFPortDemand demand = this->Internals->Demand;
  this->Internals->Demand = vtkPBFPortDemand();
  int result = 1;
  if (demand.Frame)
  {
    result = this->RequestFrame(request, inputVector, outputVector);
    this->RequestDomain(outputVector);
    this->RequestProbes(inputVector, outputVector);
  }
  if (demand.Frame && !demand.Surface && !result)
  {
    // A failed frame keeps the previous outputs, the surface's too; it counts as made for the
    // time asked, so that the surface's own request does not run the failing frame again.
    vtkInformation* info = outputVector->GetInformationObject(SurfacePort);
    info->Remove(vtkDemandDrivenPipeline::DATA_NOT_GENERATED());
    vtkInformation* shown = vtkPolyData::GetData(outputVector, 0)->GetInformation();
    if (shown->Has(vtkDataObject::DATA_TIME_STEP()))
    {
      vtkPolyData::GetData(outputVector, SurfacePort)->GetInformation()->Set(
        vtkDataObject::DATA_TIME_STEP(), shown->Get(vtkDataObject::DATA_TIME_STEP()));
    }
  }
  const int surface = demand.Surface ? this->RequestSurface(outputVector) : 1;
  return result && surface;
}

//------------------------------------------------------------------------------
int vtkPBFSimulation::RequestFrame(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkPolyData* output = vtkPolyData::GetData(outputVector, 0);
  vtkTable* table = vtkTable::GetData(outputVector, 1);
  vtkPBFSimulationInternals& internals = *this->Internals;
  internals.Costs = pbf::FrameReached();
  internals.DeliveryMilliseconds = 0;
  const vtkPBFSettings settings = this->Settings();
  const FrameRequest r = internals.ParseRequest(settings, request, outputVector);
  // Piece 0 holds the whole fluid outside a decomposed run (see the class documentation); after
  // an upstream abort the executive empties the outputs and marks them aborted.
  if ((r.Piece > 0 && !r.Decomposed) || this->GetAbortOutput())
  {
    output->Initialize();
    output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), r.Time);
    table->Initialize();
    table->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), r.Time);
    return 1;
  }
  vtkPointSet* input = this->GetNumberOfInputConnections(0) > 0
    ? vtkPointSet::GetData(inputVector[0]->GetInformationObject(0))
    : nullptr;
  std::vector<vtkDataSet*> obstacles;
  for (int c = 0; c < this->GetNumberOfInputConnections(1); ++c)
  {
    obstacles.push_back(vtkDataSet::GetData(inputVector[1]->GetInformationObject(c)));
  }
  pbf::Playback& playback = internals.Playback;
  try
  {
    internals.Adopt(settings, internals.MakeKey(settings, input, obstacles, r));
    internals.UpdateObstacleMotion(obstacles.size());
    if (internals.LastFrame == r.Frame)
    {
      internals.DeliverAgain(r, output, table);
      return 1;
    }
    // A device fault with Backend Auto moves the run to the CPU and tries again from the
    // checkpoints; with Backend CUDA it stops with an error (OnDeviceFault).
    for (;;)
    {
      try
      {
        const pbf::FrameReached reached = playback.reach(
          r.Frame, [&]() { return internals.Build(settings, playback.key(), input, obstacles); },
          [this](double fraction) {
            this->UpdateProgress(fraction);
            // AbortExecute stays set, as VTK has it: whoever set it clears it.
            return this->GetAbortExecute() != 0;
          });
        internals.Costs = reached;
        if (reached.aborted)
        {
          internals.ReportAbort(settings, r);
          internals.DeliverPrevious(output, table);
          return 1;
        }
        internals.Deliver(settings, r, reached, output, table);
        return 1;
      }
      catch (const pbf::DeviceFault& fault)
      {
        internals.OnDeviceFault(settings, fault, r.Frame);
      }
    }
  }
  catch (const std::bad_alloc&)
  {
    vtkErrorMacro(<< "out of memory: try a larger Particle Spacing or a smaller scene");
  }
  catch (const std::exception& error)
  {
    vtkErrorMacro(<< internals.InUserTerms(settings, error));
  }
  // A failed request may have stopped a simulation half way through a step: never step on from
  // it. Checkpoints and rows are of whole frames and stay.
  playback.dropLive();
  internals.LastFrame = -1;
  internals.DeliverPrevious(output, table);
  return 0;
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::RequestDomain(vtkInformationVector* outputVector)
{
  vtkPBFSimulationInternals& internals = *this->Internals;
  vtkPolyData* domain = vtkPolyData::GetData(outputVector, 2);
  vtkPolyData* particles = vtkPolyData::GetData(outputVector, 0);
  const pbf::Simulation* live = internals.Playback.live();
  // Built once a run without solids; with solids, at every frame, where they stand at the frame
  // and with the pressure the frame's particles put on them.
  const bool solids = live && !live->scene().solids.empty();
  if (live &&
    (solids || !(internals.DomainBuilt && internals.DomainKey == internals.Playback.key())))
  {
    internals.Domain = vtkPBFOutput::DomainOutline(live->parameters().domain, live->scene(),
      live->solidPoses(live->time()), live->parameters().particleSpacing);
    internals.DomainKey = internals.Playback.key();
    internals.DomainBuilt = true;
    if (solids)
    {
      vtkPBFAddSurfacePressure(internals.Domain, particles, live->parameters(),
        live->surfaceSolids(live->time()), internals.DecomposedRanks());
    }
  }
  // One outline for the whole run: rank 0's (the others would only draw it again).
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  if (!controller || controller->GetLocalProcessId() == 0)
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
int vtkPBFSimulation::RequestSurface(vtkInformationVector* outputVector)
{
  vtkPolyData* surface = vtkPolyData::GetData(outputVector, 3);
  vtkPolyData* particles = vtkPolyData::GetData(outputVector, 0);
  vtkInformation* shown = particles->GetInformation();
  if (!shown->Has(vtkDataObject::DATA_TIME_STEP()))
  {
    surface->Initialize();
    if (shown->Has(vtkDataObject::DATA_TIME_STEP()))
    {
      surface->GetInformation()->Set(
        vtkDataObject::DATA_TIME_STEP(), shown->Get(vtkDataObject::DATA_TIME_STEP()));
    }
    return 1;
  }
  pbf::SurfaceOptions options;
  options.resolution = this->SurfaceResolution;
  options.isoValue = this->SurfaceIsoValue;
  options.smoothing = this->SurfaceSmoothing;
  options.anisotropic = this->SurfaceAnisotropic;
  try
  {
    this->Internals->DeliverSurface(options, particles, surface);
  }
  catch (const std::exception& error)
  {
    vtkErrorMacro(<< error.what());
    surface->ShallowCopy(this->Internals->LastSurface);
    return 0;
  }
  surface->GetInformation()->Set(
    vtkDataObject::DATA_TIME_STEP(), shown->Get(vtkDataObject::DATA_TIME_STEP()));
  return 1;
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::RequestProbes(
  vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTable* table = vtkTable::GetData(outputVector, 4);
  vtkPolyData* particles = vtkPolyData::GetData(outputVector, 0);
  vtkPBFSimulationInternals& internals = *this->Internals;
  const pbf::Simulation* live = internals.Playback.live();
  vtkDataSet* probes = this->GetNumberOfInputConnections(2) > 0
    ? vtkDataSet::GetData(inputVector[2]->GetInformationObject(0))
    : nullptr;
  // One table for the whole run: rank 0's (a decomposed run's ranks all sum their particles).
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  const bool first = !controller || controller->GetLocalProcessId() == 0;
  table->Initialize();
  if (probes && live)
  {
    std::vector<vtkIdType> outside;
    vtkSmartPointer<vtkTable> rows = vtkPBFProbeTable(
      probes, particles, live->parameters(), internals.DecomposedRanks(), outside);
    if (first)
    {
      table->ShallowCopy(rows);
    }
    const std::string said = vtkPBFDescribeProbes(probes, outside);
    if (first && !outside.empty() && said != internals.ProbesOutsideSaid)
    {
      vtkWarningMacro(<< "Probes: " << said
                      << " outside the domain: their rows read NaN (the run goes on)");
    }
    internals.ProbesOutsideSaid = said;
  }
  vtkInformation* shown = particles->GetInformation();
  if (shown->Has(vtkDataObject::DATA_TIME_STEP()))
  {
    table->GetInformation()->Set(
      vtkDataObject::DATA_TIME_STEP(), shown->Get(vtkDataObject::DATA_TIME_STEP()));
  }
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::SetParameter(const char* name, double value)
{
  this->SetParameterComponents(name, 1, &value);
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::SetParameter(const char* name, int value)
{
  const double real = value;
  this->SetParameterComponents(name, 1, &real);
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::SetParameter(const char* name, double x, double y, double z)
{
  const double values[3] = { x, y, z };
  this->SetParameterComponents(name, 3, values);
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::SetParameterComponents(const char* name, int count, const double* values)
{
  const pbf::ParameterSpec* spec = pbf::findParameter(name ? name : "");
  if (!spec || spec->components() != count)
  {
    vtkErrorMacro(<< "SetParameter(\"" << (name ? name : "(null)") << "\", " << count
                  << (count == 1 ? " value" : " values") << "): "
                  << (spec ? "it has " + std::to_string(spec->components()) + " components"
                           : std::string("no such parameter (Solver/Physics/ParameterTable.h)")));
    return;
  }
  bool changed = false;
  for (int c = 0; c < count; ++c)
  {
    // Bit for bit, as the cache key compares them.
    if (!(spec->get(this->Internals->Physics, c) == values[c]))
    {
      spec->set(this->Internals->Physics, c, values[c]);
      changed = true;
    }
  }
  if (changed)
  {
    this->Modified();
  }
}

//------------------------------------------------------------------------------
double vtkPBFSimulation::GetParameter(const char* name, int component)
{
  const pbf::ParameterSpec* spec = pbf::findParameter(name ? name : "");
  if (!spec || component < 0 || component >= spec->components())
  {
    vtkErrorMacro(<< "GetParameter(\"" << (name ? name : "(null)") << "\", " << component
                  << "): no such parameter or component");
    return 0.0;
  }
  return spec->get(this->Internals->Physics, component);
}

//------------------------------------------------------------------------------
std::string vtkPBFSimulation::InvalidTimeProperty() const
{
  return vtkPBFInvalidTimeProperty(this->FrameInterval, this->NumberOfFrames,
    this->TimeStepping == TIME_STEPPING_AUTOMATIC, this->SubstepsPerFrame,
    this->Internals->Physics.timeStep);
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Preset: " << this->Preset << " (" << this->GetPresetName() << ")\n";
  os << indent << "SceneFile: " << (this->SceneFile ? this->SceneFile : "(none)") << "\n";
  os << indent << "AdaptiveIterations: " << (this->AdaptiveIterations ? "On" : "Off") << "\n";
  for (const pbf::ParameterSpec& spec : pbf::parameterTable())
  {
    os << indent << spec.property << ":";
    for (int c = 0; c < spec.components(); ++c)
    {
      os << " " << spec.get(this->Internals->Physics, c);
    }
    os << "\n";
  }
  os << indent << "GenerateSurface: " << this->GenerateSurface << "\n";
  os << indent << "SurfaceResolution: " << this->SurfaceResolution << "\n";
  os << indent << "SurfaceIsoValue: " << this->SurfaceIsoValue << "\n";
  os << indent << "SurfaceSmoothing: " << this->SurfaceSmoothing << "\n";
  os << indent << "SurfaceAnisotropic: " << this->SurfaceAnisotropic << "\n";
  os << indent << "ObstacleThickness: " << this->ObstacleThickness << "\n";
  os << indent << "FrameInterval: " << this->FrameInterval << "\n";
  os << indent << "SubstepsPerFrame: " << this->SubstepsPerFrame << "\n";
  os << indent << "TimeStepping: "
     << (this->TimeStepping == TIME_STEPPING_AUTOMATIC ? "Automatic" : "Fixed") << "\n";
  os << indent << "NumberOfFrames: " << this->NumberOfFrames << "\n";
  os << indent << "CheckpointInterval: " << this->CheckpointInterval << "\n";
  os << indent << "CheckpointMemoryMB: " << this->CheckpointMemoryMB << "\n";
  os << indent << "PageLockedOutput: " << (this->PageLockedOutput ? "On" : "Off") << "\n";
  os << indent << "Backend: " << this->Backend << "\n";
  os << indent << "DecomposeAcrossRanks: " << (this->DecomposeAcrossRanks ? "On" : "Off") << "\n";
  os << indent << "Precision: " << this->Precision << "\n";
}
