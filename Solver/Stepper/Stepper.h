// The backend seam: one interface for the serial, OpenMP and CUDA steppers. A stepper owns the
// particle state in its own memory (host or device) and advances it one solver step at a time.
#pragma once

#include "Parameters.h"
#include "Particles.h"
#include "SignedDistance.h"
#include "Vec3.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pbf
{

enum class Backend
{
  Serial, // the reference
  OpenMP, // bit-identical to Serial
  CUDA,
};

enum class Precision
{
  Single,
  Double,
};

const char* toString(Backend backend);
const char* toString(Precision precision);

// Measured on the current state; never feeds back into the simulation.
struct Statistics
{
  std::size_t particles = 0;
  double averageDensityError = 0; // mean of max(rho_i / rho_0 - 1, 0): compression only, since a
  double maxDensityError = 0;     // free-surface particle lacks neighbours, not mass
  double averageNeighbors = 0;    // neighbours within h, self excluded
  double maxSpeed = 0;
  double kineticEnergy = 0; // sum of m |v|^2 / 2 [J]
  Vec3d momentum{ 0, 0, 0 }; // sum of m v
  bool finite = true;        // no NaN or infinity in positions or velocities
};

// A cheap scan of the state for Simulation's divergence check: no neighbour search, nothing summed.
struct Health
{
  std::size_t nonFinite = 0;   // particles with a NaN or infinite position or velocity
  std::size_t outside = 0;     // particles farther than one spacing outside the domain
  double maxSpeed = 0;         // over the particles with finite velocities [m/s]
  // kRobustSpeedQuantile of the finite speeds (SpeedHistogram.h: rounded up to its bin, at most
  // 6.1 % above, never above maxSpeed) [m/s]: the automatic step's speed (nextTimeStep)
  double robustSpeed = 0;
  double maxDensityError = 0;  // max of rho_i / rho_0 - 1 at the last constraint evaluation
  std::int64_t firstBadId = -1; // the id of a particle counted above; -1: none, or not known
};

// Adaptive mode's measure of the constraint: mean and max over particles of
// max(rho_i / rho_0 - 1, 0), and whether a step may stop projecting there. With several liquids
// the mean is the largest of the liquids' means.
struct Compression
{
  double mean = 0;
  double max = 0;
  // Within the tolerances (Parameters::densityErrorTolerance, maxDensityErrorTolerance; percent).
  bool within(double meanTolerancePercent, double maxTolerancePercent) const
  {
    return mean <= meanTolerancePercent / 100.0 &&
      (maxTolerancePercent <= 0 || max <= maxTolerancePercent / 100.0);
  }
};

// What the last step() did.
// What the fluid pushes one solid with over a step: the mean force [N] and its torque about the
// world's origin [N m] (about a point c: torque - c x force).
struct SolidLoad
{
  Vec3d force{ 0, 0, 0 };
  Vec3d torque{ 0, 0, 0 };
};

struct StepReport
{
  int iterations = 0; // constraint projections applied
  // Adaptive mode: mean of max(rho_i / rho_0 - 1, 0) at the last evaluation, the one that ended
  // the loop. NaN in fixed mode, which computes no reduction inside a step (see statistics()).
  double densityError = 0;
  // One per solid obstacle, in the order of setObstacles, then with mirror walls one per wall of
  // the domain (-x, +x, -y, +y, -z, +z), over every rank; empty where the stepper has neither.
  // The GPU steppers sum the solids' loads only (no walls').
  std::vector<SolidLoad> loads;
};

class Stepper
{
public:
  virtual ~Stepper() = default;

  virtual void step() = 0; // one solver step of the current time step (setTimeStep)
  virtual void append(const ParticleBatch& batch) = 0;

  // The size of the steps that follow [s]; Parameters::timeStep until set. Simulation sets it
  // before every step when the time stepping is automatic. Throws InvalidInput for dt <= 0.
  // pressureElapsed [s]: the particles' pressure is a running mean over time (Equations.h's
  // recordPressure), and the next step joins a mean over that many seconds of steps before it;
  // 0 (the default) starts a new mean with it. Simulation sets it before every step.
  virtual void setTimeStep(double dt, double pressureElapsed = 0) = 0;
  virtual double timeStep() const = 0;

  virtual std::size_t size() const = 0;
  virtual Backend backend() const = 0;
  virtual Precision precision() const = 0;
  // Human-readable: the backend and where it runs ("OpenMP, 2 threads", "CUDA, NVIDIA H200").
  virtual std::string description() const = 0;

  // Copies the state to the host; the Snapshot of the other precision is converted.
  virtual void read(Snapshot<float>& out) const = 0;
  virtual void read(Snapshot<double>& out) const = 0;
  // As read(), into the caller's arrays: the VTK layer fills its output arrays without a Snapshot
  // in between. The default goes through read(); the CUDA backend copies straight into them.
  virtual void readInto(const SnapshotView<float>& out) const;
  virtual void readInto(const SnapshotView<double>& out) const;

  virtual Statistics statistics() const = 0;

  // The default derives it from statistics() (on CUDA a reduction on the device and a small copy
  // back): nonFinite is then 0 or 1 and outside 0 (the collision step keeps finite positions in
  // the box). The CPU stepper scans its arrays directly, well under 1% of a step.
  virtual Health health() const;

  virtual StepReport lastStep() const = 0;

  // Returns when the queued steps are done (a GPU queues them); a no-op on the CPU.
  virtual void synchronize() const {}

  // Replaces the whole state with a snapshot taken by read() of the same precision, in the same
  // order: the steps that follow are then bit-identical to those that followed the read. This is
  // what checkpoints restore. Throws InvalidInput for a snapshot of another precision or with
  // arrays of different lengths.
  virtual void load(const Snapshot<float>& state) = 0;
  virtual void load(const Snapshot<double>& state) = 0;

  // Removes the particles whose position lies in one of the boxes (the scene's outflows,
  // Physics/Outflow.h), keeping the others in their order; returns how many were removed, over
  // every rank of a decomposed run (collective there). Nothing else changes: the removed ids are
  // gone for good. The default, for a stepper without, throws InvalidInput naming the backend.
  virtual std::size_t removeOutflow(const std::vector<Box>& zones);

  // Solid obstacles the fluid flows around, as signed distance grids (Scene/SignedDistance.h,
  // Physics/Boundary.h), replacing any set before; part of the configuration like the
  // parameters. `poses` (none: every solid as sampled) places each solid now (SolidMotion.h):
  // the density and lambda at rest are evaluated with the solids there. Every stepper of the
  // solver has them; the default, for a stepper without, throws InvalidInput naming the backend.
  virtual void setObstacles(
    const std::vector<DistanceGrid>& obstacles, const std::vector<SolidPose>& poses = {});
  // Where the solids are at the end of the next step, one pose per solid: Simulation sets them
  // before every step of a scene whose solids move. Nothing is evaluated here; the steps that
  // follow read the solids there. Throws InvalidInput when the count differs from the solids'.
  virtual void setObstaclePoses(const std::vector<SolidPose>& poses);
};

// Throws InvalidInput naming the step when dt is not a positive finite number.
void checkTimeStep(double dt);

} // namespace pbf
