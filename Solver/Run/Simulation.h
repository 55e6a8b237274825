// A scene running on a stepper: owns the step count and the emitters, so that the state after
// step k depends only on (scene, parameters, backend, precision, k). The VTK algorithm and the
// command-line tools drive this.
#pragma once

#include "MassProperties.h"
#include "Parameters.h"
#include "BodyContact.h"
#include "FluidSource.h"
#include "RigidBody.h"
#include "Scene.h"
#include "SignedDistance.h"
#include "Stepper.h"
#include "SurfaceExtraction.h"

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>

namespace pbf
{
namespace distributed
{
class Communicator;
}

// The simulation blew up: the divergence check found, after step(), a particle that is not finite,
// has left the domain, or moves or is compressed beyond DivergenceLimits. what() says what, when
// and the likely cause. The state is the diverged one: restore a checkpoint or start again.
class SimulationDiverged : public std::runtime_error
{
public:
  SimulationDiverged(const std::string& what, std::uint64_t step, double time,
    std::uint64_t lastGoodStep, std::string cause)
    : std::runtime_error(what)
    , step_(step)
    , time_(time)
    , lastGoodStep_(lastGoodStep)
    , cause_(std::move(cause))
  {
  }
  std::uint64_t step() const { return step_; }         // the step after which it was found
  double time() const { return time_; }                // [s], the time of that step
  std::uint64_t lastGoodStep() const { return lastGoodStep_; } // the last step found sane
  const std::string& cause() const { return cause_; }  // the likely cause, also in what()

private:
  std::uint64_t step_;
  double time_;
  std::uint64_t lastGoodStep_;
  std::string cause_;
};

// What the divergence check tolerates, set from the scene and the parameters at construction.
// PBF clamps particles into the box, so a blow-up rarely shows as NaN: it shows as particles
// piled on a wall or corner (density many times rho_0) or jumping across the box in a step.
struct DivergenceLimits
{
  // [m/s] max(20 v_scene, 2 h / dt), v_scene = sqrt(v0^2 + 2 |g| L): the speed of a fall across
  // the domain's extent L along gravity, from the fastest initial or emitted speed v0. Measured:
  // the shipped scenes stay below 1.5 v_scene. (A blown-up run jumps wall to wall, at up to the
  // domain's diagonal / dt: 450 m/s in the dam break, so a laxer factor would never fire.)
  double maxSpeed = 0;
  double sceneSpeed = 0; // v_scene [m/s]
  // Largest rho_i / rho_0 - 1: density 3 x rho_0, or 3 x the initial largest density when the
  // initial particles are denser (given points). Measured: below 0.3 even with 1 iteration.
  double maxDensityError = 0;
};

// Everything a Simulation needs to resume exactly where it was.
struct SimulationCheckpoint
{
  std::uint64_t steps = 0;
  double time = 0; // [s]
  std::int64_t nextId = 0;
  std::uint64_t removed = 0; // particles gone through the outflows
  double pressureElapsed = 0; // [s] the steps the particles' pressure is a mean over so far
  std::vector<std::int64_t> layersEmitted;
  std::variant<Snapshot<float>, Snapshot<double>> state;
  // The bodies the fluid moves (Simulation::Body): their states and last loads.
  std::vector<RigidState> bodyStates;
  std::vector<SolidLoad> bodyLoads;

  std::size_t bytes() const; // host memory held
};

// What one advance() did.
struct AdvanceReport
{
  std::uint64_t steps = 0;
  long iterations = 0;       // constraint projections, summed over the steps
  double densityError = 0;   // adaptive mode: at the end of the last step; NaN in fixed mode
  double milliseconds = 0;   // wall time, the queued GPU work included
  double minTimeStep = 0;    // the smallest and largest dt of the steps [s]; 0 when none
  double maxTimeStep = 0;
  double seconds = 0;        // the simulated time the steps covered [s]
  std::uint64_t removed = 0; // particles that left through the scene's outflows
  // Per solid of the scene: the force its loads (StepReport::loads) gave over the steps, summed
  // as impulses, force dt [N s], and their torque about the solid's centre of mass (where it was
  // at each step's end) likewise [N m s]; empty where the stepper sums no loads.
  std::vector<SolidLoad> impulses;

