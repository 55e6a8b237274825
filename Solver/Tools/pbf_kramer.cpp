// pbf_kramer: the floating sphere of Kramer et al. (2021) (Kramer.h) at one or more spacings,
// dropped from each of the record's heights: first a run let go at its rest finds where the
// sphere floats at that spacing, then each drop's heave from that rest against the record. Prints
// per drop the first three heave periods against the record's and the heave's RMS error over the
// window; --csv writes the heaves beside the records. Documentation/ValidationBoundaries.md has
// the figures.
#include "Kramer.h"

#include "ToolOptions.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>

using namespace pbf;
using namespace pbf::validation;

namespace
{

// The record files by their drop (in diameters).
const char* recordFile(double drop)
{
  if (std::abs(drop - 0.1) < 1e-9)
  {
    return "kramer_2021_sphere_01D_H0-30mm_rep2.csv";
  }
  if (std::abs(drop - 0.3) < 1e-9)
  {
    return "kramer_2021_sphere_03D_H0-90mm_rep1.csv";
  }
  if (std::abs(drop - 0.5) < 1e-9)
  {
    return "kramer_2021_sphere_05D_H0-150mm_rep1.csv";
  }
  throw InvalidInput("--drops: " + std::to_string(drop) + " has no record (0.1, 0.3 or 0.5)");
}

double seconds(std::chrono::steady_clock::time_point since)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

} // namespace

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "records", "folder of the kramer_2021_sphere_*.csv records (required)" },
    { "spacings", "comma-separated particle spacings [m] (default 0.02: 15 per diameter)" },
    { "drops", "comma-separated drops in diameters, of 0.1, 0.3, 0.5 (default all three)" },
    { "window", "compared time from the release [s] (default 2.6)" },
    { "sample", "sampling interval [s] (default 0.004)" },
    { "side", "the square tank's side [m] (default 2.4)" },
    { "depth", "the water's depth [m] (default 0.9)" },
    { "csv", "write t, heave and the record's heave of every drop to this file" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    if (!options.extra.count("records"))
    {
      throw InvalidInput("--records is required\n" + toolUsage(keys));
    }
    const std::string folder = options.extra["records"];
    const std::vector<double> spacings = toolReals(options, "spacings", 0.02);
    std::vector<double> drops = { 0.1, 0.3, 0.5 };
    if (options.extra.count("drops"))
    {
      drops = toolReals(options, "drops", 0.3);
    }
    const double window = toolReal(options, "window", 2.6);
    const double sample = toolReal(options, "sample", 0.004);
    KramerTank tank;
    tank.side = toolReal(options, "side", tank.side);
    tank.depth = toolReal(options, "depth", tank.depth);
    std::ofstream csv;
    if (options.extra.count("csv"))
    {
      csv.open(options.extra["csv"]);
      csv << "spacing,drop_D,t_s,heave_m,record_m\n";
    }
    std::printf("spacing,drop_D,particles,rest_offset_mm,T1,T1_record,T2,T2_record,T3,"
                "T3_record,worst_period_%%,rms_%%drop,seconds\n");
    for (double s : spacings)
    {
      Parameters p = options.parameters;
      p.particleSpacing = s;
      // Where the sphere floats at this spacing: let go at the lattice's level.
      auto start = std::chrono::steady_clock::now();
      const KramerRun still =
        runKramer(p, options.backend, options.precision, tank, tank.depth, window, sample);
      const double settled = settledCentre(still);
      std::printf("# s = %g: let go at the level %.4f m, settles at %.4f m (%.1f s)\n", s,
        tank.depth, settled, seconds(start));
      for (double drop : drops)
      {
        const TimeSeries record = readKramerRecord(folder + "/" + recordFile(drop));
        const double x0 = record.value.front();
        // The start, and the rest of a run with that start's water (the sphere held higher
        // displaces less of the lattice), once more for the count at the start found.
        double centre = settled + x0;
        std::size_t particles = kramerParticles(p, tank, centre);
        centre = kramerRest(tank, s, settled, still.particles, particles) + x0;
        particles = kramerParticles(p, tank, centre);
        const double rest = kramerRest(tank, s, settled, still.particles, particles);
        start = std::chrono::steady_clock::now();
        const KramerRun run =
          runKramer(p, options.backend, options.precision, tank, centre, window, sample);
        TimeSeries heave = run.centre;
        for (double& y : heave.value)
        {
          y -= rest;
        }
        const KramerComparison c = compareKramer(heave, record, window);
        double worst = 0;
        for (int k = 0; k < 3; ++k)
        {
          // A period the heave never completed counts as missed (NaN), not as 0.
          const double miss = std::abs(c.period[k] / c.recordPeriod[k] - 1);
          worst = std::isnan(miss) || std::isnan(worst) ? std::nan("") : std::max(worst, miss);
        }
        std::printf("%g,%g,%zu,%+.2f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.2f,%.2f,%.1f\n", s, drop,
          run.particles, 1e3 * (settled - still.start), c.period[0], c.recordPeriod[0],
          c.period[1], c.recordPeriod[1], c.period[2], c.recordPeriod[2], 100 * worst,
          100 * c.rms / x0, seconds(start));
        std::fflush(stdout);
        for (std::size_t k = 0; csv.is_open() && k < heave.t.size(); ++k)
        {
          csv << s << "," << drop << "," << heave.t[k] << "," << heave.value[k] << ","
              << record.at(heave.t[k]) << "\n";
        }
      }
    }
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_kramer: " << error.what() << "\n";
    return 2;
  }
  return 0;
}
