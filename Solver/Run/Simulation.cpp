#include "Simulation.h"

#include "MassProperties.h"
#include "Outflow.h"

#include "Backends.h"
#include "ParticleChecks.h"
#include "SceneFluid.h"

#include "Distributed/FluidPieces.h"
#include "Distributed/SubdomainStepper.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace pbf
{
namespace
{

std::string number(double value)
{
  std::ostringstream out;
  out.precision(3);
  out << value;
  return out.str();
}

bool inside(const Vec3d& lo, const Vec3d& hi, const Box& box, double slack)
{
  // Written so that NaN fails.
  return lo.x >= box.min.x - slack && lo.y >= box.min.y - slack && lo.z >= box.min.z - slack &&
    hi.x <= box.max.x + slack && hi.y <= box.max.y + slack && hi.z <= box.max.z + slack;
}

// The extent of the box along the unit vector u.
double extentAlong(const Box& box, const Vec3d& u)
{
  return std::abs(u.x) * (box.max.x - box.min.x) + std::abs(u.y) * (box.max.y - box.min.y) +
    std::abs(u.z) * (box.max.z - box.min.z);
}

} // namespace

Simulation::Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
  Precision precision, distributed::Communicator* communicator)
  : Simulation(scene, parameters, backend, precision, nullptr, false, communicator)
{
}

Simulation::Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
  Precision precision, const ParticleBatch& given, distributed::Communicator* communicator)
  : Simulation(scene, parameters, backend, precision, &given, false, communicator)
{
}

Simulation::Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
  Precision precision, const ParticleBatch& piece, distributed::Communicator& communicator, InPieces)
  : Simulation(scene, parameters, backend, precision, &piece, true, &communicator)
{
}

