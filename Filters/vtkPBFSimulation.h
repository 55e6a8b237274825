/**
 * @class   vtkPBFSimulation
 * @brief   Position Based Fluids (Macklin and Mueller 2013) as a time-aware VTK source or filter.
 *
 * vtkPBFSimulation runs the project's PBF solver and outputs the particles of one animation frame
 * as a vtkPolyData: one vertex cell per particle, point arrays `density` [kg/m^3], `lambda`,
 * `velocity` [m/s] (also the active scalars and vectors, so that views color by its magnitude)
 * and `id` (the particle's stable id, also the GlobalIds), and field data holding every parameter
 * that produced the frame (enough to recompute the density independently).
 *
 * Where the fluid is comes from a scene: a preset compiled into the solver (see Preset) or a scene
 * JSON file (SceneFile, which wins when not empty). How the fluid behaves comes from this
 * algorithm's properties, whatever the scene says; their defaults are pbf::Parameters' defaults.
 *
 * As a filter (optional input port 0, any vtkPointSet), the input's points replace the scene's
 * fluid regions: point i becomes particle i, with the initial velocity of a 3-component point
 * array named `velocity` when the input has one (so a frame of this algorithm can seed another),
 * zero otherwise. The scene's emitters still run, and the scene still gives the domain box, so
 * that one scene can be seeded with different shapes; a point farther than one ParticleSpacing
 * outside the domain is an error naming the point. The input is read at its first time step.
 *
 * Time: frame k is at time k * FrameInterval exactly, for k = 0..NumberOfFrames. With
 * TimeStepping Automatic (the default) the solver's steps follow the CFL condition
 * (pbf::Simulation::nextTimeStep: CFLNumber spacings per step at the fastest particle or the
 * scene's fall speed, at most MaxTimeStep), and each frame takes a whole number of them, chosen
 * from the state at each step, so that it ends on its time; with Fixed, every frame is
 * SubstepsPerFrame steps of FrameInterval / SubstepsPerFrame. A request is answered with the
 * nearest frame. Any frame, asked in any order, is bit-identical to
 * a run straight to it, whichever way it is reached: the frame just delivered is handed out again
 * without stepping or copying; a later frame steps the live simulation on; an earlier one resumes
 * from the latest checkpoint at or before it (see CheckpointInterval), or from the initial state
 * when there is none. Anything that shapes the motion (a physics property, the time step, the
 * scene or its file's contents, the input, the backend or the precision) invalidates the live
 * simulation, the checkpoints and the diagnostics; NumberOfFrames, the checkpoint settings and
 * display properties do not.
 *
 * Long requests report progress (UpdateProgress after every solver step) and honour
 * AbortExecute, checked after every solver step: an aborted request outputs the previous frame
 * (with its own time and Frame) and the diagnostics of the frames completed so far, keeps the
 * live simulation at the last whole step (a valid state that the next request steps on from,
 * never mistaken for a frame) and succeeds. As in VTK, AbortExecute stays set until whoever set
 * it clears it; SetAbortExecute(0) also marks the algorithm modified, so that the same time asked
 * again is computed.
 *
 * Output port 1 is a vtkTable of diagnostics, one row per frame computed so far (frames 0 to the
 * furthest computed, in order; a frame computed again keeps its first row; all are replaced when
 * the physics change): Time, Frame, AverageDensityError and MaxDensityError [%] (mean and
 * maximum of max(rho_i / rho_0 - 1, 0)), AverageNeighbors, SolverIterations (constraint
 * projections per step, averaged over the frame's substeps), MillisecondsPerStep (wall time of
 * the frame's solver steps per step, queued GPU work included), Substeps (the frame's solver
 * steps), MinTimeStep and MaxTimeStep [s] (the smallest and largest of their dt), MaxSpeed [m/s],
 * KineticEnergy [J], Particles and Backend. Frame 0 took no step: its SolverIterations,
 * MillisecondsPerStep, Substeps and time steps are NaN.
 *
 * Parallel runs (mpiexec pvbatch, pvserver with N ranks): with DecomposeAcrossRanks on (the
 * default) and one piece per rank of the global vtkMultiProcessController, each rank simulates a
 * slab of the fluid along x plus ghost particles, exchanged every solver iteration
 * (Solver/Distributed), on the CPU backends; it outputs its own particles, whose ids stay
 * globally unique, and field data Rank, Ranks and ParticlesPerRank. Diagnostics are reduced over
 * the ranks, with a LoadImbalance column (the largest rank's particles over the mean, minus 1, in
 * %), and rank 0 outputs the table. Every rank must take part in every request, as
 * ParaView's parallel engine does. With it off, piece 0 simulates the whole fluid and other pieces
 * are empty. As a filter it asks its input for the whole data set on every rank.
 *
 * Output port 2 is the outline of the scene's domain (a vtkPolyData of 12 lines, field data
 * Scene) with every solid drawn where it stands at the frame and a point array `pressure` [Pa]
 * (what the particles press on it, their pressure's mean over the frame's steps), on rank 0
 * only: shown beside the particles, it makes a view frame the whole tank from frame 0 on, where
 * frame 0's particles may fill only a corner of it.
 *
 * Probes: the points of the dataset on input port 2 (optional: a Line or Point Source, a CSV of
 * gauge positions through Table To Points; SetInputConnection(2, ...)), read at every frame's
 * time. Output port 4 is a vtkTable with a row per probe: Probe (its index), Position, velocity
 * [m/s] and pressure [Pa] (the frame's mean) interpolated from the particles, WaterHeight [m]
 * (the wetted length above the probe along +y: on the floor, a wave gauge) and FluidFraction
 * (1 inside the fluid, about 1/2 at a wall or the free surface, 0 in air); Solver/Surface/Probes.h
 * says how. A probe outside the domain reads NaN, with a warning naming it; the run goes on.
 * Probes never change the simulation.
 *
 * Errors (a bad scene or parameter, an empty input, a NaN coordinate, an unavailable backend) are
 * reported with vtkErrorMacro naming the property (its GUI label) and the value as set (the
 * setters do not clamp: a clamped value would be reported as one the user never typed); the
 * request then fails and the previous output is kept.
 */

