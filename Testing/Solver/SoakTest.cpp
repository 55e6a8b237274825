// Soak runs: every shipped scene for PBF_SOAK_STEPS steps on the OpenMP backend at a coarse
// spacing, checking every 100 steps what must never change: the particle count (the initial
// ones plus exactly what the emitters' rule releases), ids 0..N-1 each once, every particle in
// the domain, nothing NaN, and flat memory once the emitters are done. The divergence check runs
// every step too (Simulation's default), so the shipped scenes must never trip it.
// Built twice: pbf_solver_tests runs 500 steps (label "solver"), pbf_soak_tests 10,000 (label
// "long", not in CI).
#include "TestScenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <unistd.h>

#ifndef PBF_SOAK_STEPS
#ifdef PBF_SANITIZE
#define PBF_SOAK_STEPS 200 // the sanitizers make a step 6 x slower
#else
#define PBF_SOAK_STEPS 500
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define PBF_SOAK_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PBF_SOAK_ASAN 1
#endif
#endif
#ifdef PBF_SOAK_LONG
#define PBF_SOAK_SUITE SoakLong
#else
#define PBF_SOAK_SUITE Soak
#endif

using namespace pbf;

namespace
{

constexpr std::uint64_t kSampleEvery = 100;
// RSS may move by a few pages (allocator bookkeeping, the test's own output); a leak of the
// smallest per-step allocation (one Vec3 per particle, 14 KB here) would pass this in 75 steps.
constexpr double kRssToleranceBytes = 1 << 20;

double residentBytes()
{
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE));
}

// How many particles the emitters have released by time t, from the rule in Data/README.md:
// one disk of lattice sites, (a^2 + b^2) s^2 <= r^2, every s / speed seconds from start, while
// start <= release < stop. {lo, hi}: a release within rounding of t may fall either side of it.
std::pair<std::int64_t, std::int64_t> expectedEmitted(const Scene& scene, double s, double t)
{
  std::int64_t lo = 0, hi = 0;
  for (const Emitter& e : scene.emitters)
  {
    const long n = static_cast<long>(std::floor(e.radius / s));
    std::int64_t perLayer = 0;
    for (long a = -n; a <= n; ++a)
    {
      for (long b = -n; b <= n; ++b)
      {
        perLayer += (a * a + b * b) * s * s <= e.radius * e.radius ? 1 : 0;
      }
    }
    const double interval = s / e.speed;
    for (std::int64_t k = 0;; ++k)
    {
      const double release = e.start + static_cast<double>(k) * interval;
      if (release >= e.stop - 1e-9 || release > t + 1e-9)
      {
        break;
      }
      hi += perLayer;
      lo += release < t - 1e-9 ? perLayer : 0;
    }
  }
  return { lo, hi };
}

// What was seen over a run.
struct Figures
{
  std::size_t startParticles = 0, endParticles = 0;
  double seconds = 0, startRss = 0, baselineRss = 0, endRss = 0, maxRss = 0;
  double maxSpeed = 0, maxDensityError = 0;
};

