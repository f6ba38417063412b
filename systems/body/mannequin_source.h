// Mannequin bodies as a BodySource (the embedded default body set), and a
// helper that cuts a garment-like shell out of a body's skin (the demo's
// own detail-template garment).
#pragma once

#include <memory>
#include <vector>

#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/mannequin.h>

namespace atelier {

class MannequinSource final : public BodySource {
 public:
  /// Bodies with the given parameters (e.g. measured people).
  MannequinSource(std::shared_ptr<const MannequinTopology> topology, std::vector<MannequinParams> params,
                  std::shared_ptr<const ReferenceBody> reference);
  /// `count` bodies of sample_mannequins(count, seed), each drawn when its
  /// chunk is generated: the source's memory does not grow with `count`.
  MannequinSource(std::shared_ptr<const MannequinTopology> topology, std::size_t count, std::uint64_t seed,
                  std::shared_ptr<const ReferenceBody> reference);
  [[nodiscard]] std::size_t size() const override { return sampled_ ? count_ : params_.size(); }
  [[nodiscard]] std::shared_ptr<const ReferenceBody> reference() const override { return reference_; }
  [[nodiscard]] std::string body_name(std::size_t i) const override;
  void generate(std::size_t first, std::size_t count, BodySet& out, std::vector<BodyFailure>& failures,
                const ExecContext& ctx) const override;
  /// The person the form is cut from: sex (sampled bodies only), stature
  /// and every girth and length of MannequinParams, in metres.
  [[nodiscard]] std::vector<std::pair<std::string, std::string>> parameters(std::size_t i) const override;
  /// The mannequin is headless: its vertical extent is not the stature.
  [[nodiscard]] bool whole_person() const override { return false; }
  [[nodiscard]] MannequinParams params(std::size_t i) const {
    return sampled_ ? sample_mannequin(seed_, i) : params_[i];
  }

 private:
  std::shared_ptr<const MannequinTopology> topology_;
  std::vector<MannequinParams> params_;
  bool sampled_ = false;
  std::size_t count_ = 0;
  std::uint64_t seed_ = 0;
  std::shared_ptr<const ReferenceBody> reference_;
};

/// A shell garment: the skin faces whose nodes all lie in the height band
/// [y_lo, y_hi] and within `max_radius` of the vertical body axis, copied and
/// pushed `offset` along the area-weighted node normals. One surface named
/// `name`. Errors when the band holds no face.
[[nodiscard]] Expected<Model> skin_band_garment(const ReferenceBody& body, double y_lo, double y_hi, double offset,
                                                double max_radius, const std::string& name);

}  // namespace atelier