// The fluid is the given particles (whole, or this rank's piece of them), or the scene's regions:
// whole on one process, and on each rank of a decomposed run only that rank's slab (SceneFluid),
// so that no rank holds the whole fluid. All leave out what the solids hold at t = 0 (seeded
// inside, it would be thrown out at once) and number the rest 0..N-1.
Simulation::Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
  Precision precision, const ParticleBatch* given, bool givenInPieces,
  distributed::Communicator* communicator)
  : scene_(scene)
  , parameters_(withSceneDomain(parameters, scene))
  , layersEmitted_(scene.emitters.size(), 0)
{
  parameters_.validate();
  const std::vector<DistanceGrid> solids = solidFields(scene_.solids, parameters_);
  motions_ = pbf::solidMotions(scene_.solids);
  solidReach_ = solidReaches(scene_.solids, motions_);
  makeBodies();
  const std::vector<SolidPose> poses = solidPoses(0.0);
  const bool inParts = !given && communicator;
  ParticleBatch whole;
  if (given)
  {
    whole = solids.empty() ? *given : outsideSolids(*given, solids, poses, seededInsideSolids_);
  }
  else if (!inParts)
  {
    whole = outsideSolids(
      fillScene(scene_, parameters_), solids, poses, seededInsideSolids_);
  }
  std::optional<SceneFluid> parts;
  if (inParts)
  {
    checkSceneSize(scene_, parameters_);
    parts.emplace(scene_, parameters_, solids, poses);
    seededInsideSolids_ = parts->insideSolids();
  }
  std::optional<distributed::FluidPieces> pieces;
  std::size_t count = parts ? parts->size() : whole.position.size();
  if (given && givenInPieces)
  {
    // The ids count across the pieces in rank order; the removed are added up.
    double before = 0, total = 0, removed = 0;
    const auto counts = distributed::allGather(*communicator,
      { static_cast<double>(whole.position.size()), static_cast<double>(seededInsideSolids_) });
    for (std::size_t r = 0; r < counts.size(); ++r)
    {
      before += r < static_cast<std::size_t>(communicator->rank()) ? counts[r][0] : 0.0;
      total += counts[r][0];
      removed += counts[r][1];
    }
    for (std::size_t i = 0; i < whole.id.size(); ++i)
    {
      whole.id[i] = static_cast<std::int64_t>(before) + static_cast<std::int64_t>(i);
    }
    count = static_cast<std::size_t>(total);
    seededInsideSolids_ = static_cast<std::size_t>(removed);
    pieces.emplace(whole, *communicator);
  }
  const BatchSource held(whole);
  const FluidSource& initial = parts
    ? static_cast<const FluidSource&>(*parts)
    : (pieces ? static_cast<const FluidSource&>(*pieces) : held);
  if (count == 0 && scene_.emitters.empty())
  {
    if (!scene_.boxes.empty() || !scene_.spheres.empty())
    {
      throw InvalidInput("particleSpacing = " + number(parameters_.particleSpacing) +
        ": the scene's fluid regions hold no lattice site at this spacing (a box needs sides of at "
        "least one spacing); lower particleSpacing");
    }
    throw InvalidInput("particle count = 0: the fluid is empty");
  }
  // An inflow's rate becomes the speed that releases it as whole layers at this spacing.
  for (Emitter& e : scene_.emitters)
  {
    e.speed = emitterSpeed(e, parameters_);
  }
  checkEmitters(count);
  outflowZones_ = pbf::outflowZones(scene_, parameters_);
  checkOutflows(initial, count);
  const std::string where = "the domain of scene \"" + scene_.name + "\"";
  if (inParts)
  {
    checkOffWalls(parameters_, initial, where);
  }
  else
  {
    checkPacking(parameters_, initial, where);
  }
  // The scene's speed scale, from the initial velocities and the emitters: the floor of the
  // automatic step and the scale of XSPH's viscosity (Parameters::sceneSpeedHint).
  double v0 = 0.0;
  if (inParts)
  {
    for (const FluidBox& box : scene_.boxes)
    {
      v0 = std::max(v0, length(box.velocity));
    }
    for (const FluidSphere& sphere : scene_.spheres)
    {
      v0 = std::max(v0, length(sphere.velocity));
    }
  }
  for (const Vec3d& v : whole.velocity)
  {
    v0 = std::max(v0, length(v)); // a NaN velocity is rejected by the stepper below
  }
  if (pieces)
  {
    for (const std::vector<double>& part : pieces->allParts({ v0 }))
    {
      v0 = std::max(v0, part[0]);
    }
  }
  for (const Emitter& e : scene_.emitters)
  {
    v0 = std::max(v0, e.speed);
  }
  const double g = length(parameters_.gravity);
  const double fall = g > 0 ? extentAlong(scene_.domain, parameters_.gravity * (1.0 / g)) : 0.0;
  const double sceneSpeed = std::sqrt(v0 * v0 + 2.0 * g * fall);
  if (parameters_.sceneSpeedHint == 0.0 && std::isfinite(sceneSpeed))
  {
    parameters_.sceneSpeedHint = sceneSpeed;
  }
  stepper_ = communicator
    ? distributed::makeSubdomainStepper(*communicator, backend, precision, parameters_, initial)
    : makeStepper(backend, precision, parameters_, whole);
  if (!solids.empty())
  {
    stepper_->setObstacles(solids, poses);
  }
  solidFields_ = solids;
  for (const SolidRegion& solid : scene_.solids)
  {
    solidCentres_.push_back(solidCentre(solid));
  }
  checkBodiesStartApart();
  nextId_ = static_cast<std::int64_t>(count);

  // The divergence limits, from the initial state and the scene.
  const bool automatic = parameters_.timeStepping == TimeStepping::Automatic;
  checkInterval_ = backend == Backend::CUDA && !automatic ? 0 : 1;
  const LatticeCalibration lattice = calibrateLattice(parameters_);
  // Both blends together (StepTime::make): c + c_4 <= kMaxXsphBlend.
  const double xsphNu = parameters_.largestXsphNu() + parameters_.xsphHyperNu();
  xsphStepLimit_ = xsphNu > 0 ? kMaxXsphBlend * lattice.xsphSecondMoment / xsphNu
                              : std::numeric_limits<double>::infinity();
  capillaryStepLimit_ = capillaryStepLimit(parameters_);
  const Health start = stepper_->health();
  health_ = start;
  healthValid_ = true;
  limits_.sceneSpeed = sceneSpeed;
  limits_.maxSpeed = std::max(
    20.0 * limits_.sceneSpeed, 2.0 * parameters_.smoothingLength() / parameters_.timeStep);
  limits_.maxDensityError = 3.0 * std::max(1.0, 1.0 + start.maxDensityError) - 1.0;
  lastGoodSpeed_ = start.maxSpeed;
  if (automatic)
  {
    checkAutomaticStep(sceneSpeed, v0);
  }
  emit();
}

