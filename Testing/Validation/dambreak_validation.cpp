// pbf_martin_moyce: the Martin & Moyce (1952) dam break at one resolution. Prints the simulated
// front as CSV (T, Z) and, per tabulated point, the experimental and simulated times and their
// relative difference, then the RMS. Regenerates the validation figures with
// Testing/Validation/validate.py.
#include "MartinMoyce.h"

#include "ToolOptions.h"

#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "across", "particles across the column width a (default 20)" },
    { "experiment", "path of martin_moyce_1952_surge_front_n2.csv" },
    { "front", "write the simulated front (T,Z) to this CSV file" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const int across = options.extra.count("across") ? std::stoi(options.extra["across"]) : 20;
    if (!options.extra.count("experiment"))
    {
      throw InvalidInput("--experiment is required\n" + toolUsage(keys));
    }
    const auto experiment = readExperiment(options.extra["experiment"]);
    MartinMoyceSetup setup = martinMoyce(across, options.parameters);
    Simulation simulation(setup.scene, setup.parameters, options.backend, options.precision);
    std::fprintf(stderr, "martin-moyce: %d across, %zu particles, dt %.3g s, %s\n", across,
      simulation.stepper().size(), setup.parameters.timeStep,
      simulation.stepper().description().c_str());
    const auto front =
      runFront(simulation, setup.timeScale, experiment.back().Z + 0.05, 1.5 * experiment.back().T);
    if (options.extra.count("front"))
    {
      FILE* out = std::fopen(options.extra["front"].c_str(), "w");
      if (!out)
      {
        throw InvalidInput("--front = \"" + options.extra["front"] + "\": cannot be written");
      }
      std::fprintf(out, "T,Z\n");
      for (const auto& f : front)
      {
        std::fprintf(out, "%.5f,%.5f\n", f.T, f.Z);
      }
      std::fclose(out);
    }
    const FrontComparison c = compareFront(front, experiment);
    std::printf("Z,T_experiment,T_simulated,relative\n");
    for (std::size_t k = 0; k < experiment.size(); ++k)
    {
      std::printf("%.2f,%.3f,%.4f,%+.4f\n", experiment[k].Z, experiment[k].T, c.simulatedT[k],
        (c.simulatedT[k] - experiment[k].T) / experiment[k].T);
    }
    std::printf("particles_across,%d\nparticles,%zu\nsteps,%llu\nrms_relative_error,%.4f\n", across,
      simulation.stepper().size(), static_cast<unsigned long long>(simulation.stepCount()),
      c.rmsRelativeError);
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_martin_moyce: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
