#include "Marin.h"

#include "Probes.h"
#include "Scene.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace pbf::validation
{

double TimeSeries::at(double time) const
{
  if (t.empty() || !(time >= t.front()) || !(time <= t.back()))
  {
    return std::numeric_limits<double>::quiet_NaN();
  }
  std::size_t k = 1;
  while (k < t.size() && t[k] < time)
  {
    ++k;
  }
  if (k == t.size())
  {
    return value.back();
  }
  const double w = t[k] > t[k - 1] ? (time - t[k - 1]) / (t[k] - t[k - 1]) : 0.0;
  return value[k - 1] + w * (value[k] - value[k - 1]);
}

std::vector<TimeSeries> readRecordColumns(const std::string& csvPath)
{
  std::ifstream in(csvPath);
  if (!in)
  {
    throw InvalidInput("record \"" + csvPath + "\": cannot be opened");
  }
  std::vector<TimeSeries> columns;
  std::string line;
  while (std::getline(in, line))
  {
    if (line.empty() || line[0] == '#' || line[0] == 't')
    {
      continue;
    }
    std::istringstream row(line);
    std::vector<double> values;
    std::string cell;
    while (std::getline(row, cell, ','))
    {
      values.push_back(std::stod(cell));
    }
    if (values.size() < 2 || (!columns.empty() && values.size() != columns.size() + 1))
    {
      throw InvalidInput("record \"" + csvPath + "\": bad row \"" + line + "\"");
    }
    columns.resize(values.size() - 1);
    for (std::size_t c = 0; c < columns.size(); ++c)
    {
      columns[c].t.push_back(values[0]);
      columns[c].value.push_back(values[c + 1]);
    }
  }
  if (columns.empty() || columns[0].t.size() < 2)
  {
    throw InvalidInput("record \"" + csvPath + "\": fewer than 2 rows");
  }
  return columns;
}

std::vector<double> boxPressure(const Simulation& simulation)
{
  Snapshot<double> state;
  simulation.stepper().read(state);
  const ParticleSums sums(simulation.parameters(), state.position.data(), state.velocity.data(),
    state.pressure.data(), state.position.size());
  std::vector<Vec3d> sensors;
  for (double y : kSensorHeights)
  {
    sensors.push_back(Vec3d{ kSensorX, y, kSensorZ });
  }
  std::vector<double> pressure;
  sums.onSolids(simulation.surfaceSolids(simulation.time()), sensors,
    std::vector<int>(sensors.size(), 0), pressure);
  return pressure;
}

TimeSeries readGaugeRecord(const std::string& csvPath)
{
  std::ifstream in(csvPath);
  if (!in)
  {
    throw InvalidInput("gauge record \"" + csvPath + "\": cannot be opened");
  }
  TimeSeries series;
  std::string line;
  while (std::getline(in, line))
  {
    if (line.empty() || line[0] == '#' || line[0] == 't')
    {
      continue;
    }
    std::istringstream row(line);
    double t = 0, v = 0;
    char comma = 0;
    if (!(row >> t >> comma >> v) || comma != ',')
    {
      throw InvalidInput("gauge record \"" + csvPath + "\": bad row \"" + line + "\"");
    }
    series.t.push_back(t);
    series.value.push_back(v);
  }
  if (series.t.size() < 2)
  {
    throw InvalidInput("gauge record \"" + csvPath + "\": fewer than 2 rows");
  }
  return series;
}

double waterHeight(const Simulation& simulation, const Gauge& gauge, double wet)
{
  Snapshot<double> state;
  simulation.stepper().read(state);
  const Parameters& p = simulation.parameters();
  // The gauge is a probe on the floor (Surface/Probes.h): what a Probes input reads in ParaView.
  const ParticleSums sums(p, state.position.data(), state.velocity.data(), state.pressure.data(),
    state.position.size());
  const Vec3d probe{ gauge.x, p.domain.min.y, gauge.z };
  std::vector<Vec3d> points = gaugeColumn(p, probe);
  points.insert(points.begin(), probe);
  std::vector<double> values;
  sums.at(points, values);
  return readProbe(p, probe, values.data(), values.data() + kProbeSums, points.size() - 1, wet)
    .waterHeight;
}

MarinRun runMarin(const Parameters& parameters, Backend backend, Precision precision,
  double until, double sampleInterval, double wet, double wallHeight)
{
  Scene scene = presetScene("marin_dam_break");
  Parameters p = parameters;
  if (wallHeight > 0)
  {
    // Only the roof moves: the speed scale (the step's floor, XSPH's viscosity) stays the one the
    // 1 m tank gives.
    p.sceneSpeedHint = withSceneDomain(p, scene).sceneSpeed();
    scene.domain.max.y = wallHeight;
  }
  Simulation simulation(scene, p, backend, precision);
  MarinRun run;
  run.spacing = parameters.particleSpacing;
  run.particles = simulation.stepper().size();
  bool arrived = false;
  for (long k = 0;; ++k)
  {
    const double t = static_cast<double>(k) * sampleInterval;
    if (t > until + 1e-12)
    {
      break;
    }
    // Until the first wave has passed H2, step by step (stepToward takes the steps advanceTo
    // would) and read H2 after each.
    AdvanceReport report;
    while (!arrived && simulation.time() < t)
    {
      simulation.stepToward(t, report);
      const double height = waterHeight(simulation, kGaugeH2, wet);
      run.h2Steps.t.push_back(simulation.time());
      run.h2Steps.value.push_back(height);
      arrived = height > kArrivalHeight;
    }
    simulation.advanceTo(t);
    run.h2.t.push_back(t);
    run.h2.value.push_back(waterHeight(simulation, kGaugeH2, wet));
    run.h4.t.push_back(t);
    run.h4.value.push_back(waterHeight(simulation, kGaugeH4, wet));
    const std::vector<double> pressure = boxPressure(simulation);
    run.pressure.resize(pressure.size());
    for (std::size_t k = 0; k < pressure.size(); ++k)
    {
      run.pressure[k].t.push_back(t);
      run.pressure[k].value.push_back(pressure[k]);
    }
  }
  return run;
}

namespace
{

// The first time the series passes `height`, interpolated between samples; NaN when never.
double firstCrossing(const TimeSeries& s, double height)
{
  for (std::size_t k = 1; k < s.t.size(); ++k)
  {
    if (s.value[k] > height && s.value[k - 1] <= height)
    {
      const double w = (height - s.value[k - 1]) / (s.value[k] - s.value[k - 1]);
      return s.t[k - 1] + w * (s.t[k] - s.t[k - 1]);
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double rms(const TimeSeries& simulated, const TimeSeries& record)
{
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < simulated.t.size(); ++k)
  {
    const double measured = record.at(simulated.t[k]);
    if (std::isfinite(measured))
    {
      const double e = simulated.value[k] - measured;
      sum += e * e;
      ++n;
    }
  }
  return n ? std::sqrt(sum / double(n)) : std::numeric_limits<double>::quiet_NaN();
}

} // namespace

ImpactComparison compareImpact(const TimeSeries& simulated, const TimeSeries& record)
{
  ImpactComparison c;
  const auto firstImpact = [](const TimeSeries& s, double& peak, double& when) {
    for (std::size_t k = 0; k < s.t.size() && s.t[k] < 1.0; ++k)
    {
      if (s.value[k] > peak)
      {
        peak = s.value[k];
        when = s.t[k];
      }
    }
  };
  firstImpact(simulated, c.peak, c.peakTime);
  firstImpact(record, c.peakExperiment, c.peakTimeExperiment);
  c.arrival = firstCrossing(simulated, kImpactPressure);
  c.arrivalExperiment = firstCrossing(record, kImpactPressure);
  // The record's mean over windows as long as the run's sampling interval, centred on each
  // simulated sample.
  const double window = simulated.t.size() > 1 ? simulated.t[1] - simulated.t[0] : 0.0;
  for (std::size_t k = 0; k < simulated.t.size() && simulated.t[k] < 1.0; ++k)
  {
    double sum = 0;
    int n = 0;
    for (std::size_t r = 0; r < record.t.size(); ++r)
    {
      if (std::abs(record.t[r] - simulated.t[k]) <= 0.5 * window)
      {
        sum += record.value[r];
        ++n;
      }
    }
    if (n > 0)
    {
      c.peakExperimentAveraged = std::max(c.peakExperimentAveraged, sum / n);
    }
  }
  return c;
}

MarinComparison compareMarin(const MarinRun& run, const TimeSeries& recordH2,
  const TimeSeries& recordH4, const TimeSeries* recordH2Arrival)
{
  MarinComparison c;
  c.arrivalH2 = firstCrossing(run.h2Steps.t.empty() ? run.h2 : run.h2Steps, kArrivalHeight);
  c.arrivalH2Experiment =
    firstCrossing(recordH2Arrival ? *recordH2Arrival : recordH2, kArrivalHeight);
  c.rmsH2 = rms(run.h2, recordH2);
  c.rmsH4 = rms(run.h4, recordH4);
  return c;
}

} // namespace pbf::validation
