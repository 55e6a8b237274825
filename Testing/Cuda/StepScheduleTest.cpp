// The CUDA backend's step schedule, run on the host: it must reproduce the serial backend bit for
// bit, with neighbour masks (any skin, so any number of rebuilds) and with the cell walk. This
// runs everywhere (label "solver"); the GPU itself is tested in CudaStepperTest.cpp.
#include "HostExecutor.h"

#include "Cuda/NeighborMasks.h"
#include "Cuda/StepSchedule.h"
#include "Scene.h"
#include "Stepper.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

// The schedule on host memory, laid out as CudaStepper lays out device memory.
template <class Real>
class HostSchedule
{
public:
  HostSchedule(const Parameters& parameters, const ParticleBatch& initial, bool masks, double skin,
    bool backwards)
    : exec_(backwards)
    , n_(initial.position.size())
  {
    const double h = parameters.smoothingLength();
    cuda::StepConstants<Real>& k = constants_;
    k.c = Coefficients<Real>::make(parameters);
    k.geometry = makeGridGeometry<Real>(parameters.domain, h);
    k.cellCount = k.geometry.cellCount();
    k.keyBits = 32;
    k.iterations = parameters.solverIterations;
    k.reach2 = static_cast<Real>(h * (1 + skin) * h * (1 + skin));
    const Box& d = parameters.domain;
    const double maxAbs = std::max({ std::abs(d.min.x), std::abs(d.min.y), std::abs(d.min.z),
      std::abs(d.max.x), std::abs(d.max.y), std::abs(d.max.z) });
    k.schedule = MaskSchedule{ skin * h, h, MaskSchedule::roundingBound<Real>(maxAbs), masks };
    k.tolerance = parameters.densityErrorTolerance / 100.0;
    k.maxTolerance = parameters.maxDensityErrorTolerance / 100.0;
    k.inverseRestDensity = 1.0 / parameters.restDensity;
    time_ = StepTime<Real>::make(parameters, calibrateLattice(parameters), parameters.timeStep);
    k.time = &time_;

    for (auto& v : vec_)
    {
      v.resize(n_);
    }
    density_.resize(n_);
    lambda_.resize(n_);
    volume_.resize(n_);
    omegaLength_.resize(n_);
    id_ = initial.id;
    keys_[0].resize(n_);
    keys_[1].resize(n_);
    masks_.resize(masks ? kNeighborRows * n_ : 0);
    offsets_.resize(std::size_t(k.cellCount) + 1);
    moved_.resize(std::max(k.iterations, 1));
    cuda::StepBuffers<Real>& b = buffers_;
    for (int i = 0; i < 4; ++i)
    {
      b.vec[i] = vec_[i].data();
    }
    b.density = density_.data();
    b.lambda = lambda_.data();
    // Stored volumes and |omega| as the CUDA backend keeps them: the serial backend computes them
    // for every pair, and the results must not differ by a bit.
    b.volume = volume_.data();
    b.omegaLength = omegaLength_.data();
    b.id = id_.data();
    b.keys[0] = keys_[0].data();
    b.keys[1] = keys_[1].data();
    b.masks = masks ? masks_.data() : nullptr;
    b.stride = static_cast<std::uint32_t>(n_);
    b.cellOffsets = offsets_.data();
    b.maxMoved = moved_.data();
    b.maskBuilds = &builds_;
    b.adaptive = &adaptive_;
    b.blockSums = nullptr;
    for (std::size_t i = 0; i < n_; ++i)
    {
      vec_[roles_.x][i] = Vec3<Real>::from(initial.position[i]);
      vec_[roles_.v][i] = Vec3<Real>::from(initial.velocity[i]);
    }
    cuda::enqueueEvaluateAtRest(exec_, b, k, count(), roles_, &sortedKeys_);
  }

  void step(int steps)
  {
    for (int s = 0; s < steps; ++s)
    {
      roles_ = cuda::enqueueStep(exec_, buffers_, constants_, count(), roles_, &sortedKeys_);
    }
  }

  Snapshot<Real> read() const
  {
    Snapshot<Real> s;
    s.position = vec_[roles_.x];
    s.velocity = vec_[roles_.v];
    s.density = density_;
    s.lambda = lambda_;
    s.id = id_;
    return s;
  }

  unsigned long long maskBuilds() const { return builds_; }
  const cuda::AdaptiveState& adaptive() const { return adaptive_; }

private:
  std::uint32_t count() const { return static_cast<std::uint32_t>(n_); }

  test::HostExecutor exec_;
  std::size_t n_;
  cuda::StepConstants<Real> constants_{};
  StepTime<Real> time_{};
  cuda::StepBuffers<Real> buffers_{};
  cuda::Roles roles_;
  const CellKey* sortedKeys_ = nullptr;
  // Vec3 buffers double as 64-bit id scratch: allocated by new, so 16-byte aligned.
  std::vector<Vec3<Real>> vec_[4];
  std::vector<Real> density_, lambda_, volume_, omegaLength_;
  std::vector<std::int64_t> id_;
  std::vector<CellKey> keys_[2];
  std::vector<std::uint32_t> masks_, offsets_;
  std::vector<unsigned long long> moved_;
  unsigned long long builds_ = 0;
  cuda::AdaptiveState adaptive_{};
};