// The capillary waves' bound (Brackbill et al. 1992): a wave of the spacing's length travels a
// spacing in sqrt(rho s^3 / (2 pi sigma)), which is about cflNumber sqrt(rho s^3 / sigma) at
// the default CFL number 0.4; the step stays below it for each liquid. Infinity without
// surface tension.
double Simulation::capillaryStepLimit(const Parameters& p)
{
  double limit = std::numeric_limits<double>::infinity();
  const double s = p.particleSpacing;
  for (int l = 0; l < p.liquidCount(); ++l)
  {
    const double sigma = p.liquidSurfaceTension(l);
    if (sigma > 0)
    {
      limit = std::min(limit, p.cflNumber * std::sqrt(p.liquidRestDensity(l) * s * s * s / sigma));
    }
  }
  return limit;
}

// The scene's own speed and gravity bound the automatic step from the start: a step too small to
// represent is an input error, named by the term that forces it.
void Simulation::checkAutomaticStep(double sceneSpeed, double v0) const
{
  const double g = length(parameters_.gravity);
  const double s = parameters_.particleSpacing;
  const double c = parameters_.cflNumber;
  // Gravity is named by its largest component (its length may overflow).
  const Vec3d& gv = parameters_.gravity;
  const int axis = std::abs(gv.x) >= std::abs(gv.y)
    ? (std::abs(gv.x) >= std::abs(gv.z) ? 0 : 2)
    : (std::abs(gv.y) >= std::abs(gv.z) ? 1 : 2);
  const std::string gravityName = std::string("gravity.") + "xyz"[axis];
  const double gravityValue = axis == 0 ? gv.x : (axis == 1 ? gv.y : gv.z);
  const struct
  {
    double dt;
    std::string field;
    double value;
  } bounds[] = {
    { c * s / sceneSpeed, g > 0 ? gravityName : "the initial or emitted speed",
      g > 0 ? gravityValue : v0 },
    { g > 0 ? c * std::sqrt(s / g) : parameters_.timeStep, gravityName, gravityValue },
    { xsphStepLimit_,
      parameters_.xsphHyperViscosity > parameters_.xsphViscosity ? "xsphHyperViscosity"
                                                                 : "xsphViscosity",
      std::max(parameters_.xsphViscosity, parameters_.xsphHyperViscosity) },
    { capillaryStepLimit_, "surfaceTension", parameters_.largestSurfaceTension() },
  };
  for (const auto& b : bounds)
  {
    if (!(b.dt >= kSmallestTimeStep))
    {
      throw InvalidInput(b.field + " = " + number(b.value) +
        ": the automatic time step it allows, " + number(b.dt) + " s, is below " +
        number(kSmallestTimeStep) + " s (cflNumber " + number(c) + ", particleSpacing " +
        number(s) + ")");
    }
  }
}

// Emitted layers must land inside the domain and their number must fit, whatever the initial
// particles: advance() never fails on input.
void Simulation::checkEmitters(std::size_t initialParticles) const
{
  const double dt = parameters_.timeStep;
  for (std::size_t e = 0; e < scene_.emitters.size(); ++e)
  {
    // A layer is released within the last step and moved on by the time since its release, at
    // most speed x dt; checkBatch allows one spacing of slack, as here.
    const Emitter& emitter = scene_.emitters[e];
    const double travel = emitter.speed * dt;
    const Vec3d moved = emitter.center + emitter.direction * travel;
    const Vec3d r{ emitter.radius, emitter.radius, emitter.radius };
    if (!inside(moved - r, moved + r, scene_.domain, parameters_.particleSpacing))
    {
      throw InvalidInput("scene .emitters[" + std::to_string(e) + "].speed = " +
        number(emitter.speed) + ": a layer travels speed x timeStep = " + number(travel) +
        " m in one step (timeStep = " + number(dt) +
        " s) and would leave the domain; lower the speed or timeStep");
    }
  }
  if (!scene_.emitters.empty())
  {
    Scene emittersOnly;
    emittersOnly.domain = scene_.domain;
    emittersOnly.emitters = scene_.emitters;
    const double emitted = estimateParticleCount(emittersOnly, parameters_);
    if (!(static_cast<double>(initialParticles) + emitted <= static_cast<double>(kMaxParticles)))
    {
      throw InvalidInput("particleSpacing = " + number(parameters_.particleSpacing) +
        ": the emitters would add about " + number(emitted) + " particles to " +
        std::to_string(initialParticles) + ", more than the " + std::to_string(kMaxParticles) +
        " supported");
    }
  }
}

