// Portable deterministic random numbers: the same seed gives the same stream
// on every platform and standard library (std::normal_distribution does not).
#pragma once

#include <cmath>
#include <cstdint>

namespace atelier {

/// SplitMix64 (Steele, Lea, Flood 2014): tiny, full-period, good for seeding
/// and for streams where each item gets its own generator (seed ^ index).
class SplitMix64 {
 public:
  explicit constexpr SplitMix64(std::uint64_t seed) noexcept : s_(seed) {}
  constexpr std::uint64_t next() noexcept {
    std::uint64_t z = (s_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1) with 53 random bits.
  double uniform() noexcept { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) noexcept { return lo + (hi - lo) * uniform(); }
  /// Standard normal by Box-Muller (one value per call; the pair's second
  /// value is dropped to keep the stream position simple).
  double normal() noexcept {
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  std::uint64_t s_;
};

/// Independent stream for item `index` of a run seeded with `seed`, so items
/// can be generated in any order (or in parallel) with identical results.
[[nodiscard]] constexpr std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t index) noexcept {
  SplitMix64 a(seed ^ (0x632be59bd9b4e019ull * (index + 1)));
  return a.next();
}

}  // namespace atelier
