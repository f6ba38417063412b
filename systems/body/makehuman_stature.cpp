// Statures of MakeHuman bodies (issue 26): the stature model of a
// HumanLibrary (head and sole vertices only), the inversion of the height
// slider from a stature, and the adults drawn with a survey's statures
// (docs/body-files.md, "Floor, up axis and statures").
#include <algorithm>
#include <array>
#include <limits>

#include <atelier/engine/random.h>
#include <atelier/systems/body/makehuman_body.h>

namespace atelier::makehuman {

StaturePercentiles stature_percentiles(bool female) noexcept {
  // NHANES 2015-2018, adults 20 years and over, measured standing height
  // (Fryar et al. 2021, table of height percentiles by sex), rounded to 0.5 cm.
  return female ? StaturePercentiles{1.500, 1.615, 1.730} : StaturePercentiles{1.630, 1.755, 1.880};
}

MacroParams sample_adult(const HumanLibrary& lib, std::uint64_t seed, std::size_t index, double* stature_m) {
  MacroParams p = sample_adult(seed, index);
  // The stature has its own stream: the other sliders stay those of sample_adult.
  SplitMix64 r(stream_seed(seed ^ 0x5157A7E5ull, index));
  const StaturePercentiles q = stature_percentiles(p.gender < 0.5);
  const double sd = (q.p95 - q.p5) / (2 * 1.6448536269514722);  // 5th-95th spread of a normal
  const double z = std::clamp(r.normal(), -2.5, 2.5);
  p.height = lib.height_for_stature(p, q.p50 + sd * z);
  if (stature_m) *stature_m = lib.stature(p);
  return p;
}

std::vector<MacroParams> sample_adults(const HumanLibrary& lib, std::size_t n, std::uint64_t seed) {
  std::vector<MacroParams> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) out.push_back(sample_adult(lib, seed, i));
  return out;
}

void HumanLibrary::stature_y(const MacroParams& p, std::vector<double>& y) const {
  y = stature_base_y_;
  for (const auto& [t, w] : active_targets(p)) {
    const std::size_t k = t >= macro_.data() && t < macro_.data() + macro_.size()
                              ? static_cast<std::size_t>(t - macro_.data())
                              : macro_.size() + static_cast<std::size_t>(t - measure_.data());
    for (const auto& [c, dy] : stature_dy_[k]) y[c] += w * dy;
  }
}

double HumanLibrary::stature(const MacroParams& p) const {
  std::vector<double> y;
  stature_y(p, y);
  if (y.empty()) return 0;
  const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
  return kMakeHumanToMetres * (*hi - *lo);
}

double HumanLibrary::height_for_stature(const MacroParams& p, double stature_m) const {
  // y at slider 0, 0.5 and 1; in between each vertex is linear in the slider.
  std::array<std::vector<double>, 3> y;
  MacroParams q = p;
  for (int k = 0; k < 3; ++k) {
    q.height = 0.5 * k;
    stature_y(q, y[static_cast<std::size_t>(k)]);
  }
  if (y[0].empty()) return p.height;
  // Per half, the candidates that can be highest (or lowest) somewhere on
  // it: a line whose higher end is below the best lower end never is.
  std::array<std::vector<std::uint32_t>, 2> top, bottom;
  for (std::size_t half = 0; half < 2; ++half) {
    const auto& a = y[half];
    const auto& b = y[half + 1];
    double floor_hi = -std::numeric_limits<double>::infinity(), ceil_lo = -floor_hi;
    for (std::size_t c = 0; c < a.size(); ++c) {
      floor_hi = std::max(floor_hi, std::min(a[c], b[c]));
      ceil_lo = std::min(ceil_lo, std::max(a[c], b[c]));
    }
    for (std::uint32_t c = 0; c < a.size(); ++c) {
      if (std::max(a[c], b[c]) >= floor_hi) top[half].push_back(c);
      if (std::min(a[c], b[c]) <= ceil_lo) bottom[half].push_back(c);
    }
  }
  auto at = [&](double h) {
    const std::size_t half = h <= 0.5 ? 0 : 1;
    const auto& a = y[half];
    const auto& b = y[half + 1];
    const double t = half == 0 ? 2 * h : 2 * h - 1;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::uint32_t c : top[half]) hi = std::max(hi, (1 - t) * a[c] + t * b[c]);
    for (std::uint32_t c : bottom[half]) lo = std::min(lo, (1 - t) * a[c] + t * b[c]);
    return kMakeHumanToMetres * (hi - lo);
  };
  if (!(stature_m > at(0.0))) return 0.0;
  if (!(stature_m < at(1.0))) return 1.0;
  double a = 0, b = 1;
  for (int it = 0; it < 60 && b - a > 1e-12; ++it) {
    const double m = 0.5 * (a + b);
    (at(m) < stature_m ? a : b) = m;
  }
  return 0.5 * (a + b);
}

}  // namespace atelier::makehuman
