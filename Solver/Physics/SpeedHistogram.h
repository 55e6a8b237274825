// The automatic step's robust speed: the 99.9th percentile of the particles' speeds, from a
// histogram of speed^2 whose bins are read off its bits (exponent and the top three mantissa
// bits), so that every backend bins a particle alike and the counts, integers, add in any order.
// One fast spray particle then no longer sets the whole fluid's step (Simulation::nextTimeStep
// bounds the fastest one separately).
#pragma once

#include "HostDevice.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace pbf
{

// 8 bins to an octave of speed^2 (its top three mantissa bits), so each is 3.3 to 6.1 % wide in
// speed, over 64 octaves: speed^2 from 2^-24 (speed 2.4e-4 m/s; slower is bin 0) to 2^40; the
// last bin takes the rest.
constexpr int kSpeedBinsPerOctave = 8;
constexpr int kSpeedLowestExponent = -24;
constexpr int kSpeedBins = 64 * kSpeedBinsPerOctave;
// The share of the particles at or below the robust speed.
constexpr double kRobustSpeedQuantile = 0.999;

// The bin of a particle with this speed^2 [m^2/s^2]; 0 for zero and NaN.
PBF_HD PBF_INLINE int speedBin(double speed2)
{
  if (!(speed2 > 0.0))
  {
    return 0;
  }
#if defined(__CUDA_ARCH__)
  const auto bits = static_cast<std::uint64_t>(__double_as_longlong(speed2));
#else
  std::uint64_t bits;
  std::memcpy(&bits, &speed2, sizeof bits);
#endif
  const int exponent = static_cast<int>((bits >> 52) & 0x7ffu) - 1023;
  const int mantissa = static_cast<int>((bits >> 49) & 7u);
  const int bin = (exponent - kSpeedLowestExponent) * kSpeedBinsPerOctave + mantissa;
  return bin < 0 ? 0 : (bin >= kSpeedBins ? kSpeedBins - 1 : bin);
}

// The largest speed bin `bin` holds [m/s] (the last bin: infinity).
inline double speedBinTop(int bin)
{
  if (bin >= kSpeedBins - 1)
  {
    return std::numeric_limits<double>::infinity();
  }
  const int exponent = bin / kSpeedBinsPerOctave + kSpeedLowestExponent;
  const int mantissa = bin % kSpeedBinsPerOctave;
  return std::sqrt(std::ldexp(1.0 + (mantissa + 1.0) / kSpeedBinsPerOctave, exponent));
}

// The speed that all but (1 - kRobustSpeedQuantile) of the counted particles reach at most:
// the top of the bin where that share is passed, counted from the fastest bin down (so at or
// above the exact percentile, by less than a bin), and never above `fastest` (with fewer than
// 1 / (1 - quantile) particles it is the fastest). 0 when nothing is counted.
template <class Count>
double robustSpeed(const Count* counts, double fastest)
{
  double total = 0.0;
  for (int b = 0; b < kSpeedBins; ++b)
  {
    total += static_cast<double>(counts[b]);
  }
  const double allowed = std::floor(total * (1.0 - kRobustSpeedQuantile));
  double above = 0.0;
  for (int b = kSpeedBins - 1; b >= 0; --b)
  {
    above += static_cast<double>(counts[b]);
    if (above > allowed)
    {
      return std::fmin(speedBinTop(b), fastest);
    }
  }
  return 0.0;
}

} // namespace pbf
