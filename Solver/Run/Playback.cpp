#include "Playback.h"

#include "Communicator.h"
#include "ParameterTable.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>

namespace pbf
{
namespace
{

double millisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
    .count();
}

bool sameBox(const Box& a, const Box& b)
{
  return a.min.x == b.min.x && a.min.y == b.min.y && a.min.z == b.min.z && a.max.x == b.max.x &&
    a.max.y == b.max.y && a.max.z == b.max.z;
}

const double NaN = std::numeric_limits<double>::quiet_NaN();

} // namespace

bool sameParameters(const Parameters& a, const Parameters& b)
{
  // The table's rows, then what the scene and the filter derive (ParameterTable.h).
  return sameTableParameters(a, b) && a.timeStepping == b.timeStepping &&
    a.sceneSpeedHint == b.sceneSpeedHint && sameBox(a.domain, b.domain);
}

bool operator==(const PlaybackKey& a, const PlaybackKey& b)
{
  return a.scene == b.scene && sameParameters(a.parameters, b.parameters) &&
    a.frameInterval == b.frameInterval && a.substeps == b.substeps && a.backend == b.backend &&
    a.precision == b.precision && a.hasInput == b.hasInput && a.inputVersion == b.inputVersion &&
    a.ranks == b.ranks && a.obstacles == b.obstacles;
}

Playback::Playback(distributed::Communicator* ranks)
  : ranks_(ranks)
{
}

Playback::~Playback() = default;

bool Playback::adopt(const PlaybackKey& key)
{
  if (hasKey_ && key_ == key)
  {
    return false;
  }
  // After a device fault, moving the same run off the GPU keeps its checkpoints and rows: they
  // are host copies, and losing them would lose the user's frames.
  if (hasKey_ && deviceFaulted_ && key_.backend == Backend::CUDA)
  {
    PlaybackKey moved = key_;
    moved.backend = key.backend;
    if (moved == key)
    {
      dropLive();
      key_ = moved;
      return true;
    }
  }
  dropLive();
  checkpoints_.clear();
  checkpointBytes_ = 0;
  stride_ = requestedInterval_;
  rows_.clear();
  ++rowsVersion_;
  deviceFaulted_ = false;
  key_ = key;
  hasKey_ = true;
  return true;
}

void Playback::configureCheckpoints(int interval, std::size_t budgetBytes)
{
  budgetBytes_ = budgetBytes;
  if (interval != requestedInterval_)
  {
    requestedInterval_ = interval;
    stride_ = interval;
  }
  if (interval <= 0)
  {
    checkpoints_.clear();
    checkpointBytes_ = 0;
    return;
  }
  fitBudget();
}

void Playback::dropLive()
{
  live_.reset();
  resetPending();
}

std::vector<int> Playback::checkpointFrames() const
{
  std::vector<int> frames;
  frames.reserve(checkpoints_.size());
  for (const auto& entry : checkpoints_)
  {
    frames.push_back(entry.first);
  }
  return frames;
}

int Playback::nextFrame(double time, double interval)
{
  int next = static_cast<int>(std::floor(time / interval));
  while (static_cast<double>(next + 1) * interval <= time)
  {
    ++next;
  }
  while (next > 0 && static_cast<double>(next) * interval > time)
  {
    --next;
  }
  return next + 1;
}

