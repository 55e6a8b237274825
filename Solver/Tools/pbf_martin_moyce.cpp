// pbf_martin_moyce: the Martin & Moyce (1952) dam break at one resolution. Prints, per tabulated
// point, the experimental and simulated times and their relative difference, then the RMS
// (T = 0 at release, the data's convention). Optionally writes the simulated front and the
// density error over time as CSV. The figures come from Utilities/validation/validate.py.
#include "MartinMoyce.h"
#include "Measures.h"

#include "ToolOptions.h"

#include <cmath>
#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

namespace
{

FILE* openOutput(const std::string& path, const char* option)
{
  FILE* out = std::fopen(path.c_str(), "w");
  if (!out)
  {
    throw InvalidInput(std::string("--") + option + " = \"" + path + "\": cannot be written");
  }
  return out;
}

} // namespace

// The experiment's column stood at rest behind its diaphragm: the same column in a box that ends
// at the gate, simulated for settleT (in T) until the lattice has become the solver's column at
// rest; its particles, to be released.
ParticleBatch settledColumn(const MartinMoyceSetup& setup, const ToolOptions& options,
  double settleT)
{
  ParticleBatch released;
  Scene gated = setup.scene;
  gated.domain.max.x = kColumnWidth;
  Simulation settling(gated, setup.parameters, options.backend, options.precision);
  settling.advanceTo(settleT / setup.timeScale);
  Snapshot<double> state;
  settling.stepper().read(state);
  released.position = state.position;
  released.velocity = state.velocity;
  released.id = state.id;
  const Statistics st = settling.stepper().statistics();
  std::fprintf(stderr, "martin-moyce: settled for T = %g (%llu steps): max speed %.3g m/s, mean "
    "compression %.3f %%, max %.3f %%\n", settleT,
    static_cast<unsigned long long>(settling.stepCount()), st.maxSpeed,
    100 * st.averageDensityError, 100 * st.maxDensityError);
  return released;
}

// The comparison with the record, as CSV rows on standard output.
void printComparison(const std::vector<FrontSample>& front,
  const std::vector<FrontSample>& experiment, long across, Simulation& simulation,
  double timeStep)
{
  const FrontComparison c = compareFront(front, experiment);
  std::printf("Z,T_experiment,T_simulated,relative\n");
  for (std::size_t k = 0; k < experiment.size(); ++k)
  {
    std::printf("%.2f,%.3f,%.4f,%+.4f\n", experiment[k].Z, experiment[k].T, c.simulatedT[k],
      (c.simulatedT[k] - experiment[k].T) / experiment[k].T);
  }
  const double shift = fitTimeShift(c, experiment);
  std::printf("particles_across,%ld\nparticles,%zu\nsteps,%llu\ndt,%.6g\n"
              "rms_relative_error,%.4f\nfitted_time_shift,%.4f\n"
              "rms_relative_error_shifted,%.4f\n",
    across, simulation.stepper().size(),
    static_cast<unsigned long long>(simulation.stepCount()), timeStep,
    c.rmsRelativeError, shift, compareFront(front, experiment, shift).rmsRelativeError);
}

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "across", "particles across the column width a (default 20)" },
    { "experiment", "path of martin_moyce_1952_surge_front_n2.csv" },
    { "front", "write the simulated front to this CSV (T, Z, Z of the particles within 2 s of "
               "the floor)" },
    { "density", "write the density error over time to this CSV (T, step, iterations per step, "
                 "mean and max compression of the end-of-step positions, the solver's own mean)" },
    { "density-dT", "sample the density every this much T (default 0.05)" },
    { "dt-factor", "multiply the scene's time step (0.25 h / sqrt(4 g a)) by this (default 1)" },
    { "settle", "first hold the column behind a gate (a wall at x = a) for this long in T, then "
                "release it from that state (default 0: released from the lattice)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const long across = toolInteger(options, "across", 20, 2);
    if (!options.extra.count("experiment"))
    {
      throw InvalidInput("--experiment is required\n" + toolUsage(keys));
    }
    const double dtFactor =
      options.extra.count("dt-factor") ? std::stod(options.extra["dt-factor"]) : 1.0;
    const double densityDT =
      options.extra.count("density-dT") ? std::stod(options.extra["density-dT"]) : 0.05;
    if (!(dtFactor > 0) || !(densityDT > 0))
    {
      throw InvalidInput("--dt-factor and --density-dT must be > 0");
    }
    const auto experiment = readExperiment(options.extra["experiment"]);
    MartinMoyceSetup setup = martinMoyce(static_cast<int>(across), options.parameters);
    // Fixed steps: dt itself; automatic (the default): the CFL number and the largest step.
    setup.parameters.timeStep *= dtFactor;
    setup.parameters.cflNumber *= dtFactor;
    const double settleT = options.extra.count("settle") ? std::stod(options.extra["settle"]) : 0.0;
    const ParticleBatch released =
      settleT > 0 ? settledColumn(setup, options, settleT) : ParticleBatch{};
    Simulation simulation = settleT > 0
      ? Simulation(setup.scene, setup.parameters, options.backend, options.precision, released)
      : Simulation(setup.scene, setup.parameters, options.backend, options.precision);
    const double s = setup.parameters.particleSpacing;
    std::fprintf(stderr, "martin-moyce: %ld across, %zu particles, dt %.4g s, %s\n", across,
      simulation.stepper().size(), setup.parameters.timeStep,
      simulation.stepper().description().c_str());

    FILE* density = nullptr;
    if (options.extra.count("density"))
    {
      density = openOutput(options.extra["density"], "density");
      std::fprintf(density, "T,step,iterations_per_step,avg_error,max_error,solver_avg_error\n");
      const DensityError e = densityErrorNow(simulation);
      std::fprintf(density, "0,0,0,%.6g,%.6g,%.6g\n", e.average, e.max,
        simulation.stepper().statistics().averageDensityError);
    }
    std::vector<double> floorFront{ surgeFront(simulation, 2 * s) };
    long iterations = 0, stepsSinceSample = 0;
    double nextSample = densityDT;
    const auto afterStep = [&](const AdvanceReport& report) {
      floorFront.push_back(surgeFront(simulation, 2 * s));
      iterations += report.iterations;
      ++stepsSinceSample;
      const double T = simulation.time() * setup.timeScale;
      if (density && T >= nextSample - 1e-9)
      {
        const DensityError e = densityErrorNow(simulation);
        std::fprintf(density, "%.5f,%llu,%.3f,%.6g,%.6g,%.6g\n", T,
          static_cast<unsigned long long>(simulation.stepCount()),
          double(iterations) / double(stepsSinceSample), e.average, e.max,
          simulation.stepper().statistics().averageDensityError);
        iterations = stepsSinceSample = 0;
        nextSample += densityDT * std::max(1.0, std::floor((T - nextSample) / densityDT) + 1);
      }
    };
    const auto front = runFront(simulation, setup.timeScale, experiment.back().Z + 0.05,
      1.5 * experiment.back().T, afterStep);
    if (density)
    {
      std::fclose(density);
    }
    if (options.extra.count("front"))
    {
      FILE* out = openOutput(options.extra["front"], "front");
      std::fprintf(out, "T,Z,Z_floor\n");
      for (std::size_t k = 0; k < front.size(); ++k)
      {
        std::fprintf(out, "%.5f,%.5f,%.5f\n", front[k].T, front[k].Z, floorFront[k]);
      }
      std::fclose(out);
    }
    printComparison(front, experiment, across, simulation, setup.parameters.timeStep);
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_martin_moyce: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
