// The dam break of Martin & Moyce (1952): a column of base a and height 2a (n^2 = 2) collapses
// along a dry floor. Builds the scene at a resolution, tracks the surge front, and compares it
// with the tabulated experiment (shared/validation/martin_moyce_1952_surge_front_n2.csv).
#pragma once

#include "Parameters.h"
#include "Scene.h"
#include "Simulation.h"

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
// lattice leaves between the centres and the fluid's edge (so Z = 1 at T = 0).
double surgeFront(const Simulation& simulation);

std::vector<FrontSample> readExperiment(const std::string& csvPath);

// The simulated time at which the front first reaches each tabulated Z (linear interpolation
// between samples), and the RMS of (T_sim - T_exp) / T_exp over the tabulated points. Points the
// simulation never reached count as missing: returns infinity if any is missing.
struct FrontComparison
{
  std::vector<double> simulatedT; // per experimental point, NaN when never reached
  double rmsRelativeError = 0;
};
FrontComparison compareFront(
  const std::vector<FrontSample>& simulated, const std::vector<FrontSample>& experiment);

// Runs until the front passes the last tabulated Z (or T = tEnd), sampling every step.
std::vector<FrontSample> runFront(Simulation& simulation, double timeScale, double zEnd, double tEnd);

} // namespace pbf::validation
