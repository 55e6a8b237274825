// vtkPBFSimulation's state between requests and the steps of a request, apart from the
// pipeline methods (vtkPBFSimulation.cxx): the playback core (live simulation, checkpoints,
// diagnostics rows) and what the VTK side keeps of its results. Private to the filter. It reads
// the filter's properties from the vtkPBFSettings the filter hands each call, never the filter
// itself, so the filter includes this header and not the other way round.
#ifndef vtkPBFSimulationInternals_h
#define vtkPBFSimulationInternals_h

#include "vtkPBFObstacleMotion.h"
#include "vtkPBFPortDemand.h"

#include "vtkCellArray.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkTable.h"
#include "vtkTimeStamp.h"

#include "BackendChoice.h"
#include "Backends.h"
#include "Communicator.h"
#include "DeviceFault.h"
#include "Playback.h"
#include "Simulation.h"
#include "SurfaceExtraction.h"

#include <memory>
#include <string>
#include <vector>

class vtkDataSet;
class vtkInformation;
class vtkInformationVector;
class vtkObject;
class vtkPointSet;
namespace pbf::distributed
{
class DecomposedStepper;
}

// What a request needs of the filter's own properties (the physics parameters are kept here, in
// vtkPBFSimulationInternals::Physics): the filter makes one at each request.
struct vtkPBFSettings
{
  vtkObject* Owner = nullptr; // the filter, for warnings and messages that name it
  std::string SceneFile;      // empty: the preset
  std::string PresetName;
  int OutputPorts = 0;
  double FrameInterval = 1.0 / 60.0;
  int NumberOfFrames = 0;
  int SubstepsPerFrame = 1;
  bool Automatic = true; // TimeStepping Automatic
  bool AdaptiveIterations = true;
  pbf::Precision Precision = pbf::Precision::Single;
  pbf::BackendRequest Backend = pbf::BackendRequest::Auto;
  double ObstacleThickness = 0.0;
  bool DecomposeAcrossRanks = true;
  int CheckpointInterval = 0;
  double CheckpointMemoryMB = 0.0;
  bool PageLockedOutput = true;
  // What is wrong with the time properties, in the GUI's words; empty when nothing is.
  std::string InvalidTime;

  // The frame answering a requested time: the nearest one, clamped to 0..NumberOfFrames.
  int FrameForTime(double time) const;
};

// Which piece of which frame a request asks for.
struct FrameRequest
{
  int Frame = 0;
  double Time = 0; // the frame's time, Frame * FrameInterval
  int Piece = 0;
  int Pieces = 1;
  bool Decomposed = false; // one piece per rank of the global controller: a decomposed run
};

// The algorithm's state between requests: the playback core (live simulation, checkpoints,
// diagnostics rows) and what the VTK side keeps of its results.
class vtkPBFSimulationInternals
{
public:
  pbf::Playback Playback;
  // The physics parameters as set (vtkPBFSimulation::SetParameter), with the solver's defaults.
  pbf::Parameters Physics;

  // What the last successful request produced (a failed or aborted request hands it out again)
  // and, when it is a frame of the playback's key, which one (-1 otherwise).
  vtkSmartPointer<vtkPolyData> LastOutput = vtkSmartPointer<vtkPolyData>::New();
  int LastFrame = -1;
  // The outputs the current execution makes (ProcessRequest's REQUEST_DATA_NOT_GENERATED).
  vtkPBFPortDemand Demand;
  // The surface's consumers hold no surface of their frame (vtkPBFPortDemand::LeftStale), and the
  // stamp that makes them ask again.
  bool SurfaceStale = false;
  vtkTimeStamp SurfaceStamp;
  // The outline of the domain last simulated (port 2), kept when a request fails.
  vtkSmartPointer<vtkPolyData> Domain = vtkSmartPointer<vtkPolyData>::New();
  // The run Domain was built for: the tank and the scene's obstacles change only with it.
  pbf::PlaybackKey DomainKey;
  bool DomainBuilt = false;
  // The Obstacles port's connections as first seen, and their motion as seen since.
  vtkPBFObstacleMotion ObstacleMotion;
  // The mesh files of the scene file whose path and text MeshFilesOf holds.
  std::string MeshFilesOf;
  std::vector<std::string> MeshFiles;
  // Reused from frame to frame while the particle count stays.
  vtkSmartPointer<vtkCellArray> Vertices;
  // The diagnostics table of the rows of version TableVersion.
  vtkSmartPointer<vtkTable> Table;
  std::uint64_t TableVersion = 0;
  vtkSmartPointer<vtkTable> EmptyTable = vtkSmartPointer<vtkTable>::New();

