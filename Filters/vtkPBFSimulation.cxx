#include "vtkPBFSimulation.h"
#include "vtkPBFObstacles.h"
#include "vtkPBFOutput.h"
#include "vtkPBFRankCommunicator.h"
#include "vtkPBFTranslate.h"

#include "vtkDataSet.h"

#include "vtkFieldData.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOutputWindow.h"
#include "vtkPointSet.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkTable.h"

#include "BackendChoice.h"
#include "DeviceFault.h"
#include "Distributed/Communicator.h"
#include "Parameters.h"
#include "Playback.h"
#include "Scene.h"
#include "Simulation.h"
#include "Stepper.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{

// Indexed by vtkPBFSimulation::PresetScenes; the names are pbf::presetScene's.
const char* const PresetNames[] = { "dam_break", "double_dam_break", "blob", "stream",
  "marin_dam_break" };

// The size and modification time of each mesh file a scene file names: a mesh edited in place
// is another run, as an edited scene file is. A scene file that does not parse gives nothing here;
// building the run reports it.
std::string MeshFileVersions(const std::string& sceneFile)
{
  std::string versions;
  if (sceneFile.empty())
  {
    return versions;
  }
  try
  {
    for (const pbf::SolidRegion& solid : pbf::loadSceneFile(sceneFile).solids)
    {
      if (!solid.file.empty())
      {
        std::error_code error;
        const auto size = std::filesystem::file_size(solid.file, error);
        const auto time = std::filesystem::last_write_time(solid.file, error);
        versions += "\nmesh " + solid.file + " " + std::to_string(error ? 0 : size) + " " +
          std::to_string(error ? 0 : time.time_since_epoch().count());
      }
    }
  }
  catch (const std::exception&)
  {
  }
  return versions;
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

// Which piece of which frame a request asks for.
struct FrameRequest
{
  int Frame = 0;
  double Time = 0; // the frame's time, Frame * FrameInterval
  int Piece = 0;
  int Pieces = 1;
  bool Decomposed = false; // one piece per rank of the global controller: a decomposed run
};

} // namespace

// The algorithm's state between requests: the playback core (live simulation, checkpoints,
// diagnostics rows) and what the VTK side keeps of its results.
class vtkPBFSimulation::vtkInternals
{
public:
  pbf::Playback Playback;

  // What the last successful request produced (a failed or aborted request hands it out again)
  // and, when it is a frame of the playback's key, which one (-1 otherwise).
  vtkSmartPointer<vtkPolyData> LastOutput = vtkSmartPointer<vtkPolyData>::New();
  int LastFrame = -1;
  // The outline of the domain last simulated (port 2), kept when a request fails.
  vtkSmartPointer<vtkPolyData> Domain = vtkSmartPointer<vtkPolyData>::New();
  // The run Domain was built for: the tank and the scene's obstacles change only with it.
  pbf::PlaybackKey DomainKey;
  bool DomainBuilt = false;
  // Reused from frame to frame while the particle count stays.
  vtkSmartPointer<vtkCellArray> Vertices;
  // The diagnostics table of the rows of version TableVersion.
  vtkSmartPointer<vtkTable> Table;
  std::uint64_t TableVersion = 0;
  vtkSmartPointer<vtkTable> EmptyTable = vtkSmartPointer<vtkTable>::New();

  // The cost of the last request.
  pbf::FrameReached Costs;
  double DeliveryMilliseconds = 0;

  // The ranks of a decomposed run, over ParaView's global controller: its MPI communicator where
  // it has one (pvbatch under mpiexec, a pvserver), so that a rank whose GPU faults stops every
  // rank with its error (Distributed/RankFailure.h).
  std::unique_ptr<pbf::distributed::Communicator> Ranks;

  // CUDA is probed once: a device does not come and go while ParaView runs.
  bool CudaProbed = false;
  bool CudaPresent = false;
  std::string CudaAbsence;
  bool FallbackReported = false;
  // The run met a device fault and went on on the CPU: the warning, which the frames computed
  // since carry in their field data ("DeviceFault").
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

