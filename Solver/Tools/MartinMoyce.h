// The dam break of Martin & Moyce (1952): a column of base a and height 2a (n^2 = 2) collapses
// along a dry floor. Builds the scene at a resolution, tracks the surge front, and compares it
// with the tabulated experiment (shared/validation/martin_moyce_1952_surge_front_n2.csv).
#pragma once

#include "Parameters.h"
#include "Scene.h"
#include "Simulation.h"

#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace pbf::validation
{

constexpr double kColumnWidth = 0.05715; // a = 2.25 in [m]

struct FrontSample
{
  double T; // t sqrt(2 g / a)
  double Z; // x_front / a
};

struct MartinMoyceSetup
{
  Scene scene;
  Parameters parameters;
  double timeScale; // sqrt(2 g / a): T = t * timeScale
};

// particlesAcross = a / s. The column is 2a high and a few spacings deep (mirror walls make the
// thin slab behave as the 2-D flow of the experiment's wide tank).
MartinMoyceSetup martinMoyce(int particlesAcross, const Parameters& base = Parameters());

// Z of the farthest particle from the back wall: its centre plus s/2, the half spacing the
// lattice leaves between the centres and the fluid's edge (so Z = 1 at T = 0). With maxHeight,
// only particles whose centre is at most that high above the floor count (a check that the
// front is the tongue along the floor, not a splash above it).
double surgeFront(const Simulation& simulation,
  double maxHeight = std::numeric_limits<double>::infinity());

std::vector<FrontSample> readExperiment(const std::string& csvPath);

// The simulated time at which the front first reaches each tabulated Z (linear interpolation
// between samples), plus `shift`, and the RMS of (T_sim + shift - T_exp) / T_exp over the
// tabulated points. shift = 0 is the data's own convention (T = 0 at release); a shift moves the
// simulation's time origin (the supplementary view: the experiment's column took a while to be
// released). Points the simulation never reached count as missing: the RMS is then infinity.
struct FrontComparison
{
  std::vector<double> simulatedT; // per experimental point, shift included; NaN when never reached
  double shift = 0;
  double rmsRelativeError = 0;
};
FrontComparison compareFront(const std::vector<FrontSample>& simulated,
  const std::vector<FrontSample>& experiment, double shift = 0);

// The time-origin shift that fits the simulated arrival times to the experiment's in least
// squares on T: mean(T_exp - T_sim) over the tabulated points (from an unshifted comparison).
double fitTimeShift(const FrontComparison& unshifted, const std::vector<FrontSample>& experiment);

// Runs until the front passes zEnd (or T = tEnd), sampling the front every step; afterStep, when
// given, is called after every step with the step's report.
std::vector<FrontSample> runFront(Simulation& simulation, double timeScale, double zEnd,
  double tEnd, const std::function<void(const AdvanceReport&)>& afterStep = {});

} // namespace pbf::validation
