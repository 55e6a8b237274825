// pbf_droplet: a drop without gravity (Droplet.h) at one or more spacings: a spheroid of liquid
// --elongation longer than the sphere of --radius along x, of its volume, pulls itself round
// under --surface-tension and oscillates; the l = 2 period fitted to its deformation (a damped
// cosine) against Rayleigh's. --series 1 prints the deformation every --sample seconds as well.
// Documentation/ValidationInterfaces.md has the figures.
#include "Droplet.h"

#include "ToolOptions.h"

#include <chrono>
#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "spacings", "comma-separated particle spacings [m] (default 0.01)" },
    { "radius", "the drop's radius [m] (default 0.1)" },
    { "elongation", "the spheroid's long semi-axis over the radius, less 1 (default 0.15)" },
    { "until", "simulated time [s] (default 2.5 Rayleigh periods)" },
    { "sample", "sampling interval [s] (default a 40th of Rayleigh's period)" },
    { "series", "1: print the deformation's samples (default 0)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    if (!(options.parameters.surfaceTension > 0))
    {
      options.parameters.surfaceTension = 1.0; // a visible default: 1 N/m
    }
    const std::vector<double> spacings = toolReals(options, "spacings", 0.01);
    const double radius = toolReal(options, "radius", 0.1);
    const double elongation = toolReal(options, "elongation", 0.15);
    const double theory = rayleighPeriod(
      radius, options.parameters.restDensity, options.parameters.surfaceTension);
    const double until = toolReal(options, "until", 2.5 * theory);
    const double sample = toolReal(options, "sample", theory / 40);
    const bool series = toolInteger(options, "series", 0, 0) != 0;
    std::printf("spacing,particles,sigma_N_m,radius_m,steps,crossings,period_s,rayleigh_s,"
                "error%%,damping_1_s,pressure_Pa,laplace_Pa,seconds\n");
    for (double s : spacings)
    {
      Parameters p = options.parameters;
      p.particleSpacing = s;
      const auto start = std::chrono::steady_clock::now();
      const DropletRun run =
        runDroplet(p, options.backend, options.precision, radius, elongation, until, sample);
      const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (series)
      {
        for (std::size_t i = 0; i < run.t.size(); ++i)
        {
          std::printf("# t=%.4f D=%.4e\n", run.t[i], run.deformation[i]);
        }
      }
      std::printf("%.4g,%zu,%.4g,%.4g,%.0f,%d,%.4f,%.4f,%+.1f,%.3f,%.3g,%.3g,%.1f\n", s,
        run.particles, p.surfaceTension, radius, run.steps, run.crossings, run.period, run.theory,
        100 * (run.period / run.theory - 1), run.damping, run.pressure, run.laplace, seconds);
      std::fflush(stdout);
    }
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_droplet: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
