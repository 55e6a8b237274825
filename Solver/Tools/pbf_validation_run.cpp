// pbf_validation_run: runs a scene and writes, every --every steps, what the validation plots:
// the density error of the end-of-step positions (mean and max compression), the iterations per
// step, the solver's own mean error, kinetic energy, potential energy released since the start,
// max speed, and whether count, ids, domain and finiteness still hold. Used for the hydrostatic
// tank (incompressibility) and the vorticity-confinement run (stability); validate.py drives it.
#include "Measures.h"

#include "Scene.h"
#include "ToolOptions.h"

#include <algorithm>
#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "steps", "steps to run (default 480)" },
    { "every", "write a row every this many steps (default 10)" },
    { "out", "CSV file to write (default: standard output)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const long steps = toolInteger(options, "steps", 480, 0);
    const long every = toolInteger(options, "every", 10, 1);
    const Scene scene = options.scene.find(".json") != std::string::npos
      ? loadSceneFile(options.scene)
      : presetScene(options.scene);
    Simulation simulation(scene, options.parameters, options.backend, options.precision);
    FILE* out = stdout;
    if (options.extra.count("out") && !(out = std::fopen(options.extra["out"].c_str(), "w")))
    {
      throw InvalidInput("--out = \"" + options.extra["out"] + "\": cannot be written");
    }
    std::fprintf(stderr, "validation run: %s, %zu particles, %s\n%s\n", scene.name.c_str(),
      simulation.stepper().size(), simulation.stepper().description().c_str(),
      describe(simulation.parameters()).c_str());
    std::fprintf(out, "step,time,iterations_per_step,avg_error,max_error,solver_avg_error,"
                      "kinetic_energy,potential_released,max_speed,particles,violation\n");
    const double initialPotential = potentialEnergy(simulation);
    int status = 0;
    for (bool first = true; first || simulation.stepCount() < std::uint64_t(steps); first = false)
    {
      const std::uint64_t n =
        first ? 0 : std::min(std::uint64_t(every), std::uint64_t(steps) - simulation.stepCount());
      const AdvanceReport report = simulation.advance(n);
      const DensityError e = densityErrorNow(simulation);
      const Statistics s = simulation.stepper().statistics();
      const std::string violation = conservationViolation(simulation, simulation.idCount());
      std::fprintf(out, "%llu,%.6f,%.3f,%.6g,%.6g,%.6g,%.6g,%.6g,%.5g,%zu,%s\n",
        static_cast<unsigned long long>(simulation.stepCount()), simulation.time(),
        report.steps ? double(report.iterations) / double(report.steps) : 0.0, e.average, e.max,
        s.averageDensityError, s.kineticEnergy, initialPotential - potentialEnergy(simulation),
        s.maxSpeed, s.particles, violation.empty() ? "none" : violation.c_str());
      if (!violation.empty())
      {
        status = 1;
        break;
      }
    }
    if (out != stdout)
    {
      std::fclose(out);
    }
    return status;
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_validation_run: " << error.what() << "\n";
    return 2;
  }
}
