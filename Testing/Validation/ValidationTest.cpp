// The validation report's figures (Testing/Validation/README.md) at sizes CI can afford: the
// Martin & Moyce dam break at 10 and 20 particles across the column, the density error of a
// small hydrostatic tank and of the moving dam break per iteration count, and the adaptive mode.
// Bounds are the measured values plus a stated margin; the figures at full size come from
// validate.py.
#include "MartinMoyce.h"
#include "Measures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace pbf;
using namespace pbf::validation;

namespace
{

std::vector<FrontSample> experiment()
{
  return readExperiment(PBF_VALIDATION_DIR "/martin_moyce_1952_surge_front_n2.csv");
}

// The time-origin shift of the report's supplementary view: fitted once, by validate.py, on the
// 80-across run (least squares on T), and applied unchanged at every resolution.
constexpr double kReportTimeShift = PBF_REPORT_TIME_SHIFT;

struct DamBreakRun
{
  std::vector<FrontSample> front;
  FrontComparison comparison;
  double averageError = 0; // the mean compression, averaged over samples through the run
  double maxError = 0;     // the largest compression seen at a sample
  double iterationsPerStep = 0;
};

DamBreakRun damBreak(int across, Parameters p = Parameters(), double dtFactor = 1)
{
  const auto data = experiment();
  MartinMoyceSetup setup = martinMoyce(across, p);
  setup.parameters.timeStep *= dtFactor;
  Simulation simulation(setup.scene, setup.parameters, Backend::OpenMP, Precision::Single);
  DamBreakRun run;
  long iterations = 0, samples = 0;
  run.front = runFront(simulation, setup.timeScale, data.back().Z + 0.05, 1.5 * data.back().T,
    [&](const AdvanceReport& report) {
      iterations += report.iterations;
      if (simulation.stepCount() % 3 == 0)
      {
        const DensityError e = densityErrorNow(simulation);
        run.averageError += e.average;
        run.maxError = std::max(run.maxError, e.max);
        ++samples;
      }
    });
  run.averageError /= double(std::max(samples, 1L));
  run.iterationsPerStep = double(iterations) / double(simulation.stepCount());
  run.comparison = compareFront(run.front, data);
  return run;
}

struct TankFigures
{
  double average = 0; // mean compression, averaged over the window's samples
  double max = 0;     // largest compression in the window
  double iterationsPerStep = 0;
};

// Hydrostatic tank at spacing 0.04 m (15 layers, 1,500 particles): 1 s to settle, then the
// figures over the next 0.25 s, sampled every 10 steps.
TankFigures settledTank(Parameters p)
{
  p.particleSpacing = 0.04;
  Simulation simulation(loadSceneFile(PBF_VALIDATION_DIR "/hydrostatic_tank.json"), p,
    Backend::OpenMP, Precision::Single);
  simulation.advance(240);
  TankFigures f;
  long iterations = 0;
  for (int k = 0; k < 6; ++k)
  {
    iterations += simulation.advance(10).iterations;
    const DensityError e = densityErrorNow(simulation);
    f.average += e.average / 6;
    f.max = std::max(f.max, e.max);
  }
  f.iterationsPerStep = double(iterations) / 60.0;
  return f;
}

Parameters withIterations(int n, double tolerancePercent = 0)
{
  Parameters p;
  p.solverIterations = n;
  p.densityErrorTolerance = tolerancePercent;
  return p;
}

} // namespace

TEST(MartinMoyce, TenAcrossFrontWithinReportedErrorOfExperiment)
{
  const DamBreakRun run = damBreak(10);
  std::printf("10 across: RMS of relative differences %.4f (shifted by %.3f: %.4f)\n",
    run.comparison.rmsRelativeError, kReportTimeShift,
    compareFront(run.front, experiment(), kReportTimeShift).rmsRelativeError);
  // Measured 0.0917. A few ulps of difference (another compiler, FMA) move the front's arrival
  // at a Z by a fraction of a step; a whole step (dT 0.035) at the first point (T = 0.41) would
  // move the RMS by 0.01: 0.11 allows that twice over and still fails a real change.
  EXPECT_LT(run.comparison.rmsRelativeError, 0.11);
}

TEST(MartinMoyce, TwentyAcrossFrontWithinReportedErrorAndLateSpeedOfExperiment)
{
  const auto data = experiment();
  const DamBreakRun run = damBreak(20);
  // Measured 0.1360; the same margin as at 10 across. It is above 10 %: the report says why.
  EXPECT_LT(run.comparison.rmsRelativeError, 0.155);
  // dZ/dT between the tabulated Z = 2.56 and 4.11: the experiment's is (4.11 - 2.56) /
  // (3.33 - 2.20) = 1.37. The simulated front leads in time but runs at nearly the same speed.
  const auto& t = run.comparison.simulatedT;
  const std::size_t a = 7, b = data.size() - 1; // Z = 2.56 and 4.11
  const double simulated = (data[b].Z - data[a].Z) / (t[b] - t[a]);
  const double measured = (data[b].Z - data[a].Z) / (data[b].T - data[a].T);
  std::printf("20 across: RMS of relative differences %.4f; late front speed dZ/dT %.3f, "
              "experiment %.3f\n",
    run.comparison.rmsRelativeError, simulated, measured);
  // Measured 1.334. Within 10 %: the experiment's times are given to 0.01-0.02 in T, 1-2 % of
  // the 1.13 span, and the simulated speed moves by a few % with resolution.
  EXPECT_NEAR(simulated, measured, 0.10 * measured);
}

