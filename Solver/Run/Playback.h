// Frames of a Simulation, played in any order: frame k is the state at time k * frameInterval,
// and it is the same bit for bit however it is reached (the live simulation stepped on, the
// latest checkpoint at or before it, or the initial state), because the steps of a frame depend
// only on the state at its start. Checkpoints are taken every few frames within a memory budget
// (thinned evenly when over it); every frame reached gets one diagnostics row. A device fault
// leaves the checkpoints and rows (host copies) for the run to go on from on the CPU.
//
// This is the policy of the VTK algorithm (Filters/vtkPBFSimulation), without VTK: the algorithm
// turns pipeline requests into calls of this class and its results into VTK data. In a decomposed
// run every rank holds one Playback over the same communicator and calls it in step; the calls
// that say "collective" then talk to every rank.
#pragma once

#include "Parameters.h"
#include "Simulation.h"
#include "Stepper.h"

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace pbf
{
namespace distributed
{
class Communicator;
}

// Everything that decides the frames from the initial state: two equal keys have bit-identical
// frames, so the live simulation, the checkpoints and the rows of one serve the other. How many
// frames there are and the checkpoint settings are deliberately absent: they change no frame.
struct PlaybackKey
{
  std::string scene; // the preset's name, or a scene file's name and contents
  Parameters parameters;
  double frameInterval = 0; // [s]
  int substeps = 0;         // steps per frame with fixed time steps; 0 with automatic ones
  Backend backend = Backend::OpenMP;
  Precision precision = Precision::Single;
  bool hasInput = false;          // the fluid starts from given particles ...
  std::uint64_t inputVersion = 0; // ... of this version (the VTK input's modification time)
  int ranks = 1;                  // > 1: this rank's share of a decomposed run
  std::string obstacles;          // the solids given besides the scene's (and their versions)
};

// Field by field, so that a field added to Parameters and not here is noticed by the tests; a
// NaN never compares equal, which only costs a rebuild that then reports it.
bool sameParameters(const Parameters& a, const Parameters& b);
bool operator==(const PlaybackKey& a, const PlaybackKey& b);
inline bool operator!=(const PlaybackKey& a, const PlaybackKey& b)
{
  return !(a == b);
}

// One diagnostics row: the state at a frame and the steps that led to it from the frame before.
struct FrameRow
{
  double time = 0;                // [s]
  double averageDensityError = 0; // percent: mean of max(rho_i / rho_0 - 1, 0)
  double maxDensityError = 0;     // percent
  double averageNeighbors = 0;
  double solverIterations = 0;    // per step, averaged over the frame's steps (NaN at frame 0)
  double millisecondsPerStep = 0; // likewise
  double substeps = 0;            // the frame's solver steps (NaN at frame 0)
  double minTimeStep = 0;         // the smallest and largest of their dt [s] (NaN at frame 0)
  double maxTimeStep = 0;
  double maxSpeed = 0;      // [m/s]
  double kineticEnergy = 0; // [J]
  std::int64_t particles = 0;
  std::string backend;
  double loadImbalance = 0; // decomposed: the largest rank's particles over the mean - 1, percent
  // Per obstacle of the scene, then per mirror wall: the mean force the fluid pushed it with
  // over the frame's steps [N] and its torque about the obstacle's centre of mass (a wall's
  // middle) [N m] (their impulses over the frame's time); empty at frame 0, and the walls'
  // without Parameters::tankLoads.
  std::vector<SolidLoad> loads;
  std::vector<std::string> loadNames; // the obstacles' and walls' names (Simulation::loadName)
  // Per body the fluid moves (Simulation::bodies): where it is at the frame.
  struct BodyAt
  {
    std::string name;
    Vec3d centre;          // of mass [m]
    Rotation orientation;  // from its own frame (the scene's at the start)
    Vec3d velocity;        // [m/s]
    Vec3d angularVelocity; // [rad/s]
  };
  std::vector<BodyAt> bodies;
};

// What reaching a frame did.
struct FrameReached
{
  int frame = 0;
  std::string resumedFrom;         // "live", "checkpoint" or "initial"
  std::uint64_t resumedFromStep = 0;
  std::uint64_t steps = 0;         // solver steps taken for this request
  bool aborted = false;            // stopped within the way; the simulation is at a whole step
  double simulationMilliseconds = 0;
  double diagnosticsMilliseconds = 0;
  double checkpointMilliseconds = 0;
};

class Playback
{
public:
  // Builds the simulation at step 0 (the scene and the initial particles are read only then).
  using Build = std::function<std::unique_ptr<Simulation>()>;
  // Called after every solver step with the fraction of the way done; true asks to stop.
  using AfterStep = std::function<bool(double fraction)>;

  // `ranks`: the communicator of a decomposed run (keys with ranks > 1), or null.
  explicit Playback(distributed::Communicator* ranks = nullptr);
  ~Playback();
  Playback(const Playback&) = delete;
  Playback& operator=(const Playback&) = delete;

  void setRanks(distributed::Communicator* ranks) { ranks_ = ranks; }

  // Makes `key` current. What was computed for another key is dropped (the live simulation
  // first: two large simulations need not fit at once), except after a device fault that moved
  // the same run off the GPU: then only the backend differs and the checkpoints and rows stay.
  // Returns true when anything was dropped.
  bool adopt(const PlaybackKey& key);

  // Takes a checkpoint every `interval` frames (0: none, and those held are freed) within
  // `budgetBytes`; over it the interval doubles and the checkpoints off it are dropped until they
  // fit, the earliest always kept. Checkpoints already taken stay valid. Collective.
  void configureCheckpoints(int interval, std::size_t budgetBytes);

  // Steps to `frame` from the nearest of the live simulation and the checkpoints at or before
  // it, or from `build()` at step 0, recording a row (and a checkpoint when due) at every frame
  // passed. afterStep runs after every step; when it asks to stop (on any rank: collective), the
  // simulation stays at that whole step and the result says aborted. Throws what Simulation
  // throws; after a throw call dropLive() (the state may be half way through a step).
  FrameReached reach(int frame, const Build& build, const AfterStep& afterStep);

  // Forgets the live simulation (after a failed request); checkpoints and rows stay.
  void dropLive();

  // The GPU failed on the way to `frame`: the live simulation is gone, and the run may go on from
  // the checkpoints and rows, which are host copies. Returns where it would resume ("frame 8 (a
  // checkpoint)" or "the initial state"). With `fallBack` the key moves to OpenMP, and adopt()
  // of the same configuration on OpenMP keeps what was computed.
  std::string afterDeviceFault(int frame, bool fallBack);
  bool deviceFaulted() const { return deviceFaulted_; }

  bool hasKey() const { return hasKey_; }
  const PlaybackKey& key() const { return key_; }
  Simulation* live() { return live_.get(); }
  const Simulation* live() const { return live_.get(); }
  const std::map<int, FrameRow>& rows() const { return rows_; }
  // Changes whenever rows() does, so that a table built from them is rebuilt only then.
  std::uint64_t rowsVersion() const { return rowsVersion_; }
  std::vector<int> checkpointFrames() const;
  std::size_t checkpointBytes() const { return checkpointBytes_; }

  // The frame a simulation at `time` lands on next: k + 1 when it is on frame k (time k *
  // interval exactly) or between k and k + 1 (after an abort).
  static int nextFrame(double time, double interval);

private:
  void resetPending();
  void addPending(const AdvanceReport& report);
  void recordFrame(int frame, FrameReached& reached);
  void takeCheckpoint(int frame, FrameReached& reached);
  void fitBudget();
  double budgetedBytes();
  bool anyRank(bool mine);

  distributed::Communicator* ranks_ = nullptr;
  PlaybackKey key_;
  bool hasKey_ = false;
  bool deviceFaulted_ = false;
  std::unique_ptr<Simulation> live_;

  // The steps already taken towards the next frame of live_, so that its row counts every step
  // even when the frame was finished by a later request.
  long pendingIterations_ = 0;
  double pendingMilliseconds_ = 0;
  int pendingSteps_ = 0;
  double pendingMinTimeStep_ = 0;
  double pendingMaxTimeStep_ = 0;
  double pendingSeconds_ = 0;
  std::vector<SolidLoad> pendingImpulses_;

  std::map<int, SimulationCheckpoint> checkpoints_;
  std::size_t checkpointBytes_ = 0;
  std::size_t budgetBytes_ = 0;
  int requestedInterval_ = 0;
  int stride_ = 0; // the interval new checkpoints are taken at (doubled by each thinning)

  std::map<int, FrameRow> rows_;
  std::uint64_t rowsVersion_ = 0;
};

} // namespace pbf