  void add(const AdvanceReport& more); // the steps of `more` after these
};

// An obstacle of the scene with a density: the fluid moves it (two-way coupling). Each step
// first moves it by the previous step's load on it and gravity (RigidBody.h) and keeps it inside
// the tank (a rigid contact with each wall), so that the constraints see it where it is at the
// step's end, as they see a prescribed motion; the step's load on it (StepReport::loads, its
// torque about the body's centre) then moves it over the next.
struct Body
{
  std::size_t solid = 0; // its index among the scene's solids
  MassProperties mass;
  RigidState state;
  SolidLoad load;        // the last step's: force [N], torque about the centre [N m]
  double reach = 0;      // from its centre to the farthest corner of its bounds [m]
  ContactHull hull;      // what of it touches the tank's walls
};

class Simulation
{
public:
  // Throws InvalidInput for a bad scene or parameters, std::runtime_error when the backend is
  // unavailable. parameters.domain is replaced by the scene's.
  // With a communicator the run is one rank's share of a domain-decomposed run
  // (Distributed/SubdomainStepper.h): every rank constructs and advances its Simulation in step,
  // and the stepper holds this rank's particles (Backend::CUDA: on the GPU of the local rank).
  Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
    Precision precision, distributed::Communicator* communicator = nullptr);
  // The fluid starts from given particles (the VTK filter's input points) instead of the scene's
  // regions; the scene still gives the domain and emitters.
  Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
    Precision precision, const ParticleBatch& initial,
    distributed::Communicator* communicator = nullptr);
  // As above on one rank of a decomposed run whose given particles come in pieces: each rank
  // passes its own piece (what its part of a parallel pipeline holds), and the pieces in rank
  // order are the fluid, its order and its ids (Distributed/FluidPieces.h). No rank holds the
  // particles whole; each piece's particles go to the ranks that own them.
  struct InPieces
  {
  };
  Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
    Precision precision, const ParticleBatch& piece, distributed::Communicator& communicator,
    InPieces);

  // Throws SimulationDiverged from the divergence check; InvalidInput when emitted particles no
  // longer fit in the device's memory (the stepper keeps the particles it had); DeviceFault for a
  // GPU that fails. After any of them, restore a checkpoint (or start again) before stepping on.
  // `steps` solver steps of the size nextTimeStep() chooses, landing on no particular time.
  // The particles' pressure (Snapshot::pressure) is then the last step's, as the state after
  // step k does not depend on how the steps were split into calls.
  AdvanceReport advance(std::uint64_t steps);

  // Steps until time() is `until` exactly (the time of an output frame): each step is the one
  // nextTimeStep() chooses, shortened so that a whole number of them ends on `until`. The sizes
  // follow from the state alone, so a run frame by frame is the same bit for bit however it is
  // split into calls, resumed or repeated. Nothing happens when time() >= until.
  // The particles' pressure is then their mean over the frame's steps, each weighed by its dt
  // (the steps since the last landing on a frame's time, or since the last advance()), so that
  // a frame's pressure (and the surface pressure and probes read from it) does not flicker with
  // its last step's corrections. Density, lambda and velocity are the last step's.
  AdvanceReport advanceTo(double until);
  // One step of advanceTo(until); returns true when time() has reached `until`. For callers that
  // must be able to stop within a frame (the VTK filter's abort).
  bool stepToward(double until, AdvanceReport& report);

  // The size of the next step [s] when nothing has to be landed on: Parameters::timeStep when
  // fixed; when automatic, the smallest of
  //   timeStep (the largest step),
  //   kFastestStepSpacings s / v_max: the fastest particle moves at most a spacing (cflNumber
  //     spacings in a scene with solids, which a prediction could otherwise cross),
  //   cflNumber s / max(v_robust, v_scene): all but a thousandth of the particles move at most
  //     cflNumber spacings (Health::robustSpeed, the 99.9th percentile: a few fast spray
  //     particles no longer set the step of the whole fluid; Performance.md measures it). v_scene
  //     = sqrt(v0^2 + 2 |g| L), the speed of a fall across the domain (DivergenceLimits), is a
  //     floor, as weakly compressible SPH bounds its step by a speed of sound: PBF's compression
  //     in a column of depth H after k projections grows as |g| dt^2 H / (k s^2), and with dt
  //     proportional to s / v_scene it is the same at every spacing and depth,
  //   cflNumber sqrt(s / |g|): gravity moves a resting particle at most cflNumber^2 spacings,
  //   kMaxXsphBlend beta h^2 / (nu + nu_4): explicit XSPH smoothing stays stable.
  // The spacings the fastest particle may move in a step: h / 2 at the default ratio, so that it
  // crosses at most half a neighbour's reach while the rest move cflNumber spacings.
  static constexpr double kFastestStepSpacings = 1.0;
  // The smallest step it may choose [s]: below it single precision's 1 / dt and dt^2 lose their
  // meaning, and no physical scene needs it. At construction a smaller step is InvalidInput
  // naming the parameter that forces it; later, SimulationDiverged.
  static constexpr double kSmallestTimeStep = 1e-30;
  double nextTimeStep() const;

  // The divergence check runs after every `steps`-th step, counted from step 0, so it falls on
  // the same steps however advance() is called, and at the end of every advanceTo(); it scans the
  // particles (Stepper::health) and throws SimulationDiverged at the first step that breaks a
  // limit. 0 leaves only the check at the end of advanceTo. Default: every step, except for
  // CUDA with fixed time steps, where the scan's copy back would stall the queued steps (it still
  // runs when advanceTo lands, once per frame for the VTK filter). With automatic time steps the
  // scan runs every step anyway: it gives the fastest particle.
  void setDivergenceCheckInterval(std::uint64_t steps) { checkInterval_ = steps; }
  std::uint64_t divergenceCheckInterval() const { return checkInterval_; }
  const DivergenceLimits& divergenceLimits() const { return limits_; }
  // Runs the check now, whatever the interval.
  void checkDivergence();

  // A copy of the whole state; restore() continues bit-identically from it. The checkpoint must
  // come from a Simulation of the same scene, parameters and precision.
  SimulationCheckpoint checkpoint() const;
  void restore(const SimulationCheckpoint& checkpoint);

  // Replaces how solid `solid` of the scene moves from now on (its pivot given). The steps
  // already taken stay as they were, so the new motion must agree with the old one up to time():
  // the VTK filter appends the keyframes it observes on its Obstacles input as frames are asked.
  // Throws InvalidInput for a bad motion or index.
  void setSolidMotion(std::size_t solid, SolidMotion motion);
  const std::vector<SolidMotion>& solidMotions() const { return motions_; }
  // The solids where they stand at `time`, to clip the fluid's surface with (views of this
  // simulation's fields: valid while it lives).
  SurfaceSolids surfaceSolids(double time) const;

  // What errors and tables call solid k: its name, or "obstacles[k]".
  std::string solidName(std::size_t k) const;
  // What the loads' columns call load k (StepReport::loads): solid k's name, then the mirror
  // walls "tank -x", "tank +x", "tank -y" (the floor), "tank +y", "tank -z", "tank +z".
  std::string loadName(std::size_t k) const;
  const std::vector<Body>& bodies() const { return bodies_; }
  // Where every solid is at `time`: a prescribed one by its keyframes, a body where its state
  // has it now; empty when none moves (each stands where its field was made).
  std::vector<SolidPose> solidPoses(double time) const;

  // Initial particles that lay inside a solid obstacle of the scene and were removed.
  std::size_t seededInsideSolids() const { return seededInsideSolids_; }

  std::uint64_t stepCount() const { return steps_; }
  // Ids run 0..idCount()-1: the initial particles and every one an emitter has released. An id
  // that left through an outflow is never given again.
  std::int64_t idCount() const { return nextId_; }
  // The particles that left through the scene's outflows since step 0 (over every rank).
  std::uint64_t removedCount() const { return removed_; }
  // The outflows as the stepper removes by them (outflowZones of the scene at the parameters).
  const std::vector<Box>& outflowZones() const { return outflowZones_; }
  double time() const { return time_; }
  const Parameters& parameters() const { return parameters_; }
  const Scene& scene() const { return scene_; }
  Stepper& stepper() { return *stepper_; }
  const Stepper& stepper() const { return *stepper_; }

