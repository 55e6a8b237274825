// XSPH's bi-Laplacian (Parameters::xsphHyperViscosity): on the particle scale it damps a velocity
// pattern as XSPH's own smoothing does at the same alpha, on a flow's scale far less. (OpenMP
// against serial with it: BackendEquivalenceTest.)
#include "Backends.h"
#include "Scene.h"
#include "Stepper.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

using namespace pbf;

namespace
{

constexpr double kSpacing = 0.02;
constexpr double kHeight = 0.8;
constexpr double kAmplitude = 1e-3; // [m/s]: the projections barely see a pattern this small

// A closed box full of fluid (no free surface), 20 x 40 x 4 particles between mirror walls, no
// gravity, s_corr or vorticity confinement: one step changes the velocities by the smoothing
// alone (a shear flow does not compress the lattice, and the checkerboard's compression cancels
// to first order by symmetry). The scene speed is given, as gravity would give it.
Scene fullBox()
{
  return parseScene(R"({
    "domain": { "min": [0, 0, 0], "max": [0.4, 0.8, 0.08] },
    "fluid": [ { "type": "box", "min": [0, 0, 0], "max": [0.4, 0.8, 0.08] } ] })");
}

Parameters smoothingOnly(double alpha, double alpha4)
{
  Parameters p;
  p.particleSpacing = kSpacing;
  p.gravity = { 0, 0, 0 };
  p.sCorrK = 0;
  p.vorticityEpsilon = 0;
  p.solverIterations = 1;
  p.densityErrorTolerance = 0;
  p.xsphViscosity = alpha;
  p.xsphHyperViscosity = alpha4;
  p.sceneSpeedHint = 4.0; // the dam break's fall speed: c = c_4 = 0.44 per step at alpha 0.05
  return withSceneDomain(p, fullBox());
}

using Pattern = std::function<double(const Vec3d&)>;

// How much of `pattern` (v_x = A pattern(x)) one step of 1/240 s removes: 1 - A' / A, A' the
// pattern's least-squares amplitude afterwards over the particles more than 3 h from the walls
// across the flow (x = 0 and 0.4 m), which stop the flow next to them.
double decayPerStep(const Pattern& pattern, double alpha, double alpha4)
{
  const Parameters p = smoothingOnly(alpha, alpha4);
  ParticleBatch initial = fillScene(fullBox(), p);
  for (std::size_t i = 0; i < initial.position.size(); ++i)
  {
    initial.velocity[i] = { kAmplitude * pattern(initial.position[i]), 0, 0 };
  }
  auto stepper = makeStepper(Backend::Serial, Precision::Double, p, initial);
  stepper->setTimeStep(1.0 / 240.0);
  stepper->step();
  Snapshot<double> after;
  stepper->read(after);
  double projected = 0, norm = 0;
  for (std::size_t i = 0; i < after.position.size(); ++i)
  {
    // The pattern at the particle's start: one step moves it by 4e-6 of a spacing.
    const Vec3d start = initial.position[static_cast<std::size_t>(after.id[i])];
    if (start.x < 0.12 || start.x > 0.28)
    {
      continue;
    }
    const double phi = pattern(start);
    projected += after.velocity[i].x * phi;
    norm += phi * phi;
  }
  return 1.0 - projected / norm / kAmplitude;
}

// A shear flow one box height long (k h = 0.31), even about the floor and the lid as the mirror
// walls are.
double longWave(const Vec3d& x)
{
  return std::cos(2.0 * 3.14159265358979323846 * x.y / kHeight);
}

// The finest pattern the lattice holds: the sign alternates between neighbouring particles.
double checkerboard(const Vec3d& x)
{
  const long sum = std::lround(x.x / kSpacing - 0.5) + std::lround(x.y / kSpacing - 0.5) +
    std::lround(x.z / kSpacing - 0.5);
  return sum % 2 == 0 ? 1.0 : -1.0;
}

} // namespace

TEST(XsphFilter, TheBiLaplacianDampsParticleScaleNoiseAsXsphDoesAndAFlowFarLess)
{
  const double alpha = 0.05;
  const double noiseXsph = decayPerStep(checkerboard, alpha, 0);
  const double noiseHyper = decayPerStep(checkerboard, 0, alpha);
  const double flowXsph = decayPerStep(longWave, alpha, 0);
  const double flowHyper = decayPerStep(longWave, 0, alpha);
  std::printf("decay per step at alpha %.2f: checkerboard XSPH %.4f, bi-Laplacian %.4f; long wave "
              "XSPH %.3g, bi-Laplacian %.3g\n",
    alpha, noiseXsph, noiseHyper, flowXsph, flowHyper);
  // A pattern multiplied by -g under XSPH's sum is damped by c g and c_4 g^2, c = c_4 = 0.44
  // here. The checkerboard has g = 1.04 in the bulk (less at the walls): both remove about 40 %
  // of it a step, within a third of each other.
  EXPECT_GT(noiseXsph, 0.2);
  EXPECT_GT(noiseHyper, 0.7 * noiseXsph);
  EXPECT_LT(noiseHyper, 1.4 * noiseXsph);
  // The long wave has g = beta (k h)^2 = 0.0047: XSPH removes 0.2 % of it a step, the
  // bi-Laplacian g times less (1e-5); anything within a twentieth of XSPH's would not be a
  // bi-Laplacian.
  EXPECT_GT(flowXsph, 1e-3);
  EXPECT_LT(std::abs(flowHyper), 0.05 * flowXsph);
}
