// The MARIN 3-D dam break with a box (Kleefsman et al. 2005; Data/marin_dam_break.json): water
// heights at the experiment's gauges, and their comparison with the measured records in
// ../shared/validation/marin_2005_H*.csv (Documentation/Validation.md).
#pragma once

#include "Simulation.h"

#include <string>
#include <vector>

namespace pbf::validation
{

// The gauges in the project's axes (y up): H2 between the box and the reservoir, H4 inside it.
struct Gauge
{
  const char* name;
  double x, z; // [m]
};
constexpr Gauge kGaugeH2{ "H2", 0.992, 0.5 };
constexpr Gauge kGaugeH4{ "H4", 2.638, 0.5 };

// The pressure sensors P1-P4 on the box's face towards the reservoir (x = 0.8245 m), 0.471 m
// across the tank, at heights y [m] (marin_2005_pressure.csv's first line gives the source).
constexpr double kSensorX = 0.8245, kSensorZ = 0.471;
constexpr double kSensorHeights[4] = { 0.021, 0.061, 0.101, 0.141 };

struct TimeSeries
{
  std::vector<double> t, value; // [s], [m]
  // Linear interpolation; NaN outside [t.front(), t.back()].
  double at(double time) const;
};

// A measured record: a first line of '#' (the set-up and the source), a header "t,value", rows.
TimeSeries readGaugeRecord(const std::string& csvPath);
// The same with several columns ("t,P1,P2,..."): one series per column after t.
std::vector<TimeSeries> readRecordColumns(const std::string& csvPath);

// The pressure on the box at P1-P4 now [Pa]: Surface/Probes.h's pressure on a solid (the
// boundary model's load spread over its surface), as ParaView's Domain output colours it.
std::vector<double> boxPressure(const Simulation& simulation);

// The water height at the gauge: a probe on the floor below it (Surface/Probes.h's readProbe):
// along the vertical line, the length over which the fluid fraction
// sum_j (m / rho_0) W_poly6(|y - x_j|, h) exceeds `wet` (1/2 unless a study asks for another;
// sampled every s / 4). Air pockets and drops above the free surface count only for what they
// occupy, as a wave gauge's wire measures the wetted length.
constexpr double kWetFraction = 0.5;
double waterHeight(const Simulation& simulation, const Gauge& gauge, double wet = kWetFraction);

struct MarinRun
{
  double spacing = 0;
  std::size_t particles = 0;
  TimeSeries h2, h4;
  // H2 after every solver step until it first passes kArrivalHeight: the arrival at the
  // resolution of the step (about 1 ms at 1 cm) rather than of the samples (10 ms, which is
  // 2.8 % of the arrival time, half the criterion's 5 %). Reading it changes no step.
  TimeSeries h2Steps;
  std::vector<TimeSeries> pressure; // P1-P4 at the samples [Pa]
};
// Runs Data/marin_dam_break.json at `parameters` (its spacing, its solver settings) to `until`
// [s], sampling both gauges every `sampleInterval` [s] and H2 every step until the first wave.
// `wet`: the gauges' fluid fraction (waterHeight). `wallHeight` > 0 raises the domain's top to it
// [m], above where the water climbs: the tank without its roof (Validation.md measures what the
// roof does to the gauges).
MarinRun runMarin(const Parameters& parameters, Backend backend, Precision precision,
  double until, double sampleInterval, double wet = kWetFraction, double wallHeight = 0);

struct MarinComparison
{
  // [s] first time H2 exceeds kArrivalHeight, simulated: from h2Steps, or from the samples of a
  // run that has none (one not made by runMarin)
  double arrivalH2 = 0;
  double arrivalH2Experiment = 0; // [s] the same in the record (at full rate when given)
  double rmsH2 = 0, rmsH4 = 0;    // [m] over the samples up to the run's end
};
constexpr double kArrivalHeight = 0.01; // [m]: the first wave, clear of the gauge's noise
// recordH2Arrival: the record around the first wave at its full rate (marin_2005_H2_arrival.csv;
// marin_2005_H2.csv keeps every 13th row); null: the arrival from recordH2.
// A pressure sensor's first impact, simulated against measured: the largest pressure over
// t < 1 s and when, and the first time it exceeds kImpactPressure. The record is read at its
// rate (4 ms) and also averaged over the run's sampling interval (what the samples can see).
struct ImpactComparison
{
  double peak = 0, peakTime = 0, arrival = 0;                         // simulated
  double peakExperiment = 0, peakTimeExperiment = 0, arrivalExperiment = 0;
  double peakExperimentAveraged = 0; // the record's mean over each sampling interval, largest
};
constexpr double kImpactPressure = 1000.0; // [Pa]: the first wave, clear of the sensors' noise
ImpactComparison compareImpact(const TimeSeries& simulated, const TimeSeries& record);

MarinComparison compareMarin(const MarinRun& run, const TimeSeries& recordH2,
  const TimeSeries& recordH4, const TimeSeries* recordH2Arrival = nullptr);

} // namespace pbf::validation