template <class Real>
void expectBitIdentical(const Snapshot<Real>& a, const Snapshot<Real>& b)
{
  ASSERT_EQ(a.id, b.id); // the same stable sort orders particles the same way
  const std::size_t n = a.id.size();
  EXPECT_EQ(std::memcmp(a.position.data(), b.position.data(), n * sizeof(a.position[0])), 0);
  EXPECT_EQ(std::memcmp(a.velocity.data(), b.velocity.data(), n * sizeof(a.velocity[0])), 0);
  EXPECT_EQ(std::memcmp(a.density.data(), b.density.data(), n * sizeof(a.density[0])), 0);
  EXPECT_EQ(std::memcmp(a.lambda.data(), b.lambda.data(), n * sizeof(a.lambda[0])), 0);
}

struct Case
{
  const char* scene;
  int iterations;
  bool masks;
  double skin;
  bool backwards;
  double tolerance = 0; // densityErrorTolerance [%]: adaptive mode when > 0
};

template <class Real>
void compareWithSerial(const Case& c, int steps, unsigned long long* builds = nullptr)
{
  Parameters p;
  p.particleSpacing = 0.04;
  p.solverIterations = c.iterations;
  p.densityErrorTolerance = c.tolerance;
  const Scene scene = presetScene(c.scene);
  p = withSceneDomain(p, scene);
  const ParticleBatch initial = fillScene(scene, p);
  const Precision precision = sizeof(Real) == 4 ? Precision::Single : Precision::Double;
  auto serial = makeStepper(Backend::Serial, precision, p, initial);
  HostSchedule<Real> schedule(p, initial, c.masks, c.skin, c.backwards);
  int serialIterations = 0, scheduleIterations = 0;
  for (int s = 0; s < steps; ++s)
  {
    serial->step();
    schedule.step(1);
    serialIterations += serial->lastStep().iterations;
    scheduleIterations += schedule.adaptive().iterations;
  }
  if (c.tolerance > 0)
  {
    EXPECT_EQ(scheduleIterations, serialIterations);
    // The tolerance must both stop some steps early and not others, or nothing was tested.
    EXPECT_LT(serialIterations, steps * c.iterations);
    EXPECT_GT(serialIterations, steps);
  }
  Snapshot<Real> reference;
  serial->read(reference);
  SCOPED_TRACE(std::string(c.scene) + ", " + std::to_string(c.iterations) + " iterations, " +
    (c.masks ? "masks, skin " + std::to_string(c.skin) : std::string("cell walk")) +
    (c.backwards ? ", backwards" : ""));
  expectBitIdentical(reference, schedule.read());
  if (builds)
  {
    *builds = schedule.maskBuilds();
  }
}

} // namespace

TEST(StepSchedule, CellWalkReproducesTheSerialBackendBitForBit)
{
  compareWithSerial<float>({ "dam_break", 4, false, 0.1, false }, 40);
  compareWithSerial<double>({ "blob", 3, false, 0.1, true }, 40);
}

TEST(StepSchedule, NeighborMasksReproduceTheSerialBackendBitForBit)
{
  for (bool backwards : { false, true })
  {
    compareWithSerial<float>({ "dam_break", 4, true, 0.1, backwards }, 60);
    compareWithSerial<double>({ "double_dam_break", 3, true, 0.1, backwards }, 60);
  }
}

TEST(StepSchedule, MasksStayExactWhenEveryPassMustRebuildThem)
{
  // A skin this thin is exceeded by the first corrections, so most passes rebuild: the
  // rebuild path must give the same bits as the walk. The blob falls fast onto the pool.
  unsigned long long thin = 0, thick = 0;
  compareWithSerial<float>({ "blob", 4, true, 1e-4, false }, 60, &thin);
  compareWithSerial<float>({ "blob", 4, true, 0.5, false }, 60, &thick);
  // One build at rest plus at least one per step; the thin skin must rebuild far more often.
  EXPECT_GE(thick, 61u);
  EXPECT_GT(thin, 2 * thick);
}

TEST(StepSchedule, AdaptiveIterationsReproduceTheSerialBackendBitForBit)
{
  // Steps that meet the tolerance early skip their remaining projections on the device too.
  compareWithSerial<float>({ "dam_break", 6, true, 0.1, false, 0.05 }, 60);
  compareWithSerial<double>({ "blob", 5, false, 0.1, true, 0.05 }, 60);
}

TEST(MaskSchedule, RebuildsExactlyWhenTheBoundCouldBeExceeded)
{
  const double h = 0.04;
  const MaskSchedule schedule{ 0.1 * h, h, 1e-9, 1 };
  auto bits = [](double d) { return MaskSchedule::doubleToBits(d); };
  // 2 * moved must stay under skin - 1e-3 h = 0.0039 m, with the 1e-3 relative margin.
  const unsigned long long small[3] = { bits(0.0005), bits(0.0005), bits(0.0005) };
  EXPECT_TRUE(schedule.rebuildAt(0, small)); // the first pass of a step always builds
  EXPECT_FALSE(schedule.rebuildAt(1, small));
  EXPECT_FALSE(schedule.rebuildAt(3, small)); // 2 * 0.0015 = 0.003 < 0.0039
  const unsigned long long large[3] = { bits(0.001), bits(0.001), bits(0.001) };
  EXPECT_FALSE(schedule.rebuildAt(1, large));
  EXPECT_TRUE(schedule.rebuildAt(2, large));  // 2 * 0.002 = 0.004 > 0.0039: rebuild here
  EXPECT_FALSE(schedule.rebuildAt(3, large)); // 0.001 since that rebuild
  const unsigned long long nan[2] = { bits(std::numeric_limits<double>::quiet_NaN()), bits(0) };
  EXPECT_TRUE(schedule.rebuildAt(1, nan)); // a NaN displacement never passes for small
  EXPECT_GT(bits(std::numeric_limits<double>::quiet_NaN()),
    bits(std::numeric_limits<double>::infinity())); // and wins an integer max over the bits
}