  // The last surface delivered on port 3 and what it was made from (the frame's particles'
  // modification time and the options), so that asking again reuses it.
  vtkSmartPointer<vtkPolyData> LastSurface = vtkSmartPointer<vtkPolyData>::New();
  std::string LastSurfaceOf;
  bool SmoothingDecomposedSaid = false;
  // A CUDA run's surface is made on its GPU (the CPU's mesh, bit for bit); the extractor keeps
  // its device arrays from frame to frame. Null until a CUDA run asks for a surface.
  std::shared_ptr<void> GpuSurface;
  bool GpuSurfaceFailedSaid = false;

  // The cost of the last request.
  pbf::FrameReached Costs;
  double DeliveryMilliseconds = 0;

  // The ranks of a decomposed run, over ParaView's global controller: its MPI communicator where
  // it has one (pvbatch under mpiexec, a pvserver), so that a rank whose GPU faults stops every
  // rank with its error (Distributed/RankFailure.h).
  std::unique_ptr<pbf::distributed::Communicator> Ranks;
  // Ranks when the live run is decomposed (its key has ranks > 1), null otherwise: the ranks that
  // sum the particles a probe or a solid's surface reads.
  pbf::distributed::Communicator* DecomposedRanks()
  {
    return this->Playback.key().ranks > 1 ? this->Ranks.get() : nullptr;
  }
  // The probes outside the domain last warned about (vtkPBFDescribeProbes), said once.
  std::string ProbesOutsideSaid;

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

  FrameRequest ParseRequest(const vtkPBFSettings& settings, vtkInformation* request,
    vtkInformationVector* outputVector) const;
  pbf::PlaybackKey MakeKey(const vtkPBFSettings& settings, vtkPointSet* input,
    const std::vector<vtkDataSet*>& obstacles, const FrameRequest& r);
  // Makes `key` the playback's and applies the checkpoint settings.
  void Adopt(const vtkPBFSettings& settings, const pbf::PlaybackKey& key);
  std::unique_ptr<pbf::Simulation> Build(const vtkPBFSettings& settings, const pbf::PlaybackKey& key,
    vtkPointSet* input, const std::vector<vtkDataSet*>& obstacles);
  // Hands the live simulation the Obstacles port's motion as seen up to this request (keyframes
  // past every frame it computed).
  void UpdateObstacleMotion(std::size_t connections);
  void OnDeviceFault(const vtkPBFSettings& settings, const pbf::DeviceFault& fault, int frame);
  // The frame's particles and field data on port 0, the diagnostics on port 1.
  void Deliver(const vtkPBFSettings& settings, const FrameRequest& r, const pbf::FrameReached& reached,
    vtkPolyData* output, vtkTable* table);
  void ReportAbort(const vtkPBFSettings& settings, const FrameRequest& r);
  // The surface of `particles` (port 0's output) into `surface` (port 3). Throws InvalidInput
  // for bad options.
  void DeliverSurface(
    const pbf::SurfaceOptions& options, vtkPolyData* particles, vtkPolyData* surface);
  // The surface mesh of the particles' arrays (one closed surface per liquid when liquids > 0,
  // meshLiquid saying whose each vertex is), made on the run's ranks, its GPU or the CPU.
  template <class Real>
  void ExtractMesh(vtkPolyData* particles, const pbf::Parameters& p,
    const pbf::SurfaceOptions& options, const pbf::SurfaceSolids& solids,
    const pbf::distributed::DecomposedStepper* decomposed, int liquids, pbf::SurfaceMesh& mesh,
    std::vector<unsigned char>& meshLiquid, std::string& device);
  // A CUDA run's surface on its GPU (Cuda/CudaSurface.h) into mesh, with the device's name; false
  // when the run is not on CUDA or the GPU failed (said once): the CPU makes it then.
  template <class Real>
  bool ExtractOnGpu(const pbf::Stepper& stepper, const pbf::Vec3<Real>* x, const pbf::Vec3<Real>* v,
    const Real* rho, std::size_t n, const pbf::Parameters& p, const pbf::SurfaceOptions& options,
    const pbf::SurfaceSolids& solids, pbf::SurfaceMesh& mesh, std::string& device);
  void DeliverAgain(const FrameRequest& r, vtkPolyData* output, vtkTable* table);
  void DeliverPrevious(vtkPolyData* output, vtkTable* table);
  vtkTable* DiagnosticsTable();
  std::string InUserTerms(const vtkPBFSettings& settings, const std::exception& error) const;
};

#endif
