// MakeHuman bodies: the base mesh mixed with macro morph targets the way
// MakeHuman does (rules in ../shared/data/makehuman/README.md), plus two-sided
// measure modifiers.
//
// Reads: the MakeHuman folder (once, at load). Writes: position arrays.
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "engine/exec_context.h"
#include "engine/math.h"
#include "io/makehuman.h"

namespace atelier::makehuman {

/// Macro slider values, all in [0, 1] (ethnic values are normalised to sum 1).
struct MacroParams {
  double gender = 0.5;  // 0 female, 1 male
  double age = 0.5;     // 0 = 1 year, 0.1875 = 10, 0.5 = 25, 1 = 90 years
  double muscle = 0.5;
  double weight = 0.5;
  double height = 0.5;
  double proportions = 0.5;
  double african = 1.0 / 3.0;
  double asian = 1.0 / 3.0;
  double caucasian = 1.0 / 3.0;
  /// Two-sided measure modifiers, e.g. {"measure-waist-circ", -0.3}, v in [-1, 1].
  std::vector<std::pair<std::string, double>> measures;
};

/// Weight of one factor token of a macro target file name ("female",
/// "young", "maxmuscle", "minheight", "idealproportions", "asian", ...);
/// "universal" weighs 1. Throws std::invalid_argument for an unknown token.
[[nodiscard]] double macro_factor(std::string_view token, const MacroParams& p);

/// A macro target's weight: the product of the factors named in its file
/// name, e.g. height/female-young-averagemuscle-maxweight-maxheight.
[[nodiscard]] double macro_target_weight(std::string_view target_name, const MacroParams& p);

/// Random adult bodies, deterministic for a seed: age 0.45-0.95, weight
/// 0.1-0.9, height 0.2-0.9, muscle 0.3-0.8, proportions 0.3-0.9, both
/// genders (gender near 0 or 1 with some spread), mixed ethnicity.
[[nodiscard]] std::vector<MacroParams> sample_adults(std::size_t n, std::uint64_t seed);

class HumanLibrary {
 public:
  /// Loads base.obj and every macro and measure target under `dir`
  /// (in parallel). Throws atelier::Error naming the file on bad data.
  [[nodiscard]] static HumanLibrary load(const std::filesystem::path& dir, const ExecContext& ctx = {});

  [[nodiscard]] const BaseMesh& base() const noexcept { return base_; }
  [[nodiscard]] std::uint32_t vertex_count() const noexcept { return static_cast<std::uint32_t>(base_.positions.size()); }
  [[nodiscard]] const std::vector<Target>& macro_targets() const noexcept { return macro_; }
  [[nodiscard]] const std::vector<Target>& measure_targets() const noexcept { return measure_; }
  [[nodiscard]] const Target* find_target(std::string_view name) const noexcept;

  /// (target, weight) pairs with non-zero weight for these parameters, in a
  /// fixed order (macro targets by name, then measure targets).
  [[nodiscard]] std::vector<std::pair<const Target*, double>> active_targets(const MacroParams& p) const;

  /// out = base + sum(weight * target) over all vertices of base.obj.
  /// Throws std::invalid_argument for an unknown measure modifier name.
  void build(const MacroParams& p, std::span<Vec3f> out) const;

 private:
  BaseMesh base_;
  std::vector<Target> macro_;    // sorted by name
  std::vector<Target> measure_;  // sorted by name
};

}  // namespace atelier::makehuman