void Simulation::checkOutflows(const FluidSource& initial, std::size_t count) const
{
  const OutflowZones<double> all = OutflowZones<double>::make(outflowZones_);
  for (std::size_t e = 0; e < scene_.emitters.size(); ++e)
  {
    for (std::size_t k = 0; k < outflowZones_.size(); ++k)
    {
      if (OutflowZones<double>::make({ outflowZones_[k] }).contains(scene_.emitters[e].center))
      {
        throw InvalidInput("scene ." + outflowName(scene_, k) + " holds the nozzle of .emitters[" +
          std::to_string(e) + "]: its layers would leave as they are released");
      }
    }
  }
  if (outflowZones_.empty() || count == 0 || !scene_.emitters.empty())
  {
    return;
  }
  const std::uint64_t inside = initial.countWhere([&](const Vec3d& x) { return all.contains(x); });
  if (inside < count)
  {
    return;
  }
  // Name the one zone that holds it all, if one does.
  std::string which = ".outflows";
  for (std::size_t k = 0; k < outflowZones_.size(); ++k)
  {
    const OutflowZones<double> one = OutflowZones<double>::make({ outflowZones_[k] });
    if (initial.countWhere([&](const Vec3d& x) { return one.contains(x); }) == count)
    {
      which = "." + outflowName(scene_, k);
      break;
    }
  }
  throw InvalidInput("scene " + which + " covers all " + std::to_string(inside) +
    " particles of the fluid and no emitter adds any: the first step would remove them all");
}

void Simulation::checkDivergence()
{
  const Health health = stepper_->health();
  health_ = health;
  healthValid_ = true;
  std::vector<std::string> found;
  const auto which = [&](std::size_t count, const std::string& what) {
    std::string text = std::to_string(count) + (count == 1 ? " particle " : " particles ") + what;
    if (health.firstBadId >= 0)
    {
      text += " (particle id " + std::to_string(health.firstBadId) + " among them)";
    }
    found.push_back(text);
  };
  if (health.nonFinite > 0)
  {
    which(health.nonFinite, "with a non-finite position or velocity");
  }
  if (health.outside > 0)
  {
    which(health.outside, "farther than one spacing outside the domain");
  }
  if (health.maxSpeed > limits_.maxSpeed)
  {
    found.push_back("the fastest particle moves at " + number(health.maxSpeed) +
      " m/s, beyond the limit of " + number(limits_.maxSpeed) +
      " m/s (20 x the scene's speed sqrt(v0^2 + 2 |g| L) = " + number(limits_.sceneSpeed) +
      " m/s, or 2 h / dt)");
  }
  if (health.maxDensityError > limits_.maxDensityError)
  {
    found.push_back("the densest particle reads " +
      number((1.0 + health.maxDensityError) * parameters_.restDensity) + " kg/m^3, " +
      number(1.0 + health.maxDensityError) + " x restDensity (the limit is " +
      number(1.0 + limits_.maxDensityError) + " x): particles are piling up");
  }
  if (found.empty())
  {
    lastGoodStep_ = steps_;
    lastGoodSpeed_ = health.maxSpeed;
    return;
  }
  std::string text;
  for (const std::string& f : found)
  {
    text += (text.empty() ? "" : "; ") + f;
  }
  const std::string cause = likelyCause();
  throw SimulationDiverged("simulation diverged at step " + std::to_string(steps_) + " (t = " +
      number(time()) + " s; last good check at step " + std::to_string(lastGoodStep_) + "): " +
      text + ". Likely cause: " + cause,
    steps_, time(), lastGoodStep_, cause);
}

