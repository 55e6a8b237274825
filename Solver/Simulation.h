// A scene running on a stepper: owns the step count and the emitters, so that the state after
// step k depends only on (scene, parameters, backend, precision, k). The VTK algorithm and the
// command-line tools drive this.
#pragma once

#include "Parameters.h"
#include "Scene.h"
#include "Stepper.h"

#include <cstdint>
#include <memory>

namespace pbf
{

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

  void advance(std::uint64_t steps);

  std::uint64_t stepCount() const { return steps_; }
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