  FrameRequest ParseRequest(vtkPBFSimulation* self, vtkInformation* request,
    vtkInformationVector* outputVector) const;
  pbf::PlaybackKey MakeKey(vtkPBFSimulation* self, vtkPointSet* input,
    const std::vector<vtkDataSet*>& obstacles, const FrameRequest& r);
  // Makes `key` the playback's and applies the checkpoint settings.
  void Adopt(vtkPBFSimulation* self, const pbf::PlaybackKey& key, int frame);
  std::unique_ptr<pbf::Simulation> Build(vtkPBFSimulation* self, const pbf::PlaybackKey& key,
    vtkPointSet* input, const std::vector<vtkDataSet*>& obstacles);
  void OnDeviceFault(vtkPBFSimulation* self, const pbf::DeviceFault& fault, int frame);
  // The frame's particles and field data on port 0, the diagnostics on port 1.
  void Deliver(vtkPBFSimulation* self, const FrameRequest& r, const pbf::FrameReached& reached,
    vtkPolyData* output, vtkTable* table);
  void ReportAbort(vtkPBFSimulation* self, const FrameRequest& r);
  void DeliverAgain(const FrameRequest& r, vtkPolyData* output, vtkTable* table);
  void DeliverPrevious(vtkPolyData* output, vtkTable* table);
  vtkTable* DiagnosticsTable();
  std::string InUserTerms(vtkPBFSimulation* self, const std::exception& error) const;
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
  this->ObstacleThickness = 0.0;
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

  // Port 0 is optional: without an input the algorithm is a source. Port 1: the obstacles.
  this->SetNumberOfInputPorts(2);
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
  // Every input (the fluid's points, the obstacles) whole, in one piece, on every rank alike so
  // that a collective upstream filter sees the same request everywhere; only piece 0 simulates.
  // Each is read at its first time, not at the frame being computed: the fluid's points are the
  // initial state and the obstacles stand still, so playing the animation does not re-execute
  // them.
  for (int port = 0; port < 2; ++port)
  {
    for (int c = 0; c < this->GetNumberOfInputConnections(port); ++c)
    {
      vtkInformation* inInfo = inputVector[port]->GetInformationObject(c);
      inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), 0);
      inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(), 1);
      inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_GHOST_LEVELS(), 0);
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
    }
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
int vtkPBFSimulation::RequestFrame(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkPolyData* output = vtkPolyData::GetData(outputVector, 0);
  vtkTable* table = vtkTable::GetData(outputVector, 1);
  vtkInternals& internals = *this->Internals;
  internals.Costs = pbf::FrameReached();
  internals.DeliveryMilliseconds = 0;
  const FrameRequest r = internals.ParseRequest(this, request, outputVector);
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
    internals.Adopt(this, internals.MakeKey(this, input, obstacles, r), r.Frame);
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
          r.Frame, [&]() { return internals.Build(this, playback.key(), input, obstacles); },
          [this](double fraction) {
            this->UpdateProgress(fraction);
            // AbortExecute stays set, as VTK has it: whoever set it clears it.
            return this->GetAbortExecute() != 0;
          });
        internals.Costs = reached;
        if (reached.aborted)
        {
          internals.ReportAbort(this, r);
          internals.DeliverPrevious(output, table);
          return 1;
        }
        internals.Deliver(this, r, reached, output, table);
        return 1;
      }
      catch (const pbf::DeviceFault& fault)
      {
        internals.OnDeviceFault(this, fault, r.Frame);
      }
    }
  }
  catch (const std::bad_alloc&)
  {
    vtkErrorMacro(<< "out of memory: try a larger Particle Spacing or a smaller scene");
  }
  catch (const std::exception& error)
  {
    vtkErrorMacro(<< internals.InUserTerms(this, error));
  }
  // A failed request may have stopped a simulation half way through a step: never step on from
  // it. Checkpoints and rows are of whole frames and stay.
  playback.dropLive();
  internals.LastFrame = -1;
  internals.DeliverPrevious(output, table);
  return 0;
}

//------------------------------------------------------------------------------
FrameRequest vtkPBFSimulation::vtkInternals::ParseRequest(
  vtkPBFSimulation* self, vtkInformation* request, vtkInformationVector* outputVector) const
{
  // The request may come through any port; all carry the same time.
  int port = request->Has(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    ? request->Get(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    : 0;
  if (port < 0 || port >= self->GetNumberOfOutputPorts())
  {
    port = 0;
  }
  vtkInformation* info = outputVector->GetInformationObject(port);
  FrameRequest r;
  r.Frame = self->FrameForTime(info->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
      ? info->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
      : 0.0);
  r.Time = static_cast<double>(r.Frame) * self->FrameInterval;
  if (info->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()))
  {
    r.Piece = info->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER());
  }
  if (info->Has(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES()))
  {
    r.Pieces = info->Get(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES());
  }
  // One piece per rank of ParaView's parallel engine: a domain-decomposed run, in which every
  // rank takes part in every request. Any other split (streaming pieces in one process) gets the
  // whole fluid on piece 0.
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  r.Decomposed = self->DecomposeAcrossRanks && r.Pieces > 1 && controller &&
    controller->GetNumberOfProcesses() == r.Pieces && controller->GetLocalProcessId() == r.Piece;
  return r;
}

