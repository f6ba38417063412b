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

/// Random adult sliders, deterministic for a seed: age 0.45-0.95, weight
/// 0.1-0.9, height slider 0.2-0.9, muscle 0.3-0.8, proportions 0.3-0.9, both
/// genders (gender near 0 or 1 with some spread), mixed ethnicity. The height
/// slider is uniform here, which makes 17% of adults taller than 2.05 m:
/// bodies meant as people come from the library form below, which replaces
/// it by the slider of a stature drawn from a survey.
[[nodiscard]] std::vector<MacroParams> sample_adults(std::size_t n, std::uint64_t seed);
/// Adult `index` of sample_adults(n, seed) for any n > index, drawn alone
/// (its own random stream): a source draws each body when it is made.
[[nodiscard]] MacroParams sample_adult(std::uint64_t seed, std::size_t index);

/// Adult stature percentiles (metres) of one sex: 5th, 50th, 95th.
struct StaturePercentiles {
  double p5 = 0, p50 = 0, p95 = 0;
};
/// What the stature sampler aims for: US adults aged 20 and over, NHANES
/// 2015-2018 (Fryar et al. 2021, Anthropometric reference data for children
/// and adults: United States, 2015-2018, Vital Health Stat 3(46); docs/body-files.md).
[[nodiscard]] StaturePercentiles stature_percentiles(bool female) noexcept;

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

  /// out = base + sum(weight * target) over all vertices of base.obj, then
  /// translated along y so that the lowest skin vertex is at y = 0: every
  /// body source stands on the floor y = 0, Y up (docs/body-files.md);
  /// base.obj is centred mid-body. Helpers and garments fitted to `out`
  /// move with it. Throws std::invalid_argument for an unknown measure
  /// modifier name.
  void build(const MacroParams& p, std::span<Vec3f> out) const;

  /// Stature (metres: highest minus lowest skin vertex) of the body build(p)
  /// makes, from the skin vertices near the top of the head and the soles
  /// (those within 4% of the base body's height of its top or bottom; the
  /// targets do not move other vertices that far) in double precision.
  [[nodiscard]] double stature(const MacroParams& p) const;
  /// The height slider in [0, 1] that gives `stature_m` with p's other
  /// sliders: each vertex is linear in the slider on [0, 0.5] and on
  /// [0.5, 1] (the min/maxheight weights, README), so the stature is known
  /// exactly between three evaluations and bisected. A stature out of the
  /// sliders' reach gives 0 or 1.
  [[nodiscard]] double height_for_stature(const MacroParams& p, double stature_m) const;

 private:
  BaseMesh base_;
  std::vector<Target> macro_;    // sorted by name
  std::vector<Target> measure_;  // sorted by name
  std::map<std::string, std::vector<std::uint32_t>> measures_;
  std::vector<std::string> measure_modifiers_;
  std::uint32_t skin_vertices_ = 0;
  // Per macro target, its factor tokens as indices into kFactorNames (the
  // file name parsed once: active_targets is called per body and per
  // stature evaluation).
  std::vector<std::vector<std::uint8_t>> macro_factors_;
  // stature(): skin vertices near the top and the soles, their base y and,
  // per target (macro_ then measure_), (candidate slot, dy) pairs.
  std::vector<std::uint32_t> stature_vertices_;
  std::vector<double> stature_base_y_;
  std::vector<std::vector<std::pair<std::uint32_t, float>>> stature_dy_;
  void stature_y(const MacroParams& p, std::vector<double>& y) const;
  // build(): each target (macro_ then measure_) as the 16-float chunks of
  // the interleaved coordinates it moves (chunk index, lane mask, values),
  // added with AVX-512 where the machine has it (the same bits as the
  // sparse loop); empty for a target that lists a vertex twice.
  struct ChunkTarget {
    std::vector<std::uint32_t> chunk;
    std::vector<std::uint16_t> mask;
    std::vector<float> value;  // 16 per chunk
  };
  std::vector<ChunkTarget> chunks_;
  [[nodiscard]] static ChunkTarget chunk_target(const Target& t);
};

/// Adult `index` for a seed, drawn alone: the sliders of sample_adult(seed,
/// index) with the height slider replaced by the one that gives a stature
/// drawn for the sex (gender < 0.5: female) from a normal distribution with
/// the survey's median and the spread of its 5th-95th percentiles, clamped
/// to 2.5 standard deviations (stature_percentiles). `stature_m`, when set,
/// gets the stature the body has (lib.stature of the result).
[[nodiscard]] MacroParams sample_adult(const HumanLibrary& lib, std::uint64_t seed, std::size_t index,
                                       double* stature_m = nullptr);
/// Adults 0..n-1 of sample_adult(lib, seed, i).
[[nodiscard]] std::vector<MacroParams> sample_adults(const HumanLibrary& lib, std::size_t n, std::uint64_t seed);

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
  /// `count` bodies of sample_adult(*lib, seed, i), each drawn when its chunk
  /// is generated: the source's memory does not grow with `count` (issue 27:
  /// the list of 10^7 parameters took 1 GB before the first body).
  MakeHumanSource(std::shared_ptr<const HumanLibrary> lib, std::size_t count, std::uint64_t seed,
                  std::shared_ptr<const ReferenceBody> reference);
  [[nodiscard]] std::size_t size() const override { return sampled_ ? count_ : params_.size(); }
  [[nodiscard]] MacroParams params(std::size_t i) const {
    return sampled_ ? sample_adult(*lib_, seed_, i) : params_[i];
  }
  [[nodiscard]] std::shared_ptr<const ReferenceBody> reference() const override { return reference_; }
  [[nodiscard]] std::string body_name(std::size_t i) const override;
  /// The macro sliders of body i (MacroParams, each in [0, 1]), the sex
  /// they make (gender below 0.5: female) and the body's stature
  /// (sampled_stature_m, HumanLibrary::stature: for sampled bodies the
  /// stature drawn, unless out of the sliders' reach).
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
