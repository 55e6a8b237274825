// pbf_channel: an open channel (Channel.h; the "channel" preset unless --scene names another
// scene with an outflow) run to --until: the particle count sampled as it goes, then how steady it
// held from --start on and what came in and went out. Documentation/ValidationBoundaries.md has the figures.
#include "Channel.h"

#include "ToolOptions.h"

#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "ranks", "decomposed ranks, as threads (default 1: none)" },
    { "until", "simulated time [s] (default 60)" },
    { "start", "the time from which the count must hold [s] (default 5)" },
    { "sample", "sampling interval [s] (default 0.5)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    if (!options.given.count("scene"))
    {
      options.scene = "channel";
    }
    const Scene scene = toolScene(options);
    const long ranks = toolInteger(options, "ranks", 1, 1);
    const double until = toolReal(options, "until", 60.0);
    const double start = toolReal(options, "start", 5.0);
    const double sample = toolReal(options, "sample", 0.5);
    const ChannelRun run = runChannel(scene, options.parameters, options.backend,
      options.precision, static_cast<int>(ranks), until, start, sample);
    std::printf("# scene %s, %s, %s precision, %ld rank(s), spacing %g m\n", scene.name.c_str(),
      toString(options.backend), toString(options.precision), ranks,
      options.parameters.particleSpacing);
    std::printf("t_s,particles,removed,released\n");
    for (const ChannelSample& s : run.samples)
    {
      std::printf("%.3f,%zu,%llu,%lld\n", s.time, s.particles,
        static_cast<unsigned long long>(s.removed), static_cast<long long>(s.released));
    }
    std::printf("# from %.3g s: mean %.1f particles, lowest %+.2f %%, highest %+.2f %%; inflow "
                "%.5g m^3/s, outflow %.5g m^3/s (%+.2f %%); %llu steps, %.1f s\n",
      start, run.mean, 100 * run.lowest, 100 * run.highest, run.inflow, run.outflow,
      100 * (run.outflow / run.inflow - 1), static_cast<unsigned long long>(run.steps),
      run.seconds);
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_channel: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