//------------------------------------------------------------------------------
pbf::PlaybackKey vtkPBFSimulation::vtkInternals::MakeKey(vtkPBFSimulation* self,
  vtkPointSet* input, const std::vector<vtkDataSet*>& obstacles, const FrameRequest& r)
{
  const std::string invalidTime = self->InvalidTimeProperty();
  if (!invalidTime.empty())
  {
    throw pbf::InvalidInput(invalidTime);
  }
  pbf::PlaybackKey key;
  const std::string sceneFile = self->SceneFile ? self->SceneFile : "";
  key.scene = sceneFile.empty() ? std::string("preset ") + self->GetPresetName()
                                : "file " + sceneFile + "\n" + ReadWholeFile(sceneFile);
  key.scene += MeshFileVersions(sceneFile);
  pbf::Parameters& p = key.parameters;
  p.restDensity = self->RestDensity;
  p.particleSpacing = self->ParticleSpacing;
  p.smoothingRatio = self->SmoothingRatio;
  p.solverIterations = self->SolverIterations;
  p.densityErrorTolerance = self->AdaptiveIterations ? self->DensityErrorTolerance : 0.0;
  p.maxDensityErrorTolerance = self->MaxDensityErrorTolerance;
  p.relaxation = self->RelaxationEpsilon;
  p.sCorrK = self->SCorrK;
  p.sCorrN = self->SCorrN;
  p.sCorrDeltaQ = self->SCorrDeltaQ;
  p.xsphViscosity = self->XSPHViscosity;
  p.vorticityEpsilon = self->VorticityEpsilon;
  p.unilateral = self->Unilateral;
  p.mirrorWalls = self->MirrorWalls;
  p.gravity = pbf::Vec3d{ self->Gravity[0], self->Gravity[1], self->Gravity[2] };
  // Fixed: SubstepsPerFrame equal steps per frame. Automatic: steps chosen from the state, at
  // most MaxTimeStep, landing on every frame; SubstepsPerFrame then changes nothing.
  const bool automatic = self->TimeStepping == TIME_STEPPING_AUTOMATIC;
  p.timeStepping = automatic ? pbf::TimeStepping::Automatic : pbf::TimeStepping::Fixed;
  p.timeStep = automatic ? self->MaxTimeStep : self->FrameInterval / self->SubstepsPerFrame;
  p.cflNumber = automatic ? self->CFLNumber : pbf::Parameters().cflNumber;
  key.frameInterval = self->FrameInterval;
  key.substeps = automatic ? 0 : self->SubstepsPerFrame;
  key.precision =
    self->Precision == PRECISION_DOUBLE ? pbf::Precision::Double : pbf::Precision::Single;
  key.hasInput = input != nullptr;
  key.inputVersion = input ? input->GetMTime() : 0;
  // A new obstacle, a changed one or another thickness is another run; none: empty.
  if (!obstacles.empty())
  {
    std::ostringstream solids;
    solids << obstacles.size() << " thickness " << self->ObstacleThickness;
    for (vtkDataSet* obstacle : obstacles)
    {
      solids << " " << (obstacle ? obstacle->GetMTime() : 0);
    }
    key.obstacles = solids.str();
  }

  // The ranks of a decomposed run, and the backend every rank agrees on.
  if (r.Decomposed && !this->Ranks)
  {
    this->Ranks = MakeRankCommunicator(vtkMultiProcessController::GetGlobalController());
  }
  pbf::distributed::Communicator* ranks = r.Decomposed ? this->Ranks.get() : nullptr;
  if (ranks && ranks->failed())
  {
    // Every rank failed together (the same error on each), so every rank comes here and opens a
    // fresh channel before the next collective call, leaving the failed one's messages behind.
    ranks->recover();
  }
  this->Playback.setRanks(ranks);
  key.ranks = r.Decomposed ? r.Pieces : 1;
  const pbf::BackendRequest requested[] = { pbf::BackendRequest::Auto, pbf::BackendRequest::CUDA,
    pbf::BackendRequest::OpenMP, pbf::BackendRequest::Serial };
  const pbf::BackendChoice choice =
    pbf::chooseBackend(requested[self->Backend], this->HasCuda(), this->CudaAbsence, ranks);
  key.backend = choice.backend;
  if (!choice.noCuda.empty() && !this->FallbackReported)
  {
    this->FallbackReported = true;
    std::ostringstream text;
    text << self->GetClassName() << " (" << self << "): Backend Auto: no CUDA (" << choice.noCuda
         << "); falling back to CPU (OpenMP).\n";
    vtkOutputWindowDisplayText(text.str().c_str());
  }
  return key;
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::vtkInternals::Adopt(
  vtkPBFSimulation* self, const pbf::PlaybackKey& key, int frame)
{
  // Obstacles are static: one that changes (moved by hand, or by an animated Transform upstream)
  // starts the run again with the obstacle where it is now. Said whenever a later frame is asked
  // (playing, scrubbing), so that an animated obstacle is not mistaken for a moving one.
  const std::string& before = this->Playback.key().obstacles;
  if (frame > 0 && !before.empty() && !key.obstacles.empty() && before != key.obstacles)
  {
    vtkWarningWithObjectMacro(self, << "the Obstacles input changed: the simulation starts "
                                       "again from frame 0 with the obstacles as they are now "
                                       "(obstacles stand still; a moving one is not simulated).");
  }
  if (this->Playback.adopt(key) && !this->Playback.deviceFaulted())
  {
    this->LastFrame = -1; // another run: nothing delivered belongs to it
    this->DeviceFaultText.clear();
  }
  this->Playback.configureCheckpoints(self->CheckpointInterval,
    static_cast<std::size_t>(std::min(self->CheckpointMemoryMB * 1048576.0, 1e18)));
}

//------------------------------------------------------------------------------
std::unique_ptr<pbf::Simulation> vtkPBFSimulation::vtkInternals::Build(vtkPBFSimulation* self,
  const pbf::PlaybackKey& key, vtkPointSet* input, const std::vector<vtkDataSet*>& obstacles)
{
  const std::string sceneFile = self->SceneFile ? self->SceneFile : "";
  pbf::Scene scene =
    sceneFile.empty() ? pbf::presetScene(self->GetPresetName()) : pbf::loadSceneFile(sceneFile);
  vtkPBFReadMeshFiles(scene);
  // The Obstacles port's solids join the scene's own, named as the user can find them.
  for (std::size_t c = 0; c < obstacles.size(); ++c)
  {
    const std::string name = "Obstacles input " + std::to_string(c + 1) + " of " +
      std::to_string(obstacles.size()) + " (" +
      (obstacles[c] ? obstacles[c]->GetClassName() : "no data") + ")";
    scene.solids.push_back(vtkPBFSolidFromInput(obstacles[c], self->ObstacleThickness, name));
  }
  // Decomposed, every rank builds the whole fluid (from the whole input, which
  // RequestUpdateExtent asks for on every rank) and keeps its slab.
  pbf::distributed::Communicator* ranks = key.ranks > 1 ? this->Ranks.get() : nullptr;
  if (ranks && ranks->failed())
  {
    ranks->recover();
  }
  auto simulation = input
    ? std::make_unique<pbf::Simulation>(scene, key.parameters, key.backend, key.precision,
        vtkPBFBatchFromInput(input), ranks)
    : std::make_unique<pbf::Simulation>(scene, key.parameters, key.backend, key.precision, ranks);
  if (simulation->seededInsideSolids() > 0 && (!ranks || ranks->rank() == 0))
  {
    vtkWarningWithObjectMacro(self, << simulation->seededInsideSolids()
                                    << " initial particles lay inside the obstacles and were "
                                       "removed before the first step.");
  }
  return simulation;
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::vtkInternals::OnDeviceFault(
  vtkPBFSimulation* self, const pbf::DeviceFault& fault, int frame)
{
  // The GPU failed (a lost device, a kernel that faulted): its copy of the state is gone, while
  // the checkpoints and the diagnostics rows are host copies of whole frames and stay. CUDA is
  // not tried again (a lost context stays lost until the process ends). Backend Auto goes on on
  // the CPU; Backend CUDA stops with an error that says how to go on.
  const std::uint64_t failedAt = this->Playback.live() ? this->Playback.live()->stepCount() : 0;
  const bool fallBack =
    self->Backend == BACKEND_AUTO && this->Playback.key().backend == pbf::Backend::CUDA;
  const std::string resumable = this->Playback.afterDeviceFault(frame, fallBack);
  this->CudaProbed = true;
  this->CudaPresent = false;
  this->CudaAbsence = std::string("the GPU failed earlier: ") + fault.what();
  this->FallbackReported = true; // this message says it; the Auto notice need not
  std::ostringstream text;
  text << "CUDA device fault near step " << failedAt << ", on the way to frame " << frame << ": "
       << fault.what() << ". ";
  if (!fallBack)
  {
    text << "The previous output stays and so do the checkpoints: choose Backend Auto or CPU "
            "(OpenMP) to go on from "
         << resumable << " on the CPU.";
    throw std::runtime_error(text.str());
  }
  text << "Backend Auto: falling back to CPU (OpenMP) from " << resumable
       << "; the frames from there on are computed on the CPU (they agree with the GPU's to "
          "rounding, not bit for bit).";
  this->DeviceFaultText = text.str();
  vtkWarningWithObjectMacro(self, << this->DeviceFaultText);
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::vtkInternals::Deliver(vtkPBFSimulation* self, const FrameRequest& r,
  const pbf::FrameReached& reached, vtkPolyData* output, vtkTable* table)
{
  const auto start = std::chrono::steady_clock::now();
  const pbf::Simulation& simulation = *this->Playback.live();
  vtkNew<vtkPolyData> result;
  vtkPBFOutput::FillParticles(simulation.stepper(),
    self->PageLockedOutput && simulation.stepper().backend() == pbf::Backend::CUDA,
    this->Vertices, result);
  vtkSmartPointer<vtkFieldData> fieldData = vtkPBFOutput::FrameFieldData(
    simulation, r.Frame, self->FrameInterval, self->SubstepsPerFrame);
  vtkPBFOutput::AddInteger(fieldData, "RequestSteps", static_cast<vtkIdType>(reached.steps));
  vtkPBFOutput::AddText(fieldData, "ResumedFrom", reached.resumedFrom);
  if (this->Playback.key().ranks > 1)
  {
    // Collective, like every step: all ranks deliver the same frame.
    vtkPBFOutput::AddInteger(fieldData, "Rank", r.Piece);
    vtkPBFOutput::AddInteger(fieldData, "Ranks", this->Playback.key().ranks);
    vtkNew<vtkIdTypeArray> perRank;
    perRank->SetName("ParticlesPerRank");
    for (const std::vector<double>& theirs :
      pbf::distributed::allGather(*this->Ranks, { double(simulation.stepper().size()) }))
    {
      perRank->InsertNextValue(static_cast<vtkIdType>(theirs[0]));
    }
    fieldData->AddArray(perRank);
  }
  if (!this->DeviceFaultText.empty())
  {
    vtkPBFOutput::AddText(fieldData, "DeviceFault", this->DeviceFaultText);
  }
  vtkPBFOutput::AddInteger(
    fieldData, "ResumedFromStep", static_cast<vtkIdType>(reached.resumedFromStep));
  vtkNew<vtkIdTypeArray> held;
  held->SetName("CheckpointFrames");
  for (int frame : this->Playback.checkpointFrames())
  {
    held->InsertNextValue(frame);
  }
  fieldData->AddArray(held);
  vtkPBFOutput::AddValue(
    fieldData, "CheckpointMemoryMB", this->Playback.checkpointBytes() / 1048576.0);
  result->SetFieldData(fieldData);
  result->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), r.Time);
  this->LastOutput = result;
  this->LastFrame = r.Frame;
  output->ShallowCopy(result);
  output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), r.Time);
  table->ShallowCopy(this->DiagnosticsTable());
  table->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), r.Time);
  this->DeliveryMilliseconds = Milliseconds(start);
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::vtkInternals::ReportAbort(vtkPBFSimulation* self, const FrameRequest& r)
{
  const pbf::Simulation& simulation = *this->Playback.live();
  std::ostringstream text;
  text << self->GetClassName() << " (" << self << "): aborted at step " << simulation.stepCount()
       << " (t = " << simulation.time() << " s) on the way to frame " << r.Frame
       << " (t = " << r.Time << " s); the previous output stays.\n";
  vtkOutputWindowDisplayText(text.str().c_str());
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::vtkInternals::DeliverAgain(
  const FrameRequest& r, vtkPolyData* output, vtkTable* table)
{
  // The frame just delivered: handed out again, arrays shared, nothing stepped or copied.
  output->ShallowCopy(this->LastOutput);
  vtkNew<vtkFieldData> fieldData;
  fieldData->ShallowCopy(this->LastOutput->GetFieldData());
  vtkPBFOutput::AddInteger(fieldData, "RequestSteps", 0);
  vtkPBFOutput::AddText(fieldData, "ResumedFrom", "output");
  vtkDataArray* steps = this->LastOutput->GetFieldData()->GetArray("StepCount");
  vtkPBFOutput::AddInteger(fieldData, "ResumedFromStep",
    steps ? static_cast<vtkIdType>(steps->GetTuple1(0)) : vtkIdType(0));
  output->SetFieldData(fieldData);
  output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), r.Time);
  table->ShallowCopy(this->DiagnosticsTable());
  table->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), r.Time);
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::vtkInternals::DeliverPrevious(vtkPolyData* output, vtkTable* table)
{
  // The last good output (with its own time) and the diagnostics known so far.
  output->ShallowCopy(this->LastOutput);
  table->ShallowCopy(this->DiagnosticsTable());
  vtkInformation* last = this->LastOutput->GetInformation();
  if (last->Has(vtkDataObject::DATA_TIME_STEP()))
  {
    const double shown = last->Get(vtkDataObject::DATA_TIME_STEP());
    output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), shown);
    table->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), shown);
  }
}

