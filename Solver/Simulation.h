// A scene running on a stepper: owns the step count and the emitters, so that the state after
// step k depends only on (scene, parameters, backend, precision, k). The VTK algorithm and the
// command-line tools drive this.
#pragma once

#include "Parameters.h"
#include "Scene.h"
#include "Stepper.h"

#include <cstdint>
#include <memory>
#include <variant>

namespace pbf
{

// Everything a Simulation needs to resume exactly where it was.
struct SimulationCheckpoint
{
  std::uint64_t steps = 0;
  std::int64_t nextId = 0;
  std::vector<std::int64_t> layersEmitted;
  std::variant<Snapshot<float>, Snapshot<double>> state;

  std::size_t bytes() const; // host memory held
};

// What one advance() did.
struct AdvanceReport
{
  std::uint64_t steps = 0;
  long iterations = 0;       // constraint projections, summed over the steps
  double densityError = 0;   // adaptive mode: at the end of the last step; NaN in fixed mode
  double milliseconds = 0;   // wall time, the queued GPU work included
};

class Simulation
{
public:
  // Throws InvalidInput for a bad scene or parameters, std::runtime_error when the backend is
  // unavailable. parameters.domain is replaced by the scene's.
  Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
    Precision precision);
  // The fluid starts from given particles (the VTK filter's input points) instead of the scene's
  // regions; the scene still gives the domain and emitters.
  Simulation(const Scene& scene, const Parameters& parameters, Backend backend,
    Precision precision, const ParticleBatch& initial);

  AdvanceReport advance(std::uint64_t steps);

  // A copy of the whole state; restore() continues bit-identically from it. The checkpoint must
  // come from a Simulation of the same scene, parameters and precision.
  SimulationCheckpoint checkpoint() const;
  void restore(const SimulationCheckpoint& checkpoint);

  std::uint64_t stepCount() const { return steps_; }
  // Ids run 0..idCount()-1: the initial particles and every one an emitter has released.
  std::int64_t idCount() const { return nextId_; }
  double time() const { return static_cast<double>(steps_) * parameters_.timeStep; }
  const Parameters& parameters() const { return parameters_; }
  const Scene& scene() const { return scene_; }
  Stepper& stepper() { return *stepper_; }
  const Stepper& stepper() const { return *stepper_; }

private:
  void emit();

  Scene scene_;
  Parameters parameters_;
  std::unique_ptr<Stepper> stepper_;
  std::uint64_t steps_ = 0;
  std::int64_t nextId_ = 0;
  std::vector<std::int64_t> layersEmitted_; // per emitter
};

} // namespace pbf
