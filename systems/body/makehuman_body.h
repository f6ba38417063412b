// MakeHuman bodies: the base mesh mixed with macro morph targets the way
// MakeHuman does (rules in ../shared/data/makehuman/README.md), plus two-sided
// measure modifiers.
//
// Reads: the MakeHuman folder (once, at load). Writes: position arrays.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/io/makehuman/makehuman.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/reference_body.h>

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
/// Adult `index` of sample_adults(n, seed) for any n > index, drawn alone
/// (its own random stream): a source draws each body when it is made.
[[nodiscard]] MacroParams sample_adult(std::uint64_t seed, std::size_t index);

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

  /// Measurement loops and chains of measures.json (empty if the file is absent).
  [[nodiscard]] const std::map<std::string, std::vector<std::uint32_t>>& measures() const noexcept { return measures_; }
  /// Two-sided measure modifiers declared in modifiers/measurement_modifiers.json
  /// (e.g. "measure-waist-circ"), each with its decr and incr targets loaded.
  [[nodiscard]] const std::vector<std::string>& measure_modifiers() const noexcept { return measure_modifiers_; }
  /// Number of skin vertices: the `body` group uses vertices [0, skin_vertex_count()).
  [[nodiscard]] std::uint32_t skin_vertex_count() const noexcept { return skin_vertices_; }

  /// out = base + sum(weight * target) over all vertices of base.obj.
  /// Throws std::invalid_argument for an unknown measure modifier name.
  void build(const MacroParams& p, std::span<Vec3f> out) const;

 private:
  BaseMesh base_;
  std::vector<Target> macro_;    // sorted by name
  std::vector<Target> measure_;  // sorted by name
  std::map<std::string, std::vector<std::uint32_t>> measures_;
  std::vector<std::string> measure_modifiers_;
  std::uint32_t skin_vertices_ = 0;
};

/// Base-mesh units (decimetres) to metres.
inline constexpr double kMakeHumanToMetres = 0.1;

/// The MakeHuman skin as a reference body (node i = base.obj vertex i, in
/// metres) for the given full-mesh positions (base.obj units), with feature
/// curves: the girth loops of measures.json (torso: neck, bust, underbust,
/// waist, hip; limbs on the left side as in the file, mirrored for the
/// right: thigh, knee, calf, ankle, upperarm, wrist), centre_front and
/// centre_back (the sagittal section between neck and crotch), left_side and
/// right_side (the coronal section through the waist, from above the bust to
/// the hip); feature points where torso girths cross those lines, named
/// "<girth>_x_<line>". Throws atelier::Error if the loops are missing.
[[nodiscard]] ReferenceBody make_reference_body(const HumanLibrary& lib, std::span<const Vec3f> positions);
[[nodiscard]] ReferenceBody make_reference_body(const HumanLibrary& lib);  // the default body

/// MakeHuman bodies for a list of macro parameters, generated on demand.
class MakeHumanSource final : public BodySource {
 public:
  MakeHumanSource(std::shared_ptr<const HumanLibrary> lib, std::vector<MacroParams> params,
                  std::shared_ptr<const ReferenceBody> reference);
  /// `count` bodies of sample_adults(count, seed), each drawn when its chunk
  /// is generated: the source's memory does not grow with `count` (issue 27:
  /// the list of 10^7 parameters took 1 GB before the first body).
  MakeHumanSource(std::shared_ptr<const HumanLibrary> lib, std::size_t count, std::uint64_t seed,
                  std::shared_ptr<const ReferenceBody> reference);
  [[nodiscard]] std::size_t size() const override { return sampled_ ? count_ : params_.size(); }
  [[nodiscard]] MacroParams params(std::size_t i) const { return sampled_ ? sample_adult(seed_, i) : params_[i]; }
  [[nodiscard]] std::shared_ptr<const ReferenceBody> reference() const override { return reference_; }
  [[nodiscard]] std::string body_name(std::size_t i) const override;
  /// The macro sliders of body i (MacroParams, each in [0, 1]) and the sex
  /// they make (gender below 0.5: female).
  [[nodiscard]] std::vector<std::pair<std::string, std::string>> parameters(std::size_t i) const override;
  void generate(std::size_t first, std::size_t count, BodySet& out, std::vector<BodyFailure>& failures,
                const ExecContext& ctx) const override;
  /// Skin positions (metres, indexed by node) of body i.
  [[nodiscard]] std::vector<Vec3d> skin_positions(std::size_t i) const;

 private:
  std::shared_ptr<const HumanLibrary> lib_;
  std::vector<MacroParams> params_;
  bool sampled_ = false;
  std::size_t count_ = 0;
  std::uint64_t seed_ = 0;
  std::shared_ptr<const ReferenceBody> reference_;
};

}  // namespace atelier::makehuman