// Rules of thumb, from runs that blew up (dam break at s = 0.05 m): dt = 0.05 s (12 x the
// default); gravity 1e4 m/s^2; one iteration at dt = 1/60 s; Unilateral off. A tiny relaxation
// alone did not blow up, but it removes the damping the others need.
std::string Simulation::likelyCause() const
{
  const Parameters& p = parameters_;
  const double h = p.smoothingLength();
  const double dt = stepper_->timeStep();
  const double cfl = lastGoodSpeed_ * dt / h;
  const double fall = length(p.gravity) * dt * dt / p.particleSpacing;
  std::vector<std::string> causes;
  if (!p.unilateral)
  {
    causes.push_back("Unilateral is off: C_i < 0 at the free surface pulls particles together; "
                     "turn it on");
  }
  if (cfl > 1.0 || fall > 0.1)
  {
    std::string why;
    if (cfl > 1.0)
    {
      why = "at the last good check (step " + std::to_string(lastGoodStep_) +
        ") the fastest particle moved " + number(cfl) +
        " smoothing lengths in a step (CFL dt v_max / h; PBF needs well under 1)";
    }
    if (fall > 0.1)
    {
      why += (why.empty() ? "" : ", and ") + std::string("gravity alone moves a particle ") +
        number(fall) + " spacings per step (|g| dt^2 / s)";
    }
    causes.push_back("the time step dt = " + number(dt) + " s is too large: " + why +
      (p.timeStepping == TimeStepping::Fixed
          ? "; lower timeStep (more substeps per frame) or use automatic time stepping"
          : "; lower cflNumber or the largest time step"));
  }
  if (p.solverIterations < 3)
  {
    causes.push_back("too few solver iterations (solverIterations = " +
      std::to_string(p.solverIterations) +
      "): the density constraint is not enforced; raise it (paper: 2-4, default 4)");
  }
  if (p.relaxation < 1e-3)
  {
    causes.push_back("the relaxation epsilon = " + number(p.relaxation) +
      " is too small: lambda is left undamped where neighbours are few; raise relaxation "
      "(default 0.01)");
  }
  if (causes.empty())
  {
    causes.push_back("no parameter stands out: lower timeStep first, then check the initial "
                     "velocities, gravity and emitters against the spacing");
  }
  std::string text;
  for (const std::string& c : causes)
  {
    text += (text.empty() ? "" : "; ") + c;
  }
  return text;
}

void AdvanceReport::add(const AdvanceReport& more)
{
  if (more.steps == 0)
  {
    return;
  }
  minTimeStep = steps == 0 ? more.minTimeStep : std::min(minTimeStep, more.minTimeStep);
  maxTimeStep = std::max(maxTimeStep, more.maxTimeStep);
  steps += more.steps;
  iterations += more.iterations;
  removed += more.removed;
  densityError = more.densityError;
  milliseconds += more.milliseconds;
  seconds += more.seconds;
  impulses.resize(std::max(impulses.size(), more.impulses.size()));
  for (std::size_t k = 0; k < more.impulses.size(); ++k)
  {
    impulses[k].force += more.impulses[k].force;
    impulses[k].torque += more.impulses[k].torque;
  }
}

double Simulation::nextTimeStep() const
{
  const Parameters& p = parameters_;
  if (p.timeStepping == TimeStepping::Fixed)
  {
    return p.timeStep;
  }
  const double s = p.particleSpacing;
  const double v = std::max(
    { healthValid_ ? health_.maxSpeed : 0.0, limits_.sceneSpeed, fastestSolidPoint() });
  double dt = std::min({ p.timeStep, xsphStepLimit_, capillaryStepLimit_ });
  if (v > 0)
  {
    dt = std::min(dt, p.cflNumber * s / v);
  }
  const double g = length(p.gravity);
  if (g > 0)
  {
    dt = std::min(dt, p.cflNumber * std::sqrt(s / g));
  }
  return dt;
}

double Simulation::checkedTimeStep() const
{
  const double dt = nextTimeStep();
  // A largest step below the bound is the caller's own choice (validatePrecision checked it).
  if (!(dt >= std::min(kSmallestTimeStep, parameters_.timeStep)))
  {
    const std::string cause = "a particle moves at " + number(health_.maxSpeed) +
      " m/s; lower the initial speeds or gravity";
    throw SimulationDiverged("simulation diverged at step " + std::to_string(steps_) + " (t = " +
        number(time()) + " s): the automatic time step fell to " + number(dt) + " s, below " +
        number(kSmallestTimeStep) + " s. Likely cause: " + cause,
      steps_, time(), lastGoodStep_, cause);
  }
  return dt;
}