//------------------------------------------------------------------------------
vtkTable* vtkPBFSimulation::vtkInternals::DiagnosticsTable()
{
  const pbf::Playback& playback = this->Playback;
  // A decomposed run's rows are reduced over the ranks and the same on each: rank 0 shows them.
  const bool decomposed = playback.hasKey() && playback.key().ranks > 1;
  if (decomposed && this->Ranks && this->Ranks->rank() != 0)
  {
    return this->EmptyTable;
  }
  if (!this->Table || this->TableVersion != playback.rowsVersion())
  {
    this->Table = vtkPBFOutput::DiagnosticsTable(playback.rows(), decomposed);
    this->TableVersion = playback.rowsVersion();
  }
  return this->Table;
}

//------------------------------------------------------------------------------
std::string vtkPBFSimulation::vtkInternals::InUserTerms(
  vtkPBFSimulation* self, const std::exception& error) const
{
  std::string text = vtkPBFInUserTerms(error.what());
  if (dynamic_cast<const pbf::InvalidInput*>(&error) && text.find("domain") != std::string::npos)
  {
    // The user set no domain: say where it comes from and what changes it.
    const bool file = self->SceneFile && *self->SceneFile;
    text += file ? std::string(". The domain is the one of Scene File \"") + self->SceneFile + "\""
                 : std::string(". The domain is the tank of Preset \"") + self->GetPresetName() +
        "\"; a Scene File with its own \"domain\" changes it";
  }
  return text;
}

//------------------------------------------------------------------------------
void vtkPBFSimulation::RequestDomain(vtkInformationVector* outputVector)
{
  vtkInternals& internals = *this->Internals;
  vtkPolyData* domain = vtkPolyData::GetData(outputVector, 2);
  vtkPolyData* particles = vtkPolyData::GetData(outputVector, 0);
  const pbf::Simulation* live = internals.Playback.live();
  if (live && !(internals.DomainBuilt && internals.DomainKey == internals.Playback.key()))
  {
    internals.Domain = vtkPBFOutput::DomainOutline(live->parameters().domain, live->scene());
    internals.DomainKey = internals.Playback.key();
    internals.DomainBuilt = true;
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
std::string vtkPBFSimulation::InvalidTimeProperty() const
{
  return vtkPBFInvalidTimeProperty(this->FrameInterval, this->NumberOfFrames,
    this->TimeStepping == TIME_STEPPING_AUTOMATIC, this->SubstepsPerFrame, this->MaxTimeStep);
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
  os << indent << "ObstacleThickness: " << this->ObstacleThickness << "\n";
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
