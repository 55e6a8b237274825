// pbf_sessile: a drop resting on the floor without gravity (SessileDrop.h), at one or more
// contact angles (--angles) and spacings: the angle its surface makes with the floor, read from
// the cap's volume and centroid, against the one set (Parameters::contactAngle).
// Documentation/ValidationInterfaces.md has the figures.
#include "SessileDrop.h"

#include "ToolOptions.h"

#include <chrono>
#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "spacings", "comma-separated particle spacings [m] (default 0.005)" },
    { "radius", "the hemisphere's radius [m] (default 0.05)" },
    { "angles", "comma-separated contact angles [degrees] (default 45,90,135)" },
    { "until", "simulated time [s] (default 4)" },
    { "average", "the last seconds the angle is averaged over (default 1)" },
    { "sample", "sampling interval [s] (default 0.05)" },
    { "on-solid", "1: the drop rests on a solid slab (an obstacle) with the angle, not the wall" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    if (!(options.parameters.surfaceTension > 0))
    {
      options.parameters.surfaceTension = 1.0; // a visible default: 1 N/m
    }
    const std::vector<double> spacings = toolReals(options, "spacings", 0.005);
    const std::vector<double> angles = toolReals(options, "angles", 90);
    const double radius = toolReal(options, "radius", 0.05);
    const double until = toolReal(options, "until", 4.0);
    const double average = toolReal(options, "average", 1.0);
    const double sample = toolReal(options, "sample", 0.05);
    const bool onSolid = toolInteger(options, "on-solid", 0, 0) != 0;
    std::printf("spacing,particles,sigma_N_m,set_deg,measured_deg,spread_deg,height_m,steps,seconds\n");
    for (double s : spacings)
    {
      for (double theta : angles)
      {
        Parameters p = options.parameters;
        p.particleSpacing = s;
        p.contactAngle = theta;
        const auto start = std::chrono::steady_clock::now();
        const SessileRun run =
          runSessileDrop(p, options.backend, options.precision, radius, until, average, sample, onSolid);
        const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("%.4g,%zu,%.4g,%.1f,%.1f,%.1f,%.4f,%.0f,%.1f\n", s, run.particles,
          p.surfaceTension, theta, run.angle, run.spread, run.height, run.steps, seconds);
        std::fflush(stdout);
      }
    }
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_sessile: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