#ifndef vtkPBFSimulation_h
#define vtkPBFSimulation_h

#include "PBFFiltersModule.h" // For export macro
#include "vtkPolyDataAlgorithm.h"

#include <memory> // For std::unique_ptr
#include <string> // For std::string

class vtkPBFSimulationInternals;
struct vtkPBFSettings;

class PBFFILTERS_EXPORT vtkPBFSimulation : public vtkPolyDataAlgorithm
{
public:
  static vtkPBFSimulation* New();
  vtkTypeMacro(vtkPBFSimulation, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /**
   * The scenes compiled into the solver; the names are those of pbf::presetScene (the files in
   * Data/ without ".json").
   */
  enum PresetScenes
  {
    PRESET_DAM_BREAK = 0,
    PRESET_DOUBLE_DAM_BREAK = 1,
    PRESET_BLOB = 2,
    PRESET_STREAM = 3,
    PRESET_MARIN_DAM_BREAK = 4,
    PRESET_CHANNEL = 5
  };

  // The values of pbf::BackendRequest (Solver/Backends/BackendChoice.h).
  enum Backends
  {
    BACKEND_AUTO = 0, // CUDA when a device is present, else OpenMP, said once
    BACKEND_CUDA = 1,
    BACKEND_OPENMP = 2,
    BACKEND_SERIAL = 3
  };

  enum TimeSteppings
  {
    TIME_STEPPING_FIXED = 0,     // SubstepsPerFrame equal steps per frame
    TIME_STEPPING_AUTOMATIC = 1, // CFL-limited steps, at most MaxTimeStep, landing on each frame
  };

  enum Precisions
  {
    PRECISION_SINGLE = 0,
    PRECISION_DOUBLE = 1
  };

  ///@{
  /**
   * The preset scene used when SceneFile is empty. Default PRESET_DAM_BREAK.
   */
  vtkSetClampMacro(Preset, int, PRESET_DAM_BREAK, PRESET_CHANNEL);
  vtkGetMacro(Preset, int);
  ///@}

  /**
   * The pbf::presetScene name of Preset, e.g. "dam_break".
   */
  const char* GetPresetName() const;

  ///@{
  /**
   * A scene JSON file (schema in Data/README.md). Empty (the default) uses Preset.
   */
  vtkSetFilePathMacro(SceneFile);
  vtkGetFilePathMacro(SceneFile);
  ///@}

  ///@{
  /**
   * The physics parameters, by the property names of the parameter table
   * (Solver/Physics/ParameterTable.h: RestDensity, ParticleSpacing, SmoothingRatio,
   * SolverIterations, DensityErrorTolerance, ..., Gravity, CFLNumber, MaxTimeStep), from which
   * the proxy XML is generated; their meanings, units and defaults are the table's, the
   * defaults those of pbf::Parameters. Values are taken as given, not clamped: the solver's
   * checks name a value out of its range when the next request runs. An unknown name, or three
   * components for a scalar (one for Gravity), is an error and changes nothing.
   * DensityErrorTolerance applies with AdaptiveIterations on; CFLNumber and MaxTimeStep with
   * TimeStepping Automatic.
   */
  void SetParameter(const char* name, double value);
  void SetParameter(const char* name, int value);
  void SetParameter(const char* name, double x, double y, double z);
  double GetParameter(const char* name, int component = 0);
  ///@}

  ///@{
  /**
   * Obstacles: the datasets on input port 1 (optional, repeatable: AddInputConnection(1, ...))
   * are solids the fluid flows around, each taken as the surface that bounds it (see
   * vtkPBFObstacles.h); they are read at their first time step. A surface that is not closed is
   * an error unless ObstacleThickness [m] (default 0) makes it a thin shell of that thickness.
   * RemoveAllObstacles() empties the port (the server manager's clean command).
   */
  vtkSetMacro(ObstacleThickness, double);
  vtkGetMacro(ObstacleThickness, double);
  void RemoveAllObstacles();
  ///@}

  ///@{
  /**
   * Surface (output port 3): the fluid's surface as triangles with Normals, velocity and density
   * (pbf::extractSurface: the level SurfaceIsoValue, default 0.5, of the SPH colour function,
   * sampled every SurfaceResolution spacings, default 0.5, on a narrow band around the particles,
   * then SurfaceSmoothing Laplacian passes, default 0; SurfaceAnisotropic: Yu & Turk's
   * anisotropic kernels, flatter water, default off), from the same frame as the particles. A
   * CUDA run makes it on its GPU (the same mesh).
   * Computed when something downstream asks for port 3 (its eye in the GUI, a Show of
   * OutputPort 3, a filter, a writer or a Fetch), for the frame asked, and not otherwise: a run
   * that never shows the surface spends nothing on it, and a proxy's UpdatePipeline (Apply)
   * alone does not make it (vtkPBFPortDemand.h). GenerateSurface (default off) makes it with
   * every frame all the same, for scripts that read the algorithm's port 3 directly. Changing a
   * surface property recomputes only the surface.
   */
  vtkSetMacro(GenerateSurface, bool);
  vtkGetMacro(GenerateSurface, bool);
  vtkBooleanMacro(GenerateSurface, bool);
  vtkSetMacro(SurfaceResolution, double);
  vtkGetMacro(SurfaceResolution, double);
  vtkSetMacro(SurfaceIsoValue, double);
  vtkGetMacro(SurfaceIsoValue, double);
  vtkSetMacro(SurfaceSmoothing, int);
  vtkGetMacro(SurfaceSmoothing, int);
  vtkSetMacro(SurfaceAnisotropic, bool);
  vtkGetMacro(SurfaceAnisotropic, bool);
  vtkBooleanMacro(SurfaceAnisotropic, bool);
  ///@}

  ///@{
  /**
   * Time: the interval between animation frames [s] (default 1/60), how the solver's step is
   * chosen (TimeStepping: TIME_STEPPING_AUTOMATIC, the default, or TIME_STEPPING_FIXED; for
   * Automatic the parameters CFLNumber and MaxTimeStep apply), for Fixed the solver steps
   * per frame (default 4, so the solver's time step is FrameInterval / SubstepsPerFrame), and the
   * number of frames after the initial one (default 120).
   */
  vtkSetClampMacro(TimeStepping, int, TIME_STEPPING_FIXED, TIME_STEPPING_AUTOMATIC);
  vtkGetMacro(TimeStepping, int);
  vtkSetMacro(FrameInterval, double);
  vtkGetMacro(FrameInterval, double);
  vtkSetMacro(SubstepsPerFrame, int);
  vtkGetMacro(SubstepsPerFrame, int);
  vtkSetMacro(NumberOfFrames, int);
  vtkGetMacro(NumberOfFrames, int);
  ///@}

  ///@{
  /**
   * Adaptive iterations: when on, a solver step stops projecting the density constraint as soon
   * as the mean compression max(rho_i / rho_0 - 1, 0) is at or below the parameter
   * DensityErrorTolerance [percent] after the first projection (and no particle is compressed by
   * more than MaxDensityErrorTolerance), and SolverIterations becomes the most it may take. On by
   * default; off: always SolverIterations projections per step.
   */
  vtkSetMacro(AdaptiveIterations, bool);
  vtkGetMacro(AdaptiveIterations, bool);
  vtkBooleanMacro(AdaptiveIterations, bool);
  ///@}

  ///@{
  /**
   * Checkpoints: a copy of the solver state (in host memory) is kept every CheckpointInterval
   * frames (default 10; 0 keeps none and frees those held), so that an earlier frame resumes from
   * the latest checkpoint at or before it instead of from the initial state. CheckpointMemoryMB
   * (default 1024) bounds the memory they hold: past it, the interval doubles and the checkpoints
   * off the doubled interval are dropped, until they fit, so the survivors stay evenly spread;
   * frame 0 (the earliest held) is always kept. Neither setting changes a frame.
   */
  vtkSetClampMacro(CheckpointInterval, int, 0, 1000000);
  vtkGetMacro(CheckpointInterval, int);
  vtkSetClampMacro(CheckpointMemoryMB, double, 0.0, 1e9);
  vtkGetMacro(CheckpointMemoryMB, double);
  ///@}

  ///@{
  /**
   * Where the solver runs: BACKEND_AUTO (the default) takes CUDA when pbf::cudaAvailable() and
   * OpenMP otherwise, saying so once; BACKEND_CUDA without a device is an error naming the
   * reason. Precision is that of the solver's state and of the output arrays. A GPU that fails
   * mid-run (a lost device, a kernel that faults) ends CUDA for this filter: with BACKEND_AUTO
   * the request goes on on the CPU from the latest checkpoint, with a warning that the frames
   * from then on also carry as field data "DeviceFault"; with BACKEND_CUDA the request fails
   * with an error saying how to go on, and the previous output and the checkpoints stay.
   */
  vtkSetClampMacro(Backend, int, BACKEND_AUTO, BACKEND_SERIAL);
  vtkGetMacro(Backend, int);
  vtkSetClampMacro(Precision, int, PRECISION_SINGLE, PRECISION_DOUBLE);
  vtkGetMacro(Precision, int);
  ///@}

  ///@{
  /**
   * Split the fluid over the ranks of a parallel run (see the class documentation); default on.
   */
  vtkSetMacro(DecomposeAcrossRanks, bool);
  vtkGetMacro(DecomposeAcrossRanks, bool);
  vtkBooleanMacro(DecomposeAcrossRanks, bool);
  ///@}

  ///@{
  /**
   * With the CUDA backend, put the output arrays in page-locked host memory, which the GPU copies
   * into at the full bus speed (ordinary memory is staged by the driver); default on. Memory
   * released by the arrays is pooled for the next frames, and past 1 GiB in use the arrays fall
   * back to ordinary memory. Not a ParaView property: Testing/Pipeline's driver compares both.
   */
  vtkSetMacro(PageLockedOutput, bool);
  vtkGetMacro(PageLockedOutput, bool);
  vtkBooleanMacro(PageLockedOutput, bool);
  ///@}

  ///@{
  /**
   * What the last request cost, for tools that time the pipeline (Testing/Pipeline): the wall
   * time of its solver steps as pbf::Simulation::advance reports it (GPU work included), of the
   * diagnostics (Stepper::statistics, once per frame stepped through), of the checkpoints taken
   * and of the delivery (copying the particles back and building the output arrays), in
   * milliseconds, and the solver steps it took. All 0 for a request answered without stepping.
   */
  double GetLastSimulationMilliseconds() const;
  double GetLastDiagnosticsMilliseconds() const;
  double GetLastCheckpointMilliseconds() const;
  double GetLastDeliveryMilliseconds() const;
  vtkIdType GetLastRequestSteps() const;
  ///@}

protected:
  vtkPBFSimulation();
  ~vtkPBFSimulation() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  // Answers REQUEST_DATA_NOT_GENERATED with the outputs this execution leaves as they are.
  vtkTypeBool ProcessRequest(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  // The surface's port is newer than anything while its consumers hold a stale surface, so that
  // the next request through it executes this algorithm again.
  int ComputePipelineMTime(vtkInformation* request, vtkInformationVector** inInfoVec,
    vtkInformationVector* outInfoVec, int requestFromOutputPort, vtkMTimeType* mtime) override;
  // The particles and diagnostics of the requested frame (ports 0 and 1).
  int RequestFrame(vtkInformation*, vtkInformationVector**, vtkInformationVector*);
  // The domain's outline (port 2), from the simulation just run.
  void RequestDomain(vtkInformationVector* outputVector);
  // The surface of the particles on port 0 (port 3). Returns 0 after an error (the previous
  // surface stays).
  int RequestSurface(vtkInformationVector* outputVector);
  // The Probes table (port 4) of the Probes input's points (port 2), read from port 0's particles.
  void RequestProbes(vtkInformationVector** inputVector, vtkInformationVector* outputVector);
  // SetParameter's work: `count` components of the named parameter.
  void SetParameterComponents(const char* name, int count, const double* values);
  // What is wrong with FrameInterval, NumberOfFrames, SubstepsPerFrame or MaxTimeStep, in the
  // GUI's words and the value typed; empty when nothing is.
  std::string InvalidTimeProperty() const;

  /**
   * The frame answering a requested time: the nearest one, clamped to 0..NumberOfFrames.
   */
  int FrameForTime(double time) const;

  int Preset;
  char* SceneFile;

  double ObstacleThickness;
  bool GenerateSurface;
  double SurfaceResolution;
  double SurfaceIsoValue;
  int SurfaceSmoothing;
  bool SurfaceAnisotropic;
  bool AdaptiveIterations;

  double FrameInterval;
  int SubstepsPerFrame;
  int TimeStepping;
  int NumberOfFrames;

  int CheckpointInterval;
  double CheckpointMemoryMB;
  bool PageLockedOutput;
  bool DecomposeAcrossRanks;

  int Backend;
  int Precision;

private:
  vtkPBFSimulation(const vtkPBFSimulation&) = delete;
  void operator=(const vtkPBFSimulation&) = delete;

  // What the internals need of this algorithm's properties, made at each request.
  vtkPBFSettings Settings() const;

  // The live simulation, its checkpoints and diagnostics and the last good output; solver types
  // stay in the .cxx.
  std::unique_ptr<vtkPBFSimulationInternals> Internals;
};

#endif