FrameReached Playback::reach(int frame, const Build& build, const AfterStep& afterStep)
{
  FrameReached reached;
  reached.frame = frame;
  const double interval = key_.frameInterval;
  // Frame k is at k * interval exactly: the simulation lands on it (Simulation::stepToward).
  const double target = static_cast<double>(frame) * interval;
  auto start = [&]() {
    dropLive();
    live_ = build();
    recordFrame(0, reached);
    takeCheckpoint(0, reached);
  };

  // Where to start: the live simulation when it is not past the frame, unless a checkpoint is
  // nearer; otherwise the latest checkpoint at or before the frame; otherwise step 0.
  reached.resumedFrom = "live";
  const SimulationCheckpoint* checkpoint = nullptr;
  auto after = checkpoints_.upper_bound(frame);
  if (after != checkpoints_.begin())
  {
    checkpoint = &std::prev(after)->second;
  }
  const bool liveUsable = live_ && live_->time() <= target;
  if (!(liveUsable && (!checkpoint || checkpoint->time <= live_->time())))
  {
    if (checkpoint)
    {
      if (!live_)
      {
        start();
      }
      live_->restore(*checkpoint);
      resetPending();
      reached.resumedFrom = "checkpoint";
    }
    else
    {
      start();
      reached.resumedFrom = "initial";
    }
  }
  Simulation& simulation = *live_;
  reached.resumedFromStep = simulation.stepCount();
  const double from = simulation.time();
  int next = nextFrame(from, interval);

  // Frame by frame, one solver step at a time: every way of reaching a frame takes the same
  // steps, and the caller hears after each one.
  const double total = target - from;
  while (simulation.time() < target)
  {
    AdvanceReport report;
    const bool landed = simulation.stepToward(static_cast<double>(next) * interval, report);
    addPending(report);
    reached.simulationMilliseconds += report.milliseconds;
    reached.steps += report.steps;
    if (landed)
    {
      recordFrame(next, reached);
      takeCheckpoint(next, reached);
      ++next;
    }
    bool stop = afterStep && afterStep((simulation.time() - from) / total) &&
      simulation.time() < target;
    if (key_.ranks > 1 && simulation.time() < target)
    {
      // A rank that left alone would leave the others waiting for it in the next step's
      // exchange: the ranks agree after every step, and any rank's stop stops them all at the
      // same step, so their slabs stay consistent and the next request resumes.
      stop = anyRank(stop);
    }
    if (stop)
    {
      reached.aborted = true;
      break;
    }
  }
  return reached;
}

std::string Playback::afterDeviceFault(int frame, bool fallBack)
{
  dropLive();
  deviceFaulted_ = true;
  auto kept = checkpoints_.upper_bound(frame);
  const std::string resumable = kept == checkpoints_.begin()
    ? std::string("the initial state")
    : "frame " + std::to_string(std::prev(kept)->first) + " (a checkpoint)";
  if (fallBack)
  {
    key_.backend = Backend::OpenMP;
  }
  return resumable;
}

void Playback::resetPending()
{
  pendingIterations_ = 0;
  pendingMilliseconds_ = 0;
  pendingSteps_ = 0;
  pendingMinTimeStep_ = 0;
  pendingMaxTimeStep_ = 0;
  pendingSeconds_ = 0;
  pendingImpulses_.clear();
}

void Playback::addPending(const AdvanceReport& report)
{
  if (report.steps == 0)
  {
    return;
  }
  pendingMinTimeStep_ = pendingSteps_ == 0 ? report.minTimeStep
                                           : std::min(pendingMinTimeStep_, report.minTimeStep);
  pendingMaxTimeStep_ = std::max(pendingMaxTimeStep_, report.maxTimeStep);
  pendingIterations_ += report.iterations;
  pendingMilliseconds_ += report.milliseconds;
  pendingSteps_ += static_cast<int>(report.steps);
  pendingSeconds_ += report.seconds;
  pendingImpulses_.resize(std::max(pendingImpulses_.size(), report.impulses.size()));
  for (std::size_t k = 0; k < report.impulses.size(); ++k)
  {
    pendingImpulses_[k].force += report.impulses[k].force;
    pendingImpulses_[k].torque += report.impulses[k].torque;
  }
}