private:
  void stepOnce(double dt, double end, AdvanceReport& report); // `end`: time() after it
  // The scene's obstacles with a density (InvalidInput naming one that cannot be a body).
  void makeBodies();
  // The bodies over a step of dt to `end` by their last loads and gravity, kept apart from each
  // other and the other solids (where they are at `end`) and inside the tank.
  void moveBodies(double dt, double end);
  // Solid k for BodyContact.h at `poses` (solidPoses or empty: as sampled).
  ContactSide contactSide(std::size_t k, const std::vector<SolidPose>& poses);
  // InvalidInput naming a body that starts through a wall of the tank or inside another solid.
  void checkBodiesStartApart();
  // A step's loads (StepReport::loads) into the report's impulses and the bodies' last loads.
  void addLoads(const std::vector<SolidLoad>& loads, const std::vector<SolidPose>& poses,
    double dt, AdvanceReport& report);
  double checkedTimeStep() const; // nextTimeStep(), or SimulationDiverged below the smallest
  void emit();
  void checkEmitters(std::size_t initialParticles) const;
  // InvalidInput naming an outflow that holds the whole fluid, or an emitter whose layers would
  // be released inside one.
  void checkOutflows(const FluidSource& initial, std::size_t count) const;
  // given: the initial particles, or null for the scene's regions.
  Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
    Precision precision, const ParticleBatch* given, bool givenInPieces,
    distributed::Communicator* communicator);
  // The constructor's steps after the initial fluid, in their order: the emitters' speeds at the
  // spacing and the outflow zones, checked against the fluid (`count` particles over every
  // rank); the stepper on it (`whole`: the particles this process holds), with the solids where
  // they stand at t = 0; the limits of the steps and of the divergence check.
  void setUpFlows(const FluidSource& initial, std::size_t count);
  void startStepper(Backend backend, Precision precision, distributed::Communicator* communicator,
    const FluidSource& initial, const ParticleBatch& whole,
    const std::vector<DistanceGrid>& solids, const std::vector<SolidPose>& poses);
  void setLimits(Backend backend, double sceneSpeed, double v0);
  // Throws InvalidInput when the scene's speed, gravity or XSPH force an automatic step below
  // the smallest one (the constructor's check).
  void checkAutomaticStep(double sceneSpeed, double v0) const;
  std::string likelyCause() const;

  Scene scene_;
  Parameters parameters_;
  std::unique_ptr<Stepper> stepper_;
  std::uint64_t steps_ = 0;
  double time_ = 0;
  // The health scan of the current state (Stepper::health): the fastest particle for the next
  // automatic step. Valid when healthValid_.
  Health health_;
  bool healthValid_ = false;
  // cflNumber sqrt(rho s^3 / sigma) [s] over the liquids (capillaryStepLimit); infinity without
  // surface tension.
  double capillaryStepLimit_ = 0;
  static double capillaryStepLimit(const Parameters& p);
  double xsphStepLimit_ = 0; // kMaxXsphBlend beta h^2 / (nu + nu_4) [s]; infinity without XSPH
  std::int64_t nextId_ = 0;
  std::uint64_t removed_ = 0;
  // [s] the steps the particles' pressure is a mean over so far: 0 after a landing (advanceTo)
  // and in advance(), so that the next step starts a new mean. stepperElapsed_ is what the
  // stepper was last given (NaN: not known, after a restore).
  double pressureElapsed_ = 0;
  double stepperElapsed_ = 0;
  std::vector<Box> outflowZones_;
  std::vector<Vec3d> solidCentres_; // per solid, its centre of mass in its own frame
  std::vector<Body> bodies_;
  std::vector<std::int64_t> layersEmitted_; // per emitter
  DivergenceLimits limits_;
  std::uint64_t checkInterval_ = 1;
  std::size_t seededInsideSolids_ = 0;
  double fastestSolidPoint() const; // [m/s], a floor of the automatic step's speed
  std::vector<SolidMotion> motions_; // per solid of the scene, pivots given
  std::vector<DistanceGrid> solidFields_; // per solid, as the stepper was given them
  std::vector<double> solidReach_;   // per solid: its farthest point from its pivot [m]
  // With bodies, per solid: what of it touches another, and its bounds' centre and half
  // diagonal (as sampled), for the contacts between solids.
  std::vector<ContactHull> hulls_;
  std::vector<Box> bounds_;
  std::uint64_t lastGoodStep_ = 0;
  double lastGoodSpeed_ = 0; // max speed at lastGoodStep_; NaN when not known (after restore)
};

} // namespace pbf
