#include "vtkPBFSimulationInternals.h"
#include "vtkPBFObstacles.h"
#include "vtkPBFOutput.h"
#include "vtkPBFRankCommunicator.h"
#include "vtkPBFTranslate.h"

#include "vtkDataArray.h"
#include "vtkDataSet.h"
#include "vtkFieldData.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkObject.h"
#include "vtkOutputWindow.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPointSet.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include "Parameters.h"
#include "Scene.h"
#include "Stepper.h"
#include "SurfaceShare.h"
#include "Distributed/RankFailure.h"
#include "Distributed/SubdomainStepper.h"
#ifdef PBF_WITH_CUDA
#include "Cuda/CudaBackend.h"
#include "Cuda/CudaSurface.h"
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{

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

} // namespace

//------------------------------------------------------------------------------
int vtkPBFSettings::FrameForTime(double time) const
{
  if (!std::isfinite(time) || time <= 0.0 || !this->InvalidTime.empty())
  {
    return 0;
  }
  const double frame = std::round(time / this->FrameInterval);
  return static_cast<int>(std::min(frame, static_cast<double>(this->NumberOfFrames)));
}

//------------------------------------------------------------------------------
FrameRequest vtkPBFSimulationInternals::ParseRequest(
  const vtkPBFSettings& settings, vtkInformation* request, vtkInformationVector* outputVector) const
{
  // The request may come through any port; all carry the same time.
  int port = request->Has(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    ? request->Get(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    : 0;
  if (port < 0 || port >= settings.OutputPorts)
  {
    port = 0;
  }
  vtkInformation* info = outputVector->GetInformationObject(port);
  FrameRequest r;
  r.Frame = settings.FrameForTime(info->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
      ? info->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
      : 0.0);
  r.Time = static_cast<double>(r.Frame) * settings.FrameInterval;
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
  r.Decomposed = settings.DecomposeAcrossRanks && r.Pieces > 1 && controller &&
    controller->GetNumberOfProcesses() == r.Pieces && controller->GetLocalProcessId() == r.Piece;
  return r;
}

//------------------------------------------------------------------------------
pbf::PlaybackKey vtkPBFSimulationInternals::MakeKey(const vtkPBFSettings& settings,
  vtkPointSet* input, const std::vector<vtkDataSet*>& obstacles, const FrameRequest& r)
{
  const std::string invalidTime = settings.InvalidTime;
  if (!invalidTime.empty())
  {
    throw pbf::InvalidInput(invalidTime);
  }
  pbf::PlaybackKey key;
  const std::string& sceneFile = settings.SceneFile;
  key.scene = sceneFile.empty() ? std::string("preset ") + settings.PresetName
                                : "file " + sceneFile + "\n" + ReadWholeFile(sceneFile);
  // The scene is parsed for its mesh files only when its path or text changed, not at every
  // request; the files themselves are looked at every time (an STL rewritten in place).
  if (key.scene != this->MeshFilesOf)
  {
    this->MeshFiles = vtkPBFSceneMeshFiles(sceneFile);
    this->MeshFilesOf = key.scene;
  }
  key.scene += vtkPBFFileVersions(this->MeshFiles);
  // The table's parameters as set; the filter's own properties decide what a run uses of them.
  pbf::Parameters& p = key.parameters;
  p = this->Physics;
  if (!settings.AdaptiveIterations)
  {
    p.densityErrorTolerance = 0.0;
  }
  // Fixed: SubstepsPerFrame equal steps per frame. Automatic: steps chosen from the state, at
  // most MaxTimeStep, landing on every frame; SubstepsPerFrame then changes nothing.
  const bool automatic = settings.Automatic;
  p.timeStepping = automatic ? pbf::TimeStepping::Automatic : pbf::TimeStepping::Fixed;
  if (!automatic)
  {
    p.timeStep = settings.FrameInterval / settings.SubstepsPerFrame;
    p.cflNumber = pbf::Parameters().cflNumber;
  }
  key.frameInterval = settings.FrameInterval;
  key.substeps = automatic ? 0 : settings.SubstepsPerFrame;
  key.precision = settings.Precision;
  key.hasInput = input != nullptr;
  key.inputVersion = input ? input->GetMTime() : 0;
  // The obstacles as read at this frame's time: a rigid motion since they were first seen
  // extends their motion; a new obstacle, a new shape, a change of the motion before its end or
  // another thickness is another run; none: empty.
  const std::string warning =
    this->ObstacleMotion.Observe(obstacles, r.Frame * settings.FrameInterval);
  if (!warning.empty() && (!r.Decomposed || r.Piece == 0))
  {
    vtkWarningWithObjectMacro(settings.Owner, << warning);
  }
  if (!obstacles.empty())
  {
    std::ostringstream solids;
    // Every digit: two runs whose thickness, density or release differ in the 7th digit differ.
    solids << std::setprecision(17);
    solids << obstacles.size() << " thickness " << settings.ObstacleThickness
           << this->ObstacleMotion.Key();
    // A body's density and name (vtkPBFRigidBody) are part of the run.
    for (vtkDataSet* obstacle : obstacles)
    {
      const vtkPBFBodyTag tag = vtkPBFBodyTagOf(obstacle);
      solids << " body " << tag.Density << " " << tag.Name << " axes " << tag.FreeAxes[0]
             << tag.FreeAxes[1] << tag.FreeAxes[2] << " turns " << tag.Turns << " release "
             << tag.Release;
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
  // HasCuda() first: it fills CudaAbsence.
  const bool cuda = this->HasCuda();
  const pbf::BackendChoice choice =
    pbf::chooseBackend(settings.Backend, cuda, this->CudaAbsence, ranks);
  key.backend = choice.backend;
  if (!choice.noCuda.empty() && !this->FallbackReported)
  {
    this->FallbackReported = true;
    std::ostringstream text;
    text << settings.Owner->GetClassName() << " (" << settings.Owner << "): Backend Auto: no CUDA (" << choice.noCuda
         << "); falling back to CPU (OpenMP).\n";
    vtkOutputWindowDisplayText(text.str().c_str());
  }
  return key;
}

//------------------------------------------------------------------------------
void vtkPBFSimulationInternals::Adopt(const vtkPBFSettings& settings, const pbf::PlaybackKey& key)
{
  if (this->Playback.adopt(key) && !this->Playback.deviceFaulted())
  {
    this->LastFrame = -1; // another run: nothing delivered belongs to it
    this->DeviceFaultText.clear();
  }
  this->Playback.configureCheckpoints(settings.CheckpointInterval,
    static_cast<std::size_t>(std::min(settings.CheckpointMemoryMB * 1048576.0, 1e18)));
}

//------------------------------------------------------------------------------
std::unique_ptr<pbf::Simulation> vtkPBFSimulationInternals::Build(const vtkPBFSettings& settings,
  const pbf::PlaybackKey& key, vtkPointSet* input, const std::vector<vtkDataSet*>& obstacles)
{
  const std::string& sceneFile = settings.SceneFile;
  pbf::Scene scene =
    sceneFile.empty() ? pbf::presetScene(settings.PresetName) : pbf::loadSceneFile(sceneFile);
  vtkPBFReadMeshFiles(scene);
  // The Obstacles port's solids join the scene's own, named as the user can find them.
  for (std::size_t c = 0; c < obstacles.size(); ++c)
  {
    const std::string name = "Obstacles input " + std::to_string(c + 1) + " of " +
      std::to_string(obstacles.size()) + " (" +
      (obstacles[c] ? obstacles[c]->GetClassName() : "no data") + ")";
    // The shape first seen, moved as it has been seen to move (vtkPBFObstacleMotion.h).
    vtkDataSet* shape = c < obstacles.size() && obstacles[c] ? this->ObstacleMotion.Reference(c) : nullptr;
    scene.solids.push_back(vtkPBFSolidFromInput(shape, settings.ObstacleThickness, name));
    scene.solids.back().motion = this->ObstacleMotion.MotionOf(c);
    // Marked by vtkPBFRigidBody: a body the fluid moves (its density checked here, by name).
    const vtkPBFBodyTag tag = vtkPBFBodyTagOf(obstacles[c]);
    if (tag.Tagged)
    {
      pbf::SolidRegion& solid = scene.solids.back();
      const std::string called = tag.Name.empty() ? name : tag.Name;
      if (!(tag.Density > 0) || !std::isfinite(tag.Density))
      {
        std::ostringstream text;
        text << called << ": Density = " << tag.Density
             << ": a rigid body's density must be a positive number [kg/m^3]";
        throw pbf::InvalidInput(text.str());
      }
      if (!(tag.Release >= 0) || !std::isfinite(tag.Release))
      {
        std::ostringstream text;
        text << called << ": Release = " << tag.Release
             << ": a rigid body's release must be a finite time >= 0 [s]";
        throw pbf::InvalidInput(text.str());
      }
      solid.density = tag.Density;
      solid.name = called;
      solid.freeAxes = { tag.FreeAxes[0], tag.FreeAxes[1], tag.FreeAxes[2] };
      solid.turns = tag.Turns;
      solid.release = tag.Release;
    }
  }
  // Decomposed, every rank generates only its slab of the scene's fluid (pbf::SceneFluid), and
  // an input's points come in pieces, one a rank (RequestUpdateExtent), which the ranks hand to
  // the ranks that own them (pbf::distributed::FluidPieces): no rank holds the whole fluid.
  pbf::distributed::Communicator* ranks = key.ranks > 1 ? this->Ranks.get() : nullptr;
  if (ranks && ranks->failed())
  {
    ranks->recover();
  }
  std::unique_ptr<pbf::Simulation> simulation;
  if (input && ranks)
  {
    // Where this piece starts in the whole input, so that ids and messages count as one process.
    vtkIdType first = 0, total = 0;
    const auto counts =
      pbf::distributed::allGather(*ranks, { double(input->GetNumberOfPoints()) });
    for (int r = 0; r < static_cast<int>(counts.size()); ++r)
    {
      first += r < ranks->rank() ? static_cast<vtkIdType>(counts[r][0]) : 0;
      total += static_cast<vtkIdType>(counts[r][0]);
    }
    // A bad point lies in one rank's piece: that rank fails, and every rank with it.
    const pbf::ParticleBatch piece = pbf::distributed::together(
      *ranks, [&] { return vtkPBFBatchFromInput(input, first, total); });
    simulation = std::make_unique<pbf::Simulation>(scene, key.parameters, key.backend,
      key.precision, piece, *ranks, pbf::Simulation::InPieces{});
  }
  else if (input)
  {
    simulation = std::make_unique<pbf::Simulation>(
      scene, key.parameters, key.backend, key.precision, vtkPBFBatchFromInput(input), ranks);
  }
  else
  {
    simulation =
      std::make_unique<pbf::Simulation>(scene, key.parameters, key.backend, key.precision, ranks);
  }
  if (simulation->seededInsideSolids() > 0 && (!ranks || ranks->rank() == 0))
  {
    vtkWarningWithObjectMacro(settings.Owner, << simulation->seededInsideSolids()
                                    << " initial particles lay inside the obstacles and were "
                                       "removed before the first step.");
  }
  return simulation;
}

//------------------------------------------------------------------------------
void vtkPBFSimulationInternals::UpdateObstacleMotion(std::size_t connections)
{
  pbf::Simulation* live = this->Playback.live();
  if (!live || connections == 0)
  {
    return;
  }
  // The port's solids follow the scene's own.
  const std::size_t first = live->solidMotions().size() - connections;
  for (std::size_t c = 0; c < connections; ++c)
  {
    const pbf::SolidMotion motion = this->ObstacleMotion.MotionOf(c);
    if (motion.moves() && live->scene().solids[first + c].density > 0)
    {
      throw pbf::InvalidInput(live->solidName(first + c) +
        ": a rigid body (Position Based Fluids Rigid Body) whose input moves: a body moves only "
        "as the fluid pushes it; animate the obstacle without the rigid body filter, or stop its "
        "input's animation");
    }
    live->setSolidMotion(first + c, motion);
  }
}

//------------------------------------------------------------------------------
void vtkPBFSimulationInternals::OnDeviceFault(
  const vtkPBFSettings& settings, const pbf::DeviceFault& fault, int frame)
{
  // The GPU failed (a lost device, a kernel that faulted): its copy of the state is gone, while
  // the checkpoints and the diagnostics rows are host copies of whole frames and stay. CUDA is
  // not tried again (a lost context stays lost until the process ends). Backend Auto goes on on
  // the CPU; Backend CUDA stops with an error that says how to go on.
  const std::uint64_t failedAt = this->Playback.live() ? this->Playback.live()->stepCount() : 0;
  const bool fallBack =
    settings.Backend == pbf::BackendRequest::Auto && this->Playback.key().backend == pbf::Backend::CUDA;
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
  vtkWarningWithObjectMacro(settings.Owner, << this->DeviceFaultText);
}

//------------------------------------------------------------------------------
void vtkPBFSimulationInternals::Deliver(const vtkPBFSettings& settings, const FrameRequest& r,
  const pbf::FrameReached& reached, vtkPolyData* output, vtkTable* table)
{
  const auto start = std::chrono::steady_clock::now();
  const pbf::Simulation& simulation = *this->Playback.live();
  vtkNew<vtkPolyData> result;
  vtkPBFOutput::FillParticles(simulation.stepper(),
    settings.PageLockedOutput && simulation.stepper().backend() == pbf::Backend::CUDA,
    !simulation.parameters().liquids.empty(), this->Vertices, result);
  vtkSmartPointer<vtkFieldData> fieldData = vtkPBFOutput::FrameFieldData(
    simulation, r.Frame, settings.FrameInterval, settings.SubstepsPerFrame);
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
  const auto row = this->Playback.rows().find(r.Frame);
  if (row != this->Playback.rows().end())
  {
    vtkPBFOutput::AddLoads(fieldData, row->second);
  }
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
void vtkPBFSimulationInternals::ReportAbort(const vtkPBFSettings& settings, const FrameRequest& r)
{
  const pbf::Simulation& simulation = *this->Playback.live();
  std::ostringstream text;
  text << settings.Owner->GetClassName() << " (" << settings.Owner << "): aborted at step " << simulation.stepCount()
       << " (t = " << simulation.time() << " s) on the way to frame " << r.Frame
       << " (t = " << r.Time << " s); the previous output stays.\n";
  vtkOutputWindowDisplayText(text.str().c_str());
}

//------------------------------------------------------------------------------
void vtkPBFSimulationInternals::DeliverAgain(
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
void vtkPBFSimulationInternals::DeliverPrevious(vtkPolyData* output, vtkTable* table)
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
vtkTable* vtkPBFSimulationInternals::DiagnosticsTable()
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
std::string vtkPBFSimulationInternals::InUserTerms(
  const vtkPBFSettings& settings, const std::exception& error) const
{
  std::string text = vtkPBFInUserTerms(error.what());
  if (dynamic_cast<const pbf::InvalidInput*>(&error) && text.find("domain") != std::string::npos)
  {
    // The user set no domain: say where it comes from and what changes it.
    const bool file = !settings.SceneFile.empty();
    text += file ? std::string(". The domain is the one of Scene File \"") + settings.SceneFile + "\""
                 : std::string(". The domain is the tank of Preset \"") + settings.PresetName +
        "\"; a Scene File with its own \"domain\" changes it";
  }
  return text;
}

