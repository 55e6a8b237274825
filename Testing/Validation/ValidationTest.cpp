// The validation measurements (Documentation/Validation.md) at sizes CI can afford: the
// Martin & Moyce dam break at 10 and 20 particles across the column, the density error of a
// small hydrostatic tank and of the moving dam break per iteration count, and the adaptive mode.
// Tests named ...Regression are gates at recorded values (any change of the flow fails them and
// must be recorded anew); the others judge by the physics or the experiment, with the criteria of
// the resolution issue. The figures at full size come from validate.py and resolution.py.
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

// The time-origin shift T0 of the Martin & Moyce criteria: fitted once, by least squares on T
// over points 2-15 of the 80-across GPU run (Utilities/validation/resolution.py,
// Documentation/Validation.md), and applied unchanged at every resolution.
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
  // Fixed steps: dt itself; automatic: the CFL number (and the largest step).
  setup.parameters.timeStep *= dtFactor;
  setup.parameters.cflNumber *= dtFactor;
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

// The iteration studies run at the fixed step they were measured at (the scene's: 1/240 s for the
// tank, 0.25 h per step at the collapse speed for the dam break), so that only the count changes.
Parameters withIterations(int n, double tolerancePercent = 0)
{
  Parameters p;
  p.timeStepping = TimeStepping::Fixed;
  p.solverIterations = n;
  p.densityErrorTolerance = tolerancePercent;
  return p;
}

// Largest |T_a - T_b| / T_b over the tabulated points both runs reached.
// The largest |T_a - T_b| / T_b over the tabulated points from `first` on (0: all 15).
double largestRelativeGap(const FrontComparison& a, const FrontComparison& b, std::size_t first = 0)
{
  double worst = 0;
  for (std::size_t k = first; k < a.simulatedT.size(); ++k)
  {
    const double ta = a.simulatedT[k], tb = b.simulatedT[k];
    if (std::isfinite(ta) && std::isfinite(tb))
    {
      worst = std::max(worst, std::abs(ta - tb) / tb);
    }
  }
  return worst;
}

} // namespace

TEST(MartinMoyceRegression, TenAcrossRmsAtItsRecordedValue)
{
  // A regression gate, not agreement with the experiment (the criteria are the next test's): the
  // unshifted RMS of the 10-across front against Martin & Moyce, recorded at 0.0844 (commit
  // 102a888, the defaults of the resolution issue). A few ulps of difference (another compiler,
  // FMA) move an arrival by a fraction of a step (dT 0.035 at 10 across, 0.01 in the RMS at the
  // first point); 0.02 either way allows that twice over, and any real change of the flow, for
  // better or worse, fails it and must be recorded here anew.
  const DamBreakRun run = damBreak(10);
  std::printf("10 across: RMS of relative differences %.4f (shifted by T0 = %.3f: %.4f)\n",
    run.comparison.rmsRelativeError, kReportTimeShift,
    compareFront(run.front, experiment(), kReportTimeShift).rmsRelativeError);
  EXPECT_NEAR(run.comparison.rmsRelativeError, 0.0844, 0.02);
}

