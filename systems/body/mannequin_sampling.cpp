// Random mannequin measurements (systems/body/mannequin.h): a body's
// parameters drawn from its own random stream, so any body of a sample is
// drawn without the ones before it.
#include <atelier/systems/body/mannequin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace atelier {

namespace {

// xoshiro256** (Blackman & Vigna) seeded by splitmix64: fixed integer
// arithmetic, so the stream is the same on every platform.
class Xoshiro256 {
 public:
  explicit Xoshiro256(std::uint64_t seed) noexcept {
    for (auto& x : s_) {
      seed += 0x9e3779b97f4a7c15ull;
      std::uint64_t z = seed;
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
      x = z ^ (z >> 31);
    }
  }
  std::uint64_t next() noexcept {
    const std::uint64_t r = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return r;
  }
  double uniform() noexcept { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Marsaglia polar method: only sqrt (correctly rounded) and log.
  double normal() noexcept {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = 2 * uniform() - 1;
      v = 2 * uniform() - 1;
      s = u * u + v * v;
    } while (s >= 1 || s == 0);
    const double f = std::sqrt(-2 * std::log(s) / s);
    spare_ = v * f;
    has_spare_ = true;
    return u * f;
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) noexcept { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4];
  double spare_ = 0;
  bool has_spare_ = false;
};

double clampz(double z) {
  return std::clamp(z, -2.5, 2.5);
}

/// Body `index` has its own stream, its seed a splitmix64 finalisation of
/// (seed, index): any body is drawn without the ones before it, so a body
/// source holds no per-body state.
Xoshiro256 body_stream(std::uint64_t seed, std::size_t index) {
  std::uint64_t z = seed + (static_cast<std::uint64_t>(index) + 1) * 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return Xoshiro256(z ^ (z >> 31));
}

}  // namespace

bool sample_mannequin_female(std::uint64_t seed, std::size_t index) {
  Xoshiro256 rng = body_stream(seed, index);
  return rng.uniform() < 0.5;  // the first draw of sample_mannequin
}

MannequinParams sample_mannequin(std::uint64_t seed, std::size_t index) {
  Xoshiro256 rng = body_stream(seed, index);
  {
    const bool female = rng.uniform() < 0.5;
    // Latent factors: stature and size (adiposity/build). Girths grow weakly
    // with stature and strongly with size; each measure adds its own noise.
    const double zh = clampz(rng.normal()), zs = clampz(rng.normal()), zb = clampz(rng.normal());
    MannequinParams p;
    p.height = female ? 1.640 + 0.065 * zh : 1.760 + 0.070 * zh;
    const double hs = p.height / (female ? 1.64 : 1.76);
    const double gh = std::pow(hs, 0.5);  // girth vs stature
    auto girth = [&](double base, double ks, double noise) {
      return base * gh * std::exp(ks * zs + noise * clampz(rng.normal()));
    };
    if (female) {
      p.neck_girth = girth(0.345, 0.05, 0.03);
      p.bust_girth = girth(0.93, 0.09, 0.03);
      p.underbust_girth = p.bust_girth * std::clamp(0.84 + 0.03 * zb, 0.76, 0.92);
      p.waist_girth = girth(0.76, 0.13, 0.04);
      p.hip_girth = girth(1.00, 0.08, 0.03);
      p.thigh_girth = girth(0.58, 0.10, 0.04);
      p.knee_girth = girth(0.37, 0.06, 0.03);
      p.ankle_girth = girth(0.225, 0.04, 0.03);
      p.upper_arm_girth = girth(0.28, 0.11, 0.04);
      p.shoulder_width = 0.385 * hs * std::exp(0.02 * zs + 0.03 * clampz(rng.normal()));
      p.back_length = 0.405 * hs * std::exp(0.03 * clampz(rng.normal()));
      p.inseam = p.height * std::clamp(0.455 + 0.012 * rng.normal(), 0.40, 0.50);
    } else {
      p.neck_girth = girth(0.39, 0.05, 0.03);
      p.bust_girth = girth(1.00, 0.08, 0.03);
      p.underbust_girth = p.bust_girth * std::clamp(0.91 + 0.02 * zb, 0.84, 0.97);
      p.waist_girth = girth(0.88, 0.12, 0.04);
      p.hip_girth = girth(1.00, 0.07, 0.03);
      p.thigh_girth = girth(0.56, 0.09, 0.04);
      p.knee_girth = girth(0.385, 0.05, 0.03);
      p.ankle_girth = girth(0.235, 0.04, 0.03);
      p.upper_arm_girth = girth(0.31, 0.09, 0.04);
      p.shoulder_width = 0.44 * hs * std::exp(0.02 * zs + 0.03 * clampz(rng.normal()));
      p.back_length = 0.44 * hs * std::exp(0.03 * clampz(rng.normal()));
      p.inseam = p.height * std::clamp(0.46 + 0.012 * rng.normal(), 0.40, 0.50);
    }
    // Clamps that keep the set inside validate_params' ranges and order.
    p.height = std::clamp(p.height, 1.45, 2.05);
    p.inseam = std::clamp(p.inseam, 0.39 * p.height, 0.51 * p.height);
    auto cl = [](double& v, double lo, double hi) { v = std::clamp(v, lo, hi); };
    cl(p.neck_girth, 0.28, 0.54);
    cl(p.bust_girth, 0.70, 1.50);
    cl(p.underbust_girth, 0.60, p.bust_girth);
    cl(p.waist_girth, 0.52, 1.50);
    cl(p.hip_girth, 0.74, 1.55);
    cl(p.thigh_girth, 0.40, 0.74 * p.hip_girth);
    cl(p.knee_girth, 0.28, 0.88 * p.thigh_girth);
    cl(p.ankle_girth, 0.17, 0.84 * p.knee_girth);
    cl(p.upper_arm_girth, 0.19, 0.44 * p.bust_girth);
    p.neck_girth = std::min(p.neck_girth, 0.49 * p.bust_girth);
    cl(p.shoulder_width, std::max(0.31, 0.42 * p.neck_girth + 0.11), 0.55);
    const double nape = 0.848 * p.height, armpit = nape - 0.118 * p.height;
    // waist between (crotch + 0.13) and (armpit - 0.09)
    p.back_length =
        std::clamp(p.back_length, std::max(0.31, nape - (armpit - 0.09)), std::min(0.57, 0.463 * p.height - 0.135));
    if (nape - p.back_length < p.inseam + 0.13) p.inseam = nape - p.back_length - 0.13;
    p.inseam = std::max(p.inseam, 0.385 * p.height);
    return p;
  }
}

std::vector<MannequinParams> sample_mannequins(std::size_t n, std::uint64_t seed) {
  std::vector<MannequinParams> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) out.push_back(sample_mannequin(seed, i));
  return out;
}

}  // namespace atelier