TEST(MartinMoyce, WithoutTensileTermTheFrontIsConvergedInTheTimeStep)
{
  // The check behind the report's diagnosis: s_corr off, halving dt moves no arrival time by more
  // than 0.05 in T (measured 0.032; one step at 10 across is 0.035 in T, so within about a step),
  // so the time integration is converged and the lead over the experiment is not a time-step
  // artefact. (With s_corr on it is not: at 20 across halving dt takes the lead from 0.25 to 0.6.)
  Parameters p;
  p.sCorrK = 0;
  const DamBreakRun full = damBreak(10, p, 1.0), half = damBreak(10, p, 0.5);
  double worst = 0;
  for (std::size_t k = 0; k < full.comparison.simulatedT.size(); ++k)
  {
    worst = std::max(worst,
      std::abs(full.comparison.simulatedT[k] - half.comparison.simulatedT[k]));
  }
  std::printf("s_corr off, dt vs dt/2 at 10 across: largest arrival-time change %.4f\n", worst);
  EXPECT_LT(worst, 0.05);
}

TEST(Incompressibility, MoreIterationsLeaveLessCompressionInAHydrostaticTank)
{
  // 1 iteration is not run: it blows up within 15 steps (the report says so).
  TankFigures f[3];
  const int counts[3] = { 2, 4, 8 };
  // Measured 0.425 %, 0.205 %, 0.069 %. The average is taken over 6 samples of a fluid that
  // never quite stops moving: rounding differences move it by a few %; 1.45 x the measured
  // value catches a projection that got half as effective.
  const double bounds[3] = { 0.0060, 0.0030, 0.0010 };
  for (int k = 0; k < 3; ++k)
  {
    f[k] = settledTank(withIterations(counts[k]));
    std::printf("tank, %d iterations: average %.4f%%, max %.3f%%\n", counts[k],
      100 * f[k].average, 100 * f[k].max);
    EXPECT_LT(f[k].average, bounds[k]) << counts[k] << " iterations";
  }
  // Each doubling at least 1.5 x less average compression (measured: see the printout and the
  // report); a regression of the projection shows as a smaller ratio long before a reversal.
  EXPECT_LT(f[1].average * 1.5, f[0].average);
  EXPECT_LT(f[2].average * 1.5, f[1].average);
  EXPECT_LT(f[2].max, f[0].max);
}

TEST(Incompressibility, AdaptiveModeKeepsTankWithinTolerance)
{
  const TankFigures f = settledTank(withIterations(100, 0.1));
  std::printf("tank, adaptive at 0.1%%: average %.4f%%, max %.3f%%, %.1f iterations per step\n",
    100 * f.average, 100 * f.max, f.iterationsPerStep);
  // The mode stops once the mean compression is at or below 0.1 %, then commits those positions:
  // measured afresh it is the same figure, summed in another order (1e-12 covers that).
  EXPECT_LE(f.average, 0.001 + 1e-12);
  EXPECT_LT(f.iterationsPerStep, 100.0); // never ran into the cap
}

TEST(Incompressibility, MoreIterationsLeaveLessCompressionInTheMovingDamBreak)
{
  DamBreakRun r[3];
  const int counts[3] = { 2, 4, 8 };
  // Measured 0.313 %, 0.115 %, 0.031 % (mean over ~30 samples of the run); margins as in the
  // tank.
  const double bounds[3] = { 0.0045, 0.0017, 0.00045 };
  for (int k = 0; k < 3; ++k)
  {
    r[k] = damBreak(10, withIterations(counts[k]));
    std::printf("dam break 10 across, %d iterations: average %.4f%%, max %.3f%%\n", counts[k],
      100 * r[k].averageError, 100 * r[k].maxError);
    EXPECT_LT(r[k].averageError, bounds[k]) << counts[k] << " iterations";
  }
  EXPECT_LT(r[1].averageError * 1.5, r[0].averageError);
  EXPECT_LT(r[2].averageError * 1.5, r[1].averageError);
}

TEST(Incompressibility, AdaptiveModeKeepsMovingDamBreakWithinTolerance)
{
  const DamBreakRun r = damBreak(10, withIterations(100, 0.1));
  std::printf("dam break 10 across, adaptive at 0.1%%: average %.4f%%, max %.3f%%, %.1f "
              "iterations per step\n",
    100 * r.averageError, 100 * r.maxError, r.iterationsPerStep);
  EXPECT_LE(r.averageError, 0.001 + 1e-12); // as in the tank
  EXPECT_LT(r.iterationsPerStep, 100.0);
}