// The row of the frame the live simulation has just reached. A frame computed again (after going
// back) keeps its first row: the same state, so only the timing could differ, and a plotted curve
// should not jitter while scrubbing.
void Playback::recordFrame(int frame, FrameReached& reached)
{
  if (rows_.count(frame))
  {
    resetPending();
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  const Stepper& stepper = live_->stepper();
  const Statistics statistics = stepper.statistics(); // collective in a decomposed run
  FrameRow row;
  row.time = live_->time();
  row.averageDensityError = 100.0 * statistics.averageDensityError;
  row.maxDensityError = 100.0 * statistics.maxDensityError;
  row.averageNeighbors = statistics.averageNeighbors;
  row.solverIterations = NaN;
  row.millisecondsPerStep = NaN;
  row.substeps = NaN;
  row.minTimeStep = NaN;
  row.maxTimeStep = NaN;
  if (pendingSteps_ > 0)
  {
    row.solverIterations = static_cast<double>(pendingIterations_) / pendingSteps_;
    row.millisecondsPerStep = pendingMilliseconds_ / pendingSteps_;
    row.substeps = pendingSteps_;
    row.minTimeStep = pendingMinTimeStep_;
    row.maxTimeStep = pendingMaxTimeStep_;
    for (const SolidLoad& impulse : pendingImpulses_)
    {
      row.loads.push_back(
        { impulse.force * (1.0 / pendingSeconds_), impulse.torque * (1.0 / pendingSeconds_) });
      row.loadNames.push_back(live_->loadName(row.loadNames.size()));
    }
  }
  row.maxSpeed = statistics.maxSpeed;
  row.kineticEnergy = statistics.kineticEnergy;
  row.particles = static_cast<std::int64_t>(statistics.particles);
  if (key_.ranks > 1 && ranks_)
  {
    // Collective, as statistics() is: every rank records the same frames.
    double largest = 0, total = 0;
    for (const std::vector<double>& r : distributed::allGather(*ranks_, { double(stepper.size()) }))
    {
      largest = std::max(largest, r[0]);
      total += r[0];
    }
    row.loadImbalance = total > 0 ? 100.0 * (largest * key_.ranks / total - 1.0) : 0.0;
  }
  row.backend = stepper.description();
  for (const Body& body : live_->bodies())
  {
    row.bodies.push_back({ live_->solidName(body.solid), body.state.centre,
      body.state.orientation, body.state.velocity, angularVelocity(body.state, body.mass) });
  }
  rows_[frame] = row;
  ++rowsVersion_;
  resetPending();
  reached.diagnosticsMilliseconds += millisecondsSince(start);
}

void Playback::takeCheckpoint(int frame, FrameReached& reached)
{
  if (stride_ <= 0 || frame % stride_ != 0 || checkpoints_.count(frame))
  {
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  SimulationCheckpoint checkpoint = live_->checkpoint();
  checkpointBytes_ += checkpoint.bytes();
  checkpoints_.emplace(frame, std::move(checkpoint));
  fitBudget();
  reached.checkpointMilliseconds += millisecondsSince(start);
}

// The bytes the budget is compared with. Decomposed, each rank holds its slab's share of a
// checkpoint, so the ranks would thin at different frames and resume from different ones (wrong
// particles, no error): the largest rank's bytes decide for every rank. Collective: every rank
// fits its budget at the same requests and frames.
double Playback::budgetedBytes()
{
  double largest = static_cast<double>(checkpointBytes_);
  if (key_.ranks > 1 && ranks_)
  {
    for (const std::vector<double>& r : distributed::allGather(*ranks_, { largest }))
    {
      largest = std::max(largest, r[0]);
    }
  }
  return largest;
}

// While over budget, double the interval and drop the checkpoints off it. The earliest
// checkpoint (frame 0 unless checkpoints were switched on late) always stays.
void Playback::fitBudget()
{
  while (checkpoints_.size() > 1 && budgetedBytes() > static_cast<double>(budgetBytes_))
  {
    stride_ *= 2;
    const int earliest = checkpoints_.begin()->first;
    for (auto it = checkpoints_.begin(); it != checkpoints_.end();)
    {
      if (it->first != earliest && it->first % stride_ != 0)
      {
        checkpointBytes_ -= it->second.bytes();
        it = checkpoints_.erase(it);
      }
      else
      {
        ++it;
      }
    }
  }
}

bool Playback::anyRank(bool mine)
{
  if (!ranks_)
  {
    return mine;
  }
  for (const std::vector<double>& theirs : distributed::allGather(*ranks_, { mine ? 1.0 : 0.0 }))
  {
    if (theirs[0] != 0.0)
    {
      return true;
    }
  }
  return false;
}

} // namespace pbf
