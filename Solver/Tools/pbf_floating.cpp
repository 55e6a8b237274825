// pbf_floating: a box of each relative density in still water (Floating.h) at one or more
// spacings, to --until seconds. Prints per run the draft against Archimedes' (r < 1), its drift,
// how far a neutral box (r = 1) strayed, where a dense one (r > 1) came to rest, and, with
// --kick, how the system's energy decays after the box is pushed. Documentation/ValidationBoundaries.md has the
// figures.
#include "Floating.h"

#include "ToolOptions.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "spacings", "comma-separated particle spacings [m] (default 0.02)" },
    { "relative", "comma-separated relative densities (default 0.25,0.5,0.75,1,2)" },
    { "kick", "at 1 s the box is given this downward speed [m/s] (default 0)" },
    { "until", "simulated time [s] (default 5)" },
    { "sample", "sampling interval [s] (default 0.02)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const std::vector<double> spacings = toolReals(options, "spacings", 0.02);
    std::vector<double> relatives = { 0.25, 0.5, 0.75, 1.0, 2.0 };
    if (options.extra.count("relative"))
    {
      relatives = toolReals(options, "relative", 0.5);
    }
    const double kick = toolReal(options, "kick", 0.0);
    const double until = toolReal(options, "until", 5.0);
    const double sample = toolReal(options, "sample", 0.02);
    const double H = kFloatingHeight;
    std::printf("spacing,relative,particles,draft/H,archimedes/H,error%%H,drift%%H,"
                "strayed%%H,bottom_m,speed_m_s,seconds\n");
    for (double s : spacings)
    {
      for (double r : relatives)
      {
        Parameters p = options.parameters;
        p.particleSpacing = s;
        const auto start = std::chrono::steady_clock::now();
        const FloatingRun run = runFloating(p, options.backend, options.precision, r, kick,
          until, sample);
        const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        // The last 30 % of the run, and its drift: the mean over the last 30 % against the 30 %
        // before it.
        const double late = meanOver(run.draft, 0.7 * until, until);
        const double before = meanOver(run.draft, 0.4 * until, 0.7 * until);
        double strayed = 0;
        for (double y : run.centre.value)
        {
          strayed = std::max(strayed, std::abs(y - run.centre.value.front()));
        }
        const double bottom = run.centre.value.back() - 0.5 * H;
        std::printf("%.4g,%.3g,%zu,%.4f,%.4f,%+.2f,%+.2f,%.2f,%.4f,%.4f,%.1f\n", s, r,
          run.particles, late / H, r < 1 ? r : std::nan(""),
          r < 1 ? 100 * (late / H - r) : std::nan(""), 100 * (late - before) / H,
          100 * strayed / H, bottom, std::abs(run.speed.value.back()), seconds);
        if (kick > 0)
        {
          const FloatingRun still =
            runFloating(p, options.backend, options.precision, r, 0.0, until, sample);
          const KickResponse k = kickResponse(run, still);
          std::printf("  kick of %.3f J: %d crossings of the draft; the energy above the run "
                      "without it rose %.2f %% of the kick's at most, %.1f %% of it left at the "
                      "end\n",
            k.kickEnergy, k.crossings, 100 * k.worstRise / k.kickEnergy,
            100 * k.left / k.kickEnergy);
        }
        std::fflush(stdout);
      }
    }
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_floating: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