void Simulation::stepOnce(double dt, double end, AdvanceReport& report)
{
  if (dt != stepper_->timeStep())
  {
    stepper_->setTimeStep(dt);
  }
  moveBodies(dt, end);
  // The constraints hold at the step's end, with the solids where they are then.
  const std::vector<SolidPose> poses = solidPoses(end);
  if (!poses.empty())
  {
    stepper_->setObstaclePoses(poses);
  }
  stepper_->step();
  ++steps_;
  healthValid_ = false;
  const StepReport step = stepper_->lastStep();
  report.iterations += step.iterations;
  report.densityError = step.densityError;
  report.minTimeStep = report.steps == 0 ? dt : std::min(report.minTimeStep, dt);
  report.maxTimeStep = std::max(report.maxTimeStep, dt);
  report.seconds += dt;
  ++report.steps;
  addLoads(step.loads, poses, dt, report);
  if (!outflowZones_.empty())
  {
    const std::size_t gone = stepper_->removeOutflow(outflowZones_);
    removed_ += gone;
    report.removed += gone;
  }
}

AdvanceReport Simulation::advance(std::uint64_t steps)
{
  AdvanceReport report;
  const auto start = std::chrono::steady_clock::now();
  const bool automatic = parameters_.timeStepping == TimeStepping::Automatic;
  for (std::uint64_t k = 0; k < steps; ++k)
  {
    if (automatic && !healthValid_)
    {
      checkDivergence(); // the fastest particle, and the check for free
    }
    const double dt = checkedTimeStep();
    stepOnce(dt, time_ + dt, report);
    time_ += dt;
    if (automatic || (checkInterval_ > 0 && steps_ % checkInterval_ == 0))
    {
      checkDivergence();
    }
    emit();
  }
  stepper_->synchronize();
  report.milliseconds =
    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return report;
}

bool Simulation::stepToward(double until, AdvanceReport& report)
{
  if (!(time_ < until))
  {
    return true;
  }
  const auto start = std::chrono::steady_clock::now();
  const bool automatic = parameters_.timeStepping == TimeStepping::Automatic;
  if (automatic && !healthValid_)
  {
    checkDivergence();
  }
  // A whole number of steps of at most nextTimeStep() to `until`; the relative slack keeps a
  // remaining time that is a multiple of a fixed step in rounding from costing one more step.
  const double remaining = until - time_;
  const double largest = checkedTimeStep();
  const double count = std::max(1.0, std::ceil(remaining / largest * (1.0 - 1e-9)));
  const bool fixedFits = !automatic && count * largest <= remaining * (1.0 + 1e-9);
  // Fixed steps stay exactly timeStep; only a remainder that is no multiple of it is shortened.
  const double dt = fixedFits || count == 1.0 ? (count == 1.0 ? remaining : largest)
                                              : remaining / count;
  const bool landed = count == 1.0;
  stepOnce(dt, landed ? until : time_ + dt, report);
  time_ = landed ? until : time_ + dt;
  if (automatic || landed || (checkInterval_ > 0 && steps_ % checkInterval_ == 0))
  {
    checkDivergence();
  }
  emit();
  report.milliseconds +=
    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return landed;
}

AdvanceReport Simulation::advanceTo(double until)
{
  AdvanceReport report;
  while (!stepToward(until, report))
  {
  }
  stepper_->synchronize();
  return report;
}

std::size_t SimulationCheckpoint::bytes() const
{
  return std::visit(
    [this](const auto& s) {
      return s.position.size() * sizeof(s.position[0]) + s.velocity.size() * sizeof(s.velocity[0]) +
        s.density.size() * sizeof(s.density[0]) + s.lambda.size() * sizeof(s.lambda[0]) +
        s.pressure.size() * sizeof(s.pressure[0]) +
        s.id.size() * sizeof(s.id[0]) + s.liquid.size() + layersEmitted.size() * sizeof(std::int64_t) +
        bodyStates.size() * sizeof(RigidState) + bodyLoads.size() * sizeof(SolidLoad);
    },
    state);
}