TEST(MartinMoyce, TwentyAcrossMeetsTheExperimentCriteria)
{
  // Judged on three things because the 1952 release is not modelled: the late front speed
  // dZ/dT within 5 % of the experiment's, and the RMS over points 2-15 after one time origin
  // shift T0 (fitted once on the 80-across GPU run, Documentation/Validation.md) at most 5 %.
  // The criteria are set at 40 and 80 across (GPU runs, Documentation/Validation.md); 20 across is what
  // CI affords, measured 1.7 % and 4.5 %. The unshifted RMS is reported, not judged.
  const auto data = experiment();
  const DamBreakRun run = damBreak(20);
  const auto& t = run.comparison.simulatedT;
  const std::size_t a = 7, b = data.size() - 1; // Z = 2.56 and 4.11
  const double simulated = (data[b].Z - data[a].Z) / (t[b] - t[a]);
  const double measured = (data[b].Z - data[a].Z) / (data[b].T - data[a].T);
  double sum = 0;
  for (std::size_t k = 1; k < data.size(); ++k) // points 2-15
  {
    ASSERT_TRUE(std::isfinite(t[k])) << "the front never reached Z = " << data[k].Z;
    const double relative = (t[k] + kReportTimeShift - data[k].T) / data[k].T;
    sum += relative * relative;
  }
  const double shiftedRms = std::sqrt(sum / static_cast<double>(data.size() - 1));
  std::printf("20 across: RMS unshifted %.4f; points 2-15 shifted by T0 = %.3f: %.4f; late front "
              "speed dZ/dT %.3f, experiment %.3f\n",
    run.comparison.rmsRelativeError, kReportTimeShift, shiftedRms, simulated, measured);
  EXPECT_NEAR(simulated, measured, 0.05 * measured);
  EXPECT_LE(shiftedRms, 0.05);
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

TEST(IncompressibilityRegression, MoreIterationsLeaveLessCompressionInAHydrostaticTank)
{
  // 1 iteration is not run: it blows up within 15 steps (the report says so).
  TankFigures f[3];
  const int counts[3] = { 2, 4, 8 };
  // Measured 0.846 %, 0.421 %, 0.204 % (with lambda relaxed by omega = 0.71 at h = 2 s, see
  // LatticeCalibration::jacobiRelaxation; 0.425, 0.205, 0.069 % before it). The average is
  // taken over 6 samples of a fluid that never quite stops moving: rounding differences move it
  // by a few %; 1.45 x the measured value catches a projection that got half as effective.
  const double bounds[3] = { 0.0123, 0.0061, 0.0030 };
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

TEST(IncompressibilityRegression, MoreIterationsLeaveLessCompressionInTheMovingDamBreak)
{
  DamBreakRun r[3];
  const int counts[3] = { 2, 4, 8 };
  // Measured 0.748 %, 0.353 %, 0.157 % (mean over ~30 samples of the run; omega as in the tank);
  // margins as in the tank.
  const double bounds[3] = { 0.0108, 0.0051, 0.0023 };
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

// The resolution checks at CI's sizes, with the defaults (automatic steps, adaptive
// iterations): the answer must not depend on the time step, the smoothing ratio or the depth
// in particles. The full-size figures are in Documentation/Validation.md ("Resolution").

TEST(Resolution, HalvingTheStepMovesTheFrontByAtMostTwoPercent)
{
  // CFL 0.4 against 0.2 at 20 across: the arrival times at the tabulated Z.
  const DamBreakRun full = damBreak(20), half = damBreak(20, Parameters(), 0.5);
  const double gap = largestRelativeGap(full.comparison, half.comparison);
  std::printf("20 across, CFL 0.4 vs 0.2: largest arrival-time change %.2f %%\n", 100 * gap);
  EXPECT_LT(gap, 0.02);
}

TEST(Resolution, SmoothingRatiosGiveTheSameFront)
{
  // h / s = 1.5, 2.5 and 3 against 2 at 20 across: within 5 % in T at points 2-15 (Z >= 1.22).
  // The first point (Z = 1.11) lies 2.2 spacings from the column's face at 20 across, where the
  // front is the lattice's corner particle rather than a resolved flow: there h/s 2.5 differs
  // by 4.86 % with XSPH alone (alpha 0.05) and 5.11 % with the defaults, every later point by
  // 3.3 % or less. The full-size check (the dam break at s = 2 cm, Documentation/Validation.md)
  // starts 10 spacings from the face. Point 1 is printed, not judged.
  const DamBreakRun reference = damBreak(20);
  for (double ratio : { 1.5, 2.5, 3.0 })
  {
    Parameters p;
    p.smoothingRatio = ratio;
    const DamBreakRun run = damBreak(20, p);
    const double gap = largestRelativeGap(run.comparison, reference.comparison, 1);
    std::printf("20 across, h/s %.1f vs 2: largest arrival-time change %.2f %% (points 2-15), "
                "%.2f %% (all 15)\n",
      ratio, 100 * gap, 100 * largestRelativeGap(run.comparison, reference.comparison));
    EXPECT_LT(gap, 0.05) << "h/s " << ratio;
  }
}

TEST(Resolution, SmoothingRatiosNeitherExpandNorCollapseATank)
{
  // The hydrostatic tank at s = 0.04 m (15 layers) for 0.5 s. Expansion or collapse moves the
  // fluid's centre of mass: it must stay within 1 % of the column's height (6 mm) of where the
  // lattice had it. The mean neighbour count must stay within 20 % of the lattice's, except at
  // h = 1.5 s, where the cubic lattice's 18 neighbours in the bulk (6 at s, 12 at 1.41 s) are
  // more than a disordered fluid of the same density has (4/3 pi 1.5^3 = 14): the lattice melts
  // and the count drops by about a fifth without any change of volume (measured -22 %).
  for (double ratio : { 1.5, 2.0, 2.5, 3.0 })
  {
    Parameters p;
    p.particleSpacing = 0.04;
    p.smoothingRatio = ratio;
    Simulation simulation(loadSceneFile(PBF_VALIDATION_DIR "/hydrostatic_tank.json"), p,
      Backend::OpenMP, Precision::Single);
    const auto centreHeight = [&] {
      Snapshot<double> s;
      simulation.stepper().read(s);
      double sum = 0;
      for (const Vec3d& x : s.position)
      {
        sum += x.y;
      }
      return sum / double(s.position.size());
    };
    const double startHeight = centreHeight();
    const double startNeighbors = simulation.stepper().statistics().averageNeighbors;
    double worstShift = 0, lowest = startNeighbors, highest = startNeighbors;
    for (int frame = 1; frame <= 30; ++frame)
    {
      simulation.advanceTo(frame / 60.0);
      worstShift = std::max(worstShift, std::abs(centreHeight() - startHeight));
      const double n = simulation.stepper().statistics().averageNeighbors;
      lowest = std::min(lowest, n);
      highest = std::max(highest, n);
    }
    std::printf("tank h/s %.1f: centre of mass moved %.2f mm at most; neighbours %.1f, between "
                "%.1f and %.1f\n",
      ratio, 1e3 * worstShift, startNeighbors, lowest, highest);
    EXPECT_LT(worstShift, 0.006) << "h/s " << ratio;
    EXPECT_LT(highest, 1.2 * startNeighbors) << "h/s " << ratio;
    EXPECT_GT(lowest, (ratio == 1.5 ? 0.75 : 0.8) * startNeighbors) << "h/s " << ratio;
  }
}

TEST(Resolution, TallColumnStaysAtRest)
{
  // 120 layers of s = 5 mm (0.6 m, 4 x 4 particles across between mirror walls: a slice of a
  // wide tank), 1 s from the lattice. The required bounds: mean compression <= 0.5 %, max <= 5 %,
  // max speed <= 0.25 m/s. Measured at 0.2 % tolerance: mean 0.2 %, max 0.7 %, 0.05 m/s,
  // 9.4 iterations per step. With Chebyshev's acceleration (chebyshevRho 0.8) the same column
  // must hold the same bounds in fewer projections: measured 5.6 a step, 0.03 m/s; without the
  // blend it would need the plain count, so at most 0.75 of it fails on a lost acceleration.
  Scene column;
  column.name = "tall_column";
  column.domain = { { 0, 0, 0 }, { 0.02, 0.7, 0.02 } };
  column.boxes.push_back({ { 0, 0, 0 }, { 0.02, 0.6, 0.02 }, { 0, 0, 0 } });
  double plainPerStep = 0;
  for (double rho : { 0.0, 0.8 })
  {
    Parameters p;
    p.particleSpacing = 0.005;
    p.chebyshevRho = rho;
    Simulation simulation(column, p, Backend::OpenMP, Precision::Single);
    ASSERT_EQ(simulation.stepper().size(), 4u * 120u * 4u);
    AdvanceReport total;
    for (int frame = 1; frame <= 60; ++frame)
    {
      total.add(simulation.advanceTo(frame / 60.0));
    }
    const DensityError e = densityErrorNow(simulation);
    const double speed = simulation.stepper().statistics().maxSpeed;
    const double perStep = double(total.iterations) / double(total.steps);
    std::printf("120-layer column after 1 s, chebyshevRho %.1f: mean %.3f %%, max %.3f %%, max "
                "speed %.4f m/s, %.2f iterations per step, %lu steps\n",
      rho, 100 * e.average, 100 * e.max, speed, perStep, static_cast<unsigned long>(total.steps));
    EXPECT_LE(e.average, 0.005) << "chebyshevRho " << rho;
    EXPECT_LE(e.max, 0.05) << "chebyshevRho " << rho;
    EXPECT_LE(speed, 0.25) << "chebyshevRho " << rho;
    if (rho == 0.0)
    {
      plainPerStep = perStep;
    }
    else
    {
      EXPECT_LE(perStep, 0.75 * plainPerStep);
    }
  }
}
