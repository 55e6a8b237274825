// The divergence check's scan and the automatic step's speeds on a GPU stepper, written once for
// both (DeviceStepper, DeviceSubdomainStepper): three maxima over the particles in one pass (the
// largest speed^2, the largest compression, any non-finite value), as the bits of doubles so that
// the device's integer maxima give the same answer in any order, then the speeds' histogram
// (SpeedHistogram.h) in integers. kHealthWords words come back (2 KB).
#pragma once

#include "NeighborMasks.h"
#include "SpeedHistogram.h"
#include "StepSchedule.h"

#include <cmath>
#include <cstdint>

namespace pbf
{
namespace cuda
{

// One particle's part of the scan: its speed^2, compression and non-finiteness, each a
// non-negative double whose maximum is taken, and its speed's bin (SpeedHistogram.h).
struct HealthSample
{
  double maxima[3];
  int bin;
};

// The three maxima, then kSpeedBins 32-bit counts.
constexpr std::size_t kHealthWords = 3 + kSpeedBins / 2;
inline std::uint32_t* speedCountsOf(unsigned long long* bits)
{
  return reinterpret_cast<std::uint32_t*>(bits + 3);
}
inline const std::uint32_t* speedCountsOf(const unsigned long long* bits)
{
  return reinterpret_cast<const std::uint32_t*>(bits + 3);
}

// Queues the three maxima into bits[0..2] and the speeds' counts after them (zeroed first),
// kHealthWords words, in one pass over the particles (healthKernel: one read of x, v and
// density).
template <class Real, class Exec>
void enqueueHealth(Exec& exec, const Vec3<Real>* x, const Vec3<Real>* v, const Real* density,
  std::uint32_t n, double inverseRestDensity, unsigned long long* bits)
{
  exec.fillZero(bits, kHealthWords * sizeof(unsigned long long));
  exec.forEachHealth(n, bits, speedCountsOf(bits), kSpeedBins,
    [=] PBF_HD(std::uint32_t i) -> HealthSample {
    const Vec3<Real> xi = x[i], vi = v[i];
    const double speed2 = double(vi.x) * vi.x + double(vi.y) * vi.y + double(vi.z) * vi.z;
    const double e = double(density[i]) * inverseRestDensity - 1.0;
    const double sum = double(xi.x) + xi.y + xi.z + vi.x + vi.y + vi.z;
    HealthSample s;
    s.maxima[0] = speed2 < 1e300 ? speed2 : 0.0; // NaN and infinity are the third maximum's
    s.maxima[1] = e > 0.0 && e < 1e300 ? e : 0.0;
    s.maxima[2] = sum - sum == 0.0 ? 0.0 : 1.0;  // finite exactly when sum - sum is 0
    // speed^2 as the maximum has it, the same double the CPU's scan bins (HostParticles.h).
    // NaN is counted in bin 0 here and infinity in the last, neither there: a blow-up stops the
    // run, so the counts differ only in a step that ends it.
    s.bin = speedBin(speed2);
    return s;
  });
}

// The three maxima as doubles: speed^2, compression, 1 when anything is not finite.
inline void decodeHealth(const unsigned long long bits[3], double out[3])
{
  for (int k = 0; k < 3; ++k)
  {
    out[k] = MaskSchedule::bitsToDouble(bits[k]);
  }
}

} // namespace cuda
} // namespace pbf
