#include "MartinMoyce.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace pbf::validation
{

MartinMoyceSetup martinMoyce(int particlesAcross, const Parameters& base)
{
  const double a = kColumnWidth;
  const double s = a / particlesAcross;
  MartinMoyceSetup setup;
  setup.parameters = base;
  setup.parameters.particleSpacing = s;
  const double g = length(base.gravity);
  setup.timeScale = std::sqrt(2 * g / a);
  // The front outruns the column's free-fall speed sqrt(2 g 2a) only slightly: 0.25 h per step
  // at that speed keeps the neighbourhood changes per step small at every resolution.
  const double speed = std::sqrt(2 * g * 2 * a);
  setup.parameters.timeStep = 0.25 * setup.parameters.smoothingLength() / speed;

  const double depth = 4 * s;
  Scene& scene = setup.scene;
  scene.name = "martin_moyce_n2";
  scene.description = "Martin & Moyce (1952) dam break, n^2 = 2";
  scene.domain = { { 0, 0, 0 }, { 6 * a, 3 * a, depth } };
  scene.boxes.push_back({ { 0, 0, 0 }, { a, 2 * a, depth }, { 0, 0, 0 } });
  return setup;
}

double surgeFront(const Simulation& simulation, double maxHeight)
{
  Snapshot<double> snapshot;
  simulation.stepper().read(snapshot);
  const Parameters& p = simulation.parameters();
  double front = -std::numeric_limits<double>::infinity();
  for (const Vec3d& x : snapshot.position)
  {
    if (x.y - p.domain.min.y <= maxHeight)
    {
      front = std::max(front, x.x);
    }
  }
  return (front - p.domain.min.x + 0.5 * p.particleSpacing) / kColumnWidth;
}

std::vector<FrontSample> readExperiment(const std::string& csvPath)
{
  std::ifstream in(csvPath);
  if (!in)
  {
    throw std::runtime_error("cannot open " + csvPath);
  }
  std::vector<FrontSample> samples;
  std::string line;
  std::getline(in, line); // header T,Z
  while (std::getline(in, line))
  {
    if (line.empty())
    {
      continue;
    }
    std::istringstream fields(line);
    FrontSample sample;
    char comma = 0;
    if (!(fields >> sample.T >> comma >> sample.Z) || comma != ',')
    {
      throw std::runtime_error("bad line in " + csvPath + ": " + line);
    }
    samples.push_back(sample);
  }
  return samples;
}

FrontComparison compareFront(const std::vector<FrontSample>& simulated,
  const std::vector<FrontSample>& experiment, double shift)
{
  FrontComparison result;
  result.shift = shift;
  double sum = 0;
  for (const FrontSample& e : experiment)
  {
    double t = std::numeric_limits<double>::quiet_NaN();
    for (std::size_t k = 1; k < simulated.size(); ++k)
    {
      if (simulated[k].Z >= e.Z && simulated[k - 1].Z < e.Z)
      {
        const double f = (e.Z - simulated[k - 1].Z) / (simulated[k].Z - simulated[k - 1].Z);
        t = simulated[k - 1].T + f * (simulated[k].T - simulated[k - 1].T) + shift;
        break;
      }
    }
    result.simulatedT.push_back(t);
    const double relative = (t - e.T) / e.T;
    sum += relative * relative;
  }
  result.rmsRelativeError = std::isnan(sum) ? std::numeric_limits<double>::infinity()
                                            : std::sqrt(sum / double(experiment.size()));
  return result;
}

double fitTimeShift(const FrontComparison& unshifted, const std::vector<FrontSample>& experiment)
{
  double sum = 0;
  for (std::size_t k = 0; k < experiment.size(); ++k)
  {
    sum += experiment[k].T - (unshifted.simulatedT[k] - unshifted.shift);
  }
  return sum / double(experiment.size()); // NaN when a point was never reached
}

std::vector<FrontSample> runFront(Simulation& simulation, double timeScale, double zEnd,
  double tEnd, const std::function<void(const AdvanceReport&)>& afterStep)
{
  std::vector<FrontSample> samples;
  samples.push_back({ 0.0, surgeFront(simulation) });
  while (samples.back().Z < zEnd && samples.back().T < tEnd)
  {
    const AdvanceReport report = simulation.advance(1);
    if (afterStep)
    {
      afterStep(report);
    }
    samples.push_back({ simulation.time() * timeScale, surgeFront(simulation) });
    if (!simulation.stepper().statistics().finite)
    {
      throw std::runtime_error("non-finite state at step " + std::to_string(simulation.stepCount()));
    }
  }
  return samples;
}

} // namespace pbf::validation
