// A user's own reference body from a file (issue 26, "any reference body"):
// a closed, consistently oriented OBJ mesh in the user's units and up axis.
//
// The transform is applied at the door: the engine always works in metres
// with Y up (the frame of the mannequin and MakeHuman bodies), and what is
// written back for the user (regenerated garments, body meshes) is turned
// back into the file's units and axes with BodyFrame::to_file. Both maps are
// exact permutations and sign changes of the axes times one scale, so a body
// given in centimetres and Z-up is the same body to the engine as in metres
// and Y-up, up to the rounding of the scale (docs/body-files.md).
//
// Reads: the OBJ file. Writes: a new ReferenceBody.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/body/reference_body.h>

#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

namespace atelier {

/// The up axis of a file: the engine's is Y.
enum class UpAxis : std::uint8_t { kY, kZ };

/// "y" or "z" (either case); anything else is kInvalidArgument naming it.
[[nodiscard]] Expected<UpAxis> parse_up_axis(std::string_view text);

/// A file's units and axes relative to the engine's (metres, Y up).
///
/// to_engine(p) = scale * R p, with R the identity for Y-up files and, for
/// Z-up files, the rotation by -90 degrees about X taking file (x, y, z) to
/// (x, z, -y): file up (+z) becomes engine up (+y) and the right-handed
/// frame keeps its handedness, so outward faces stay outward. A scale of
/// 1/n for a whole n (0.01, 0.001) divides by n instead of multiplying by
/// the rounded 1/n: one rounding, so file coordinates that are exactly n
/// times a double map to that double bit for bit.
struct BodyFrame {
  double scale = 1.0;  // file units to metres: 0.01 for centimetres, 0.001 for millimetres
  UpAxis up = UpAxis::kY;

  [[nodiscard]] Vec3d to_engine(const Vec3d& p) const noexcept;
  /// The inverse: engine (metres, Y up) to the file's units and axes.
  [[nodiscard]] Vec3d to_file(const Vec3d& p) const noexcept;
  void to_engine(std::span<Vec3d> points) const noexcept;
  void to_file(std::span<Vec3d> points) const noexcept;
  [[nodiscard]] bool identity() const noexcept { return scale == 1.0 && up == UpAxis::kY; }
  /// Errors: a scale that is not finite and positive, or so large or small
  /// that a body of 1e-3 to 1e3 file units would leave 1e-6 to 1e6 metres.
  [[nodiscard]] Status check() const;
};

/// Checks that the model's faces form closed, consistently oriented shells
/// facing outward: every edge is used by exactly two faces, once in each
/// direction, and the enclosed (signed) volume is positive. The error names
/// `what` (a file), the first bad edge by its two vertices (1-based, as in
/// an OBJ file) and how many edges are bad.
[[nodiscard]] Status check_closed_oriented(const Model& m, std::string_view what);

struct BodyFileOptions {
  BodyFrame frame;
  /// A MakeHuman data folder (`<data>/makehuman`): a body with the topology
  /// of MakeHuman's base mesh takes its feature curves. Empty: not tried.
  std::filesystem::path makehuman_data;
  /// A feature-curve file (io/feature_curves.h, docs/body-files.md): its
  /// curves are snapped onto the body (add_snapped_feature_curves) and
  /// replace any a known topology would give. Empty: none.
  std::filesystem::path features;
  /// Tolerances of the snap (metres); `source` is set to the file's name.
  FeatureSnapOptions snap;
};

/// Reads a reference body from an OBJ file and maps it to metres, Y up.
///
/// Feature curves are not in an OBJ file. A body with the topology of a
/// known reference (the mannequin, or MakeHuman's base mesh with
/// options.makehuman_data) takes that reference's feature curves and points:
/// they sit on nodes, edges and faces, so they follow the file's positions.
/// Any other body has none: detail templates (garments) encode and
/// regenerate on it, profile templates refuse it; unless options.features
/// names a feature-curve file: its points, in its own "units" and "up" when
/// it gives them and in options.frame otherwise, are mapped to metres and Y
/// up and snapped onto the body (add_snapped_feature_curves); then only the
/// file's curves are the body's.
///
/// Errors (each naming the file): missing or malformed file (with its line),
/// a bad frame, a mesh that is not closed, not consistently oriented or
/// facing inward (check_closed_oriented); a feature-curve file that is
/// missing or malformed, or a point of it too far from the body (naming the
/// file, line, curve and point).
[[nodiscard]] Expected<ReferenceBody> read_reference_body(const std::filesystem::path& file,
                                                          const BodyFileOptions& options = {},
                                                          const ExecContext& ctx = {});

}  // namespace atelier
