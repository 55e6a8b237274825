// Simulation's construction: the solids, the initial fluid (whole, in parts or in pieces), the
// checks of the scene against the run's spacing, the stepper, and the limits of the steps and of
// the divergence check.
#include "Simulation.h"

#include "MassProperties.h"
#include "Outflow.h"

#include "Backends.h"
#include "ParticleChecks.h"
#include "SceneFluid.h"
#include "SimulationText.h"

#include "Distributed/FluidPieces.h"
#include "Distributed/SubdomainStepper.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace pbf
{
namespace
{

using simulationtext::number;

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

// The fluid at t = 0 as this run holds it: the given particles (whole, or this rank's piece of
// them), or the scene's regions: whole on one process, and on each rank of a decomposed run only
// that rank's slab (SceneFluid), so that no rank holds the whole fluid. All leave out what the
// solids hold at t = 0 (seeded inside, it would be thrown out at once) and number the rest
// 0..N-1. It stays where it is made: its sources refer to `whole`.
class InitialFluid
{
public:
  InitialFluid(const Scene& scene, const Parameters& parameters, const ParticleBatch* given,
    bool givenInPieces, distributed::Communicator* communicator,
    const std::vector<DistanceGrid>& solids, const std::vector<SolidPose>& poses)
    : inParts(!given && communicator)
  {
    if (given)
    {
      whole = solids.empty() ? *given : outsideSolids(*given, solids, poses, insideSolids);
    }
    else if (!inParts)
    {
      whole = outsideSolids(fillScene(scene, parameters), solids, poses, insideSolids);
    }
    if (inParts)
    {
      checkSceneSize(scene, parameters);
      parts.emplace(scene, parameters, solids, poses);
      insideSolids = parts->insideSolids();
    }
    count = parts ? parts->size() : whole.position.size();
    if (given && givenInPieces)
    {
      numberPieces(*communicator);
    }
  }
  InitialFluid(const InitialFluid&) = delete;
  InitialFluid& operator=(const InitialFluid&) = delete;

  // What the stepper starts from.
  const FluidSource& source() const
  {
    return parts ? static_cast<const FluidSource&>(*parts)
                 : (pieces ? static_cast<const FluidSource&>(*pieces) : held_);
  }

  const bool inParts; // the scene's regions, this rank's slab of them
  ParticleBatch whole; // the particles held, whole or this rank's given piece
  std::optional<SceneFluid> parts;
  std::optional<distributed::FluidPieces> pieces;
  std::size_t count = 0;        // over every rank
  std::size_t insideSolids = 0; // left out, over every rank

private:
  void numberPieces(distributed::Communicator& communicator)
  {
    // The ids count across the pieces in rank order; the removed are added up.
    double before = 0, total = 0, removed = 0;
    const auto counts = distributed::allGather(communicator,
      { static_cast<double>(whole.position.size()), static_cast<double>(insideSolids) });
    for (std::size_t r = 0; r < counts.size(); ++r)
    {
      before += r < static_cast<std::size_t>(communicator.rank()) ? counts[r][0] : 0.0;
      total += counts[r][0];
      removed += counts[r][1];
    }
    for (std::size_t i = 0; i < whole.id.size(); ++i)
    {
      whole.id[i] = static_cast<std::int64_t>(before) + static_cast<std::int64_t>(i);
    }
    count = static_cast<std::size_t>(total);
    insideSolids = static_cast<std::size_t>(removed);
    pieces.emplace(whole, communicator);
  }

  const BatchSource held_{ whole };
};

// InvalidInput for a run without fluid: no initial particle and no emitter.
void requireFluid(const Scene& scene, const Parameters& parameters, std::size_t count)
{
  if (count == 0 && scene.emitters.empty())
  {
    if (!scene.boxes.empty() || !scene.spheres.empty())
    {
      throw InvalidInput("particleSpacing = " + number(parameters.particleSpacing) +
        ": the scene's fluid regions hold no lattice site at this spacing (a box needs sides of at "
        "least one spacing); lower particleSpacing");
    }
    throw InvalidInput("particle count = 0: the fluid is empty");
  }
}

// The initial particles' packing (checkPacking); a decomposed run's scene, a lattice by
// construction, against the walls alone.
void checkInitialPacking(
  const Parameters& parameters, const Scene& scene, const InitialFluid& fluid)
{
  const std::string where = "the domain of scene \"" + scene.name + "\"";
  if (fluid.inParts)
  {
    checkOffWalls(parameters, fluid.source(), where);
  }
  else
  {
    checkPacking(parameters, fluid.source(), where);
  }
}

// The fastest initial or emitted speed v0: of the regions' velocities where this rank holds a
// slab of them, of the particles held, of every rank's pieces, and of the emitters.
double fastestInitialSpeed(const Scene& scene, const InitialFluid& fluid)
{
  double v0 = 0.0;
  if (fluid.inParts)
  {
    for (const FluidBox& box : scene.boxes)
    {
      v0 = std::max(v0, length(box.velocity));
    }
    for (const FluidSphere& sphere : scene.spheres)
    {
      v0 = std::max(v0, length(sphere.velocity));
    }
  }
  for (const Vec3d& v : fluid.whole.velocity)
  {
    v0 = std::max(v0, length(v)); // a NaN velocity is rejected by the stepper (startStepper)
  }
  if (fluid.pieces)
  {
    for (const std::vector<double>& part : fluid.pieces->allParts({ v0 }))
    {
      v0 = std::max(v0, part[0]);
    }
  }
  for (const Emitter& e : scene.emitters)
  {
    v0 = std::max(v0, e.speed);
  }
  return v0;
}

// v_scene = sqrt(v0^2 + 2 |g| L): the speed of a fall across the domain's extent L along gravity
// from v0 (DivergenceLimits).
double sceneSpeedOf(const Scene& scene, const Parameters& parameters, double v0)
{
  const double g = length(parameters.gravity);
  const double fall = g > 0 ? extentAlong(scene.domain, parameters.gravity * (1.0 / g)) : 0.0;
  return std::sqrt(v0 * v0 + 2.0 * g * fall);
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
  const InitialFluid fluid(scene_, parameters_, given, givenInPieces, communicator, solids, poses);
  seededInsideSolids_ = fluid.insideSolids;
  requireFluid(scene_, parameters_, fluid.count);
  setUpFlows(fluid.source(), fluid.count);
  checkInitialPacking(parameters_, scene_, fluid);
  // The scene's speed scale, from the initial velocities and the emitters: the floor of the
  // automatic step and the scale of XSPH's viscosity (Parameters::sceneSpeedHint).
  const double v0 = fastestInitialSpeed(scene_, fluid);
  const double sceneSpeed = sceneSpeedOf(scene_, parameters_, v0);
  if (parameters_.sceneSpeedHint == 0.0 && std::isfinite(sceneSpeed))
  {
    parameters_.sceneSpeedHint = sceneSpeed;
  }
  startStepper(backend, precision, communicator, fluid.source(), fluid.whole, solids, poses);
  nextId_ = static_cast<std::int64_t>(fluid.count);
  setLimits(backend, sceneSpeed, v0);
  emit();
}

void Simulation::setUpFlows(const FluidSource& initial, std::size_t count)
{
  // An inflow's rate becomes the speed that releases it as whole layers at this spacing.
  for (Emitter& e : scene_.emitters)
  {
    e.speed = emitterSpeed(e, parameters_);
  }
  checkEmitters(count);
  outflowZones_ = pbf::outflowZones(scene_, parameters_);
  checkOutflows(initial, count);
}

void Simulation::startStepper(Backend backend, Precision precision,
  distributed::Communicator* communicator, const FluidSource& initial, const ParticleBatch& whole,
  const std::vector<DistanceGrid>& solids, const std::vector<SolidPose>& poses)
{
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
}

// The divergence limits, from the initial state and the scene.
void Simulation::setLimits(Backend backend, double sceneSpeed, double v0)
{
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

} // namespace pbf