void soak(const std::string& name, std::uint64_t steps, Figures& f)
{
  Parameters p;
  p.particleSpacing = 0.05;
  const Scene scene = presetScene(name);
  Simulation simulation(scene, p, Backend::OpenMP, Precision::Single);
  EXPECT_EQ(simulation.divergenceCheckInterval(), 1u);
  // Emitters run for a while: go on 100 steps past the last stop, so memory is seen flat.
  double lastStop = 0;
  for (const Emitter& e : scene.emitters)
  {
    lastStop = std::max(lastStop, e.stop);
  }
  steps = std::max<std::uint64_t>(
    steps, static_cast<std::uint64_t>(std::ceil(lastStop / p.timeStep)) + 2 * kSampleEvery);
  f.startParticles = simulation.stepper().size();
  const auto initial = static_cast<std::int64_t>(
    fillScene(scene, withSceneDomain(p, scene)).position.size());

  // The box the solver clamps to, in its precision: a particle on a wall sits exactly there.
  const Box& d = simulation.parameters().domain;
  const auto low = [](double v) { return static_cast<double>(static_cast<float>(v)); };
  const Box walls{ { low(d.min.x), low(d.min.y), low(d.min.z) },
    { low(d.max.x), low(d.max.y), low(d.max.z) } };

  Snapshot<float> state; // reused: the check itself allocates nothing once the count is steady
  std::vector<char> seen;
  const auto begin = std::chrono::steady_clock::now();
  f.startRss = residentBytes();
  for (std::uint64_t done = 0; done < steps;)
  {
    const std::uint64_t chunk = std::min(kSampleEvery, steps - done);
    simulation.advance(chunk); // throws SimulationDiverged if the check trips
    done += chunk;

    simulation.stepper().read(state);
    const auto [lo, hi] = expectedEmitted(scene, p.particleSpacing, simulation.time());
    const auto n = static_cast<std::int64_t>(state.id.size());
    ASSERT_TRUE(n >= initial + lo && n <= initial + hi)
      << name << " step " << done << ": " << n << " particles, expected " << initial << " + ["
      << lo << ", " << hi << "] emitted";
    seen.assign(static_cast<std::size_t>(n), 0);
    for (std::size_t i = 0; i < state.id.size(); ++i)
    {
      const std::int64_t id = state.id[i];
      ASSERT_TRUE(id >= 0 && id < n && !seen[static_cast<std::size_t>(id)])
        << name << " step " << done << ": id " << id << " out of 0.." << n - 1 << " or repeated";
      seen[static_cast<std::size_t>(id)] = 1;
      const Vec3<float>& x = state.position[i];
      const Vec3<float>& v = state.velocity[i];
      ASSERT_TRUE(std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z) &&
        std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) &&
        std::isfinite(state.density[i]) && std::isfinite(state.lambda[i]))
        << name << " step " << done << ": particle id " << id << " is not finite";
      ASSERT_TRUE(x.x >= walls.min.x && x.y >= walls.min.y && x.z >= walls.min.z &&
        x.x <= walls.max.x && x.y <= walls.max.y && x.z <= walls.max.z)
        << name << " step " << done << ": particle id " << id << " at (" << x.x << ", " << x.y
        << ", " << x.z << ") is outside the domain";
    }
    const Health health = simulation.stepper().health();
    f.maxSpeed = std::max(f.maxSpeed, health.maxSpeed);
    f.maxDensityError = std::max(f.maxDensityError, health.maxDensityError);

    // Memory: the baseline is taken one sample after the emitters stop (the first sample for a
    // scene without), by which time every array has its final size.
    const double rss = residentBytes();
    if (simulation.time() >= lastStop + kSampleEvery * p.timeStep && f.baselineRss == 0)
    {
      f.baselineRss = rss;
    }
    else if (f.baselineRss > 0)
    {
      f.maxRss = std::max(f.maxRss, rss);
#ifndef PBF_SOAK_ASAN
      // AddressSanitizer keeps freed memory in quarantine (the OpenMP runtime allocates and
      // frees a little per parallel loop), so resident memory grows there by design; leaks are
      // LeakSanitizer's to find in that build.
      EXPECT_LE(rss - f.baselineRss, kRssToleranceBytes)
        << name << " step " << done << ": resident memory grew from " << f.baselineRss / 1048576
        << " MB to " << rss / 1048576 << " MB";
#endif
    }
    f.endRss = rss;
  }
  f.endParticles = simulation.stepper().size();
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  std::printf("soak %s: %llu steps, %zu -> %zu particles, %.1f s, RSS %.0f kB at the start, "
              "%.0f kB baseline, %.0f kB at the end (max %.0f); sampled every %d steps: max "
              "speed %.2f m/s (limit %.1f), max compression %.2f%% (limit %.0f%%)\n",
    name.c_str(), static_cast<unsigned long long>(steps), f.startParticles, f.endParticles,
    f.seconds, f.startRss / 1024, f.baselineRss / 1024, f.endRss / 1024,
    std::max(f.maxRss, f.baselineRss) / 1024, static_cast<int>(kSampleEvery), f.maxSpeed,
    simulation.divergenceLimits().maxSpeed, 100 * f.maxDensityError,
    100 * simulation.divergenceLimits().maxDensityError);
  EXPECT_GT(f.baselineRss, 0.0) << "the run never reached the memory baseline";
}

} // namespace

TEST(PBF_SOAK_SUITE, DamBreak)
{
  Figures f;
  soak("dam_break", PBF_SOAK_STEPS, f);
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_EQ(f.endParticles, f.startParticles);
}

TEST(PBF_SOAK_SUITE, DoubleDamBreak)
{
  Figures f;
  soak("double_dam_break", PBF_SOAK_STEPS, f);
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_EQ(f.endParticles, f.startParticles);
}

TEST(PBF_SOAK_SUITE, Blob)
{
  Figures f;
  soak("blob", PBF_SOAK_STEPS, f);
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_EQ(f.endParticles, f.startParticles);
}

TEST(PBF_SOAK_SUITE, Stream)
{
  // 2 s of a 0.08 m jet at s = 0.05 m: 60 layers of 9 sites.
  Figures f;
  soak("stream", PBF_SOAK_STEPS, f);
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_EQ(f.endParticles, 540u);
}
