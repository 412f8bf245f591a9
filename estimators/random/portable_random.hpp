#pragma once
// Random draws that give the same numbers with every standard library.  std::mt19937_64 is specified bit for bit
// by the C++ standard, but std::uniform_int_distribution, std::uniform_real_distribution and
// std::normal_distribution are not (libstdc++ and libc++ turn the same engine output into different numbers), so
// a result that must be reproducible from a seed on any platform draws through these functions instead.
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>

namespace sextant::random {

/// Uniform integer in [0, n), n >= 1, by rejection: engine outputs x >= 2^64 - (2^64 mod n) are discarded (the
/// top, incomplete block of n values) and x mod n is returned, so every value has probability exactly 1/n.
/// Consumes one engine output, or more after a rejection (probability < n / 2^64 per draw).
inline uint64_t uniform_index(std::mt19937_64& rng, uint64_t n) {
  if (n == 0) throw std::invalid_argument("uniform_index: empty range (n = 0)");
  const uint64_t rejected = (0 - n) % n;  // 2^64 mod n, computed in 64-bit arithmetic
  const uint64_t limit = 0 - rejected;    // 2^64 - rejected (0 when rejected = 0: nothing is rejected)
  for (;;) {
    const uint64_t x = rng();
    if (rejected == 0 || x < limit) return x % n;
  }
}

/// Uniform double in [0, 1): the top 53 bits of one engine output times 2^-53.
inline double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// Standard normal N(0, 1) by the Box-Muller transform of two uniform01 draws (the first mapped to (0, 1] so
/// its log is finite); one value per call, two engine outputs per call.
inline double standard_normal(std::mt19937_64& rng) {
  const double u1 = 1.0 - uniform01(rng);
  const double u2 = uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace sextant::random
