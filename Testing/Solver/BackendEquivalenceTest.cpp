// The OpenMP backend is bit-identical to the serial reference, and a run is reproducible.
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

using namespace pbf;

namespace
{

template <class Real>
Snapshot<Real> run(Backend backend, Precision precision, const std::string& scene, int steps,
  double xsphHyperViscosity = 0, double chebyshevRho = 0)
{
  Parameters p;
  p.particleSpacing = 0.04;
  p.xsphHyperViscosity = xsphHyperViscosity;
  p.chebyshevRho = chebyshevRho;
  Simulation simulation(presetScene(scene), p, backend, precision);
  simulation.advance(steps);
  Snapshot<Real> s;
  simulation.stepper().read(s);
  return s;
}

} // namespace

TEST(BackendEquivalence, OpenMPIsBitIdenticalToSerialInSinglePrecision)
{
  for (const char* scene : { "dam_break", "stream" })
  {
    test::expectBitIdentical(run<float>(Backend::Serial, Precision::Single, scene, 60),
      run<float>(Backend::OpenMP, Precision::Single, scene, 60));
  }
}

TEST(BackendEquivalence, OpenMPIsBitIdenticalToSerialWithXsphsBiLaplacian)
{
  // The confinement pass then reads every neighbour's XSPH sum (XsphFilterTest).
  test::expectBitIdentical(run<float>(Backend::Serial, Precision::Single, "dam_break", 40, 0.1),
    run<float>(Backend::OpenMP, Precision::Single, "dam_break", 40, 0.1));
}

TEST(BackendEquivalence, OpenMPIsBitIdenticalToSerialWithChebyshevAcceleration)
{
  // Each particle blends only its own positions: the order of the particles does not matter.
  test::expectBitIdentical(
    run<float>(Backend::Serial, Precision::Single, "dam_break", 40, 0.05, 0.8),
    run<float>(Backend::OpenMP, Precision::Single, "dam_break", 40, 0.05, 0.8));
  const Snapshot<double> accelerated =
    run<double>(Backend::Serial, Precision::Double, "dam_break", 40, 0.05, 0.8);
  test::expectBitIdentical(
    accelerated, run<double>(Backend::OpenMP, Precision::Double, "dam_break", 40, 0.05, 0.8));
  // The acceleration changed the flow, so the comparisons say something about it.
  EXPECT_GT(test::maxRelativePositionError(
              run<double>(Backend::Serial, Precision::Double, "dam_break", 40, 0.05), accelerated),
    1e-6);
}

TEST(BackendEquivalence, OpenMPIsBitIdenticalToSerialInDoublePrecision)
{
  test::expectBitIdentical(run<double>(Backend::Serial, Precision::Double, "blob", 60),
    run<double>(Backend::OpenMP, Precision::Double, "blob", 60));
}

TEST(BackendEquivalence, SteppingInPiecesEqualsSteppingAtOnce)
{
  // What the VTK layer relies on when it resumes a simulation instead of restarting it.
  Parameters p;
  p.particleSpacing = 0.04;
  Simulation once(presetScene("dam_break"), p, Backend::OpenMP, Precision::Single);
  once.advance(40);
  Simulation pieces(presetScene("dam_break"), p, Backend::OpenMP, Precision::Single);
  pieces.advance(13);
  pieces.advance(27);
  Snapshot<float> a, b;
  once.stepper().read(a);
  pieces.stepper().read(b);
  test::expectBitIdentical(a, b);
}

TEST(BackendEquivalence, SinglePrecisionTracksDoublePrecision)
{
  // After 20 steps of a dam break the float run stays within 1e-3 m of the double run: float
  // rounding (1e-7 relative) grows through the solver but not to the particle scale (0.04 m).
  const auto a = run<double>(Backend::Serial, Precision::Single, "dam_break", 20);
  const auto b = run<double>(Backend::Serial, Precision::Double, "dam_break", 20);
  const auto index = test::indexById(b);
  ASSERT_EQ(a.id.size(), b.id.size());
  for (std::size_t i = 0; i < a.id.size(); ++i)
  {
    const Vec3d d = a.position[i] - b.position[index.at(a.id[i])];
    ASSERT_LT(length(d), 1e-3);
  }
}

TEST(BackendEquivalence, EveryReportedStatisticIsBitIdenticalWhereSummationOrderMatters)
{
  // At tens of thousands of particles a sum taken in another order (an OpenMP reduction, say)
  // differs in its last bits; at the 3,000 particles of the tests above it often does not. Every
  // statistic the filter reports, and each step's report (the adaptive loop's compression, the
  // projections taken), must be the serial backend's, bit for bit.
  Parameters p;
  p.particleSpacing = 0.015; // 42,632 particles of the dam break
  Simulation serial(presetScene("dam_break"), p, Backend::Serial, Precision::Single);
  Simulation openmp(presetScene("dam_break"), p, Backend::OpenMP, Precision::Single);
  ASSERT_GT(serial.stepper().size(), 40000u);
  auto bits = [](double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  };
  for (int step = 1; step <= 12; ++step)
  {
    serial.advance(1);
    openmp.advance(1);
    const StepReport rs = serial.stepper().lastStep(), ro = openmp.stepper().lastStep();
    EXPECT_EQ(rs.iterations, ro.iterations) << "step " << step;
    EXPECT_EQ(bits(rs.densityError), bits(ro.densityError)) << "step " << step;
    EXPECT_EQ(bits(serial.stepper().timeStep()), bits(openmp.stepper().timeStep())) << "step " << step;
  }
  const Statistics a = serial.stepper().statistics(), b = openmp.stepper().statistics();
  EXPECT_EQ(a.particles, b.particles);
  EXPECT_EQ(bits(a.averageDensityError), bits(b.averageDensityError));
  EXPECT_EQ(bits(a.maxDensityError), bits(b.maxDensityError));
  EXPECT_EQ(bits(a.averageNeighbors), bits(b.averageNeighbors));
  EXPECT_EQ(bits(a.maxSpeed), bits(b.maxSpeed));
  EXPECT_EQ(bits(a.kineticEnergy), bits(b.kineticEnergy));
  EXPECT_EQ(bits(a.momentum.x), bits(b.momentum.x));
  EXPECT_EQ(bits(a.momentum.y), bits(b.momentum.y));
  EXPECT_EQ(bits(a.momentum.z), bits(b.momentum.z));
  EXPECT_EQ(a.finite, b.finite);
  // The sums are not trivially exact here: the state moved and the errors are not all zero.
  EXPECT_GT(a.averageDensityError, 0.0);
  EXPECT_GT(a.kineticEnergy, 0.0);
}
