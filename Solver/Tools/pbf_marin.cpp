// pbf_marin: the MARIN dam break with a box (Data/marin_dam_break.json) at one or more spacings.
// Prints, per spacing, the particle count, the first arrival at gauge H2 against the record's, the
// RMS height error at H2 and H4, and the first impact on the box's pressure sensors P1-P4 against
// the record's; optionally writes the simulated series as CSV (t, then H2, H4, P1-P4 per spacing)
// for Utilities/validation/plots.py. Documentation/Validation.md has the figures.
#include "Marin.h"

#include "ToolOptions.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "records", "folder of marin_2005_H2.csv, _H4.csv and _pressure.csv (required)" },
    { "spacings", "comma-separated particle spacings [m] (default 0.02)" },
    { "until", "simulated time [s] (default 6)" },
    { "sample", "gauge sampling interval [s] (default 0.01)" },
    { "csv", "write t, then H2 and H4 per spacing, to this file" },
    { "gauge-fraction", "the fluid fraction above which a gauge's line counts as wet (default 0.5)" },
    { "wall-height", "the tank's top [m] (default: the scene's 1 m roof)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    if (!options.extra.count("records"))
    {
      throw InvalidInput("--records is required\n" + toolUsage(keys));
    }
    const std::string folder = options.extra["records"];
    const TimeSeries h2 = readGaugeRecord(folder + "/marin_2005_H2.csv");
    const TimeSeries h4 = readGaugeRecord(folder + "/marin_2005_H4.csv");
    const TimeSeries h2Arrival = readGaugeRecord(folder + "/marin_2005_H2_arrival.csv");
    const std::vector<TimeSeries> pressureRecord = readRecordColumns(folder + "/marin_2005_pressure.csv");
    const std::vector<double> spacings = toolReals(options, "spacings", 0.02);
    const double until = toolReal(options, "until", 6.0);
    const double sample = toolReal(options, "sample", 0.01);
    const double wet = toolReal(options, "gauge-fraction", kWetFraction);
    const double wallHeight = toolReal(options, "wall-height", 0.0);
    if (!(wet < 1.0))
    {
      throw InvalidInput("--gauge-fraction = " + std::to_string(wet) + ": must be below 1");
    }
    std::vector<MarinRun> runs;
    std::printf("spacing,particles,backend,arrival_H2,arrival_H2_experiment,arrival_relative,"
                "rms_H2,rms_H4,seconds\n");
    for (double s : spacings)
    {
      Parameters p = options.parameters;
      p.particleSpacing = s;
      const auto start = std::chrono::steady_clock::now();
      runs.push_back(runMarin(p, options.backend, options.precision, until, sample, wet, wallHeight));
      const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const MarinComparison c = compareMarin(runs.back(), h2, h4, &h2Arrival);
      std::printf("%.4g,%zu,%s,%.4f,%.4f,%+.4f,%.4f,%.4f,%.1f\n", s, runs.back().particles,
        toString(options.backend), c.arrivalH2, c.arrivalH2Experiment,
        c.arrivalH2 / c.arrivalH2Experiment - 1.0, c.rmsH2, c.rmsH4, seconds);
      for (std::size_t k = 0; k < runs.back().pressure.size() && k < pressureRecord.size(); ++k)
      {
        const ImpactComparison i = compareImpact(runs.back().pressure[k], pressureRecord[k]);
        std::printf("  P%zu: first impact peak %.0f Pa at %.3f s (record %.0f Pa at %.3f s; "
                    "averaged over %g s: %.0f Pa), above %.0f Pa from %.3f s (record %.3f s)\n",
          k + 1, i.peak, i.peakTime, i.peakExperiment, i.peakTimeExperiment, sample,
          i.peakExperimentAveraged, kImpactPressure, i.arrival, i.arrivalExperiment);
      }
      std::fflush(stdout);
    }
    if (options.extra.count("csv"))
    {
      FILE* out = std::fopen(options.extra["csv"].c_str(), "w");
      if (!out)
      {
        throw InvalidInput("--csv = \"" + options.extra["csv"] + "\": cannot be written");
      }
      std::fprintf(out, "t");
      for (const MarinRun& r : runs)
      {
        std::fprintf(out, ",H2_%g,H4_%g,P1_%g,P2_%g,P3_%g,P4_%g", r.spacing, r.spacing, r.spacing,
          r.spacing, r.spacing, r.spacing);
      }
      std::fprintf(out, "\n");
      for (std::size_t k = 0; k < runs.front().h2.t.size(); ++k)
      {
        std::fprintf(out, "%.4f", runs.front().h2.t[k]);
        for (const MarinRun& r : runs)
        {
          std::fprintf(out, ",%.5f,%.5f", r.h2.value[k], r.h4.value[k]);
          for (const TimeSeries& p : r.pressure)
          {
            std::fprintf(out, ",%.1f", p.value[k]);
          }
        }
        std::fprintf(out, "\n");
      }
      std::fclose(out);
    }
    return 0;
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_marin: " << error.what() << "\n";
    return 1;
  }
}