SimulationCheckpoint Simulation::checkpoint() const
{
  SimulationCheckpoint c;
  c.steps = steps_;
  c.time = time_;
  c.nextId = nextId_;
  c.removed = removed_;
  c.layersEmitted = layersEmitted_;
  for (const Body& body : bodies_)
  {
    c.bodyStates.push_back(body.state);
    c.bodyLoads.push_back(body.load);
  }
  if (stepper_->precision() == Precision::Single)
  {
    Snapshot<float> s;
    stepper_->read(s);
    c.state = std::move(s);
  }
  else
  {
    Snapshot<double> s;
    stepper_->read(s);
    c.state = std::move(s);
  }
  return c;
}

void Simulation::restore(const SimulationCheckpoint& c)
{
  if (c.layersEmitted.size() != layersEmitted_.size())
  {
    throw InvalidInput("checkpoint emitters = " + std::to_string(c.layersEmitted.size()) +
      ": the scene has " + std::to_string(layersEmitted_.size()));
  }
  if (c.bodyStates.size() != bodies_.size())
  {
    throw InvalidInput("checkpoint bodies = " + std::to_string(c.bodyStates.size()) +
      ": the scene has " + std::to_string(bodies_.size()));
  }
  for (std::size_t k = 0; k < bodies_.size(); ++k)
  {
    bodies_[k].state = c.bodyStates[k];
    bodies_[k].load = c.bodyLoads[k];
  }
  if (!bodies_.empty())
  {
    stepper_->setObstaclePoses(solidPoses(c.time));
  }
  std::visit([this](const auto& s) { stepper_->load(s); }, c.state);
  steps_ = c.steps;
  time_ = c.time;
  nextId_ = c.nextId;
  removed_ = c.removed;
  layersEmitted_ = c.layersEmitted;
  lastGoodStep_ = steps_;
  // The next automatic step needs the fastest particle, which a fresh scan gives exactly as the
  // straight run had it (the scan reads only the restored state).
  healthValid_ = false;
  if (checkInterval_ > 0 || parameters_.timeStepping == TimeStepping::Automatic)
  {
    health_ = stepper_->health();
    healthValid_ = true;
    lastGoodSpeed_ = health_.maxSpeed;
  }
  else
  {
    lastGoodSpeed_ = std::numeric_limits<double>::quiet_NaN();
  }
}

// Each emitter releases one disk of lattice sites every s / speed seconds. A layer released
// between steps is advanced along the jet by the time it has already travelled, so layers stay
// one spacing apart whatever the time step.
void Simulation::emit()
{
  const double s = parameters_.particleSpacing;
  const double t = time();
  ParticleBatch batch;
  for (std::size_t e = 0; e < scene_.emitters.size(); ++e)
  {
    const Emitter& emitter = scene_.emitters[e];
    if (t < emitter.start)
    {
      continue;
    }
    const double interval = s / emitter.speed;
    const double until = std::min(t, emitter.stop - 1e-12);
    const auto due = static_cast<std::int64_t>(std::floor((until - emitter.start) / interval)) + 1;
    // Two unit vectors across the jet.
    const Vec3d d = emitter.direction;
    const Vec3d helper = std::abs(d.x) < 0.9 ? Vec3d{ 1, 0, 0 } : Vec3d{ 0, 1, 0 };
    Vec3d u = cross(d, helper);
    u *= 1.0 / length(u);
    const Vec3d w = cross(d, u);
    const long n = static_cast<long>(std::floor(emitter.radius / s));
    for (; layersEmitted_[e] < due; ++layersEmitted_[e])
    {
      const double released = emitter.start + static_cast<double>(layersEmitted_[e]) * interval;
      const Vec3d origin = emitter.center + d * (emitter.speed * (t - released));
      for (long a = -n; a <= n; ++a)
      {
        for (long b = -n; b <= n; ++b)
        {
          if ((a * a + b * b) * s * s <= emitter.radius * emitter.radius)
          {
            batch.position.push_back(origin + u * (s * a) + w * (s * b));
            batch.velocity.push_back(d * emitter.speed);
            batch.id.push_back(nextId_++);
            if (!scene_.liquids.empty())
            {
              batch.liquid.push_back(static_cast<std::uint8_t>(emitter.liquid));
            }
          }
        }
      }
    }
  }
  if (!batch.position.empty())
  {
    stepper_->append(batch);
    // The new particles (and the densities evaluated again at rest) are not in the last scan; a
    // run resumed from a checkpoint taken now scans them too, so the straight run does the same.
    healthValid_ = false;
  }
}

} // namespace pbf
