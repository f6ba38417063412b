// Feature-curve files (issue 26, "any reference body"): the named polylines
// a user draws on their own reference body, so profile templates, which are
// placed relative to the body's girths and centre lines, encode on it.
//
// The format (docs/body-files.md) is JSON:
//
//   {"units": "cm", "up": "z",
//    "curves": [{"name": "waist", "closed": true, "points": [[x, y, z], ...]},
//               {"name": "centre_front", "closed": false, "points": [...]}]}
//
//  - "units" ("m", "cm" or "mm") and "up" ("y" or "z") are optional; when
//    absent the points are in the body file's units and axes (the --scale
//    and --up of the body);
//  - every curve has a "name" from feature_curve_names() (the names the
//    profile templates ask for; each at most once), "closed" (girths and
//    armholes are closed loops) and "points", at least 2 for an open curve
//    and 3 for a closed one (a closed curve's last point may repeat its
//    first: it is dropped), each exactly 3 finite numbers of magnitude at
//    most 1e6.
// Nothing else is accepted: an unknown key, a wrong type, a duplicate key or
// name, trailing text, nesting deeper than 16, more than 1,000,000 points.
//
// Reading is a pure function of the bytes: parse_feature_curves never throws
// for malformed input (a fuzzing entry point, fuzz/feature_curves_fuzz.cpp)
// and every error (kParse) names the file and the line of the offending
// element, with the curve's name or index and the point's index.
#pragma once

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace atelier {

/// One named polyline of a feature-curve file, in the file's units and axes.
struct FeatureCurveSpec {
  std::string name;
  bool closed = false;
  std::vector<Vec3d> points;
  std::vector<std::uint32_t> point_lines;  // 1-based line of each point
  std::uint32_t line = 0;                  // 1-based line of the curve's object
};

struct FeatureCurveFile {
  std::string source;      // the file name used in messages
  bool has_units = false;  // "units" given: `scale` is the file's own
  double scale = 1.0;      // file units to metres ("m" 1, "cm" 0.01, "mm" 0.001)
  bool has_up = false;     // "up" given: `up_z` is the file's own
  bool up_z = false;       // "z": file (x, y, z) is engine (x, z, -y)
  std::vector<FeatureCurveSpec> curves;
};

/// The curve names a feature-curve file may use: the mannequin's names and
/// MakeHuman's spellings of them (both are asked for by the profile
/// templates, systems/profile/project_templates.cpp).
[[nodiscard]] std::span<const std::string_view> feature_curve_names() noexcept;

/// Parses a feature-curve file from bytes. Errors (kParse) name
/// `display_name` and the line; never throws for malformed text.
[[nodiscard]] Expected<FeatureCurveFile> parse_feature_curves(std::string_view bytes, std::string_view display_name);

/// Reads and parses a file (kIo when it cannot be read; at most 64 MB).
[[nodiscard]] Expected<FeatureCurveFile> read_feature_curves(const std::filesystem::path& path);

/// Writes `f` (curves in order; units and up when has_units / has_up) with
/// the shortest round-trip text for every coordinate, atomically. Throws
/// Error(kInvalidArgument) for what parse_feature_curves would refuse.
void write_feature_curves(const FeatureCurveFile& f, const std::filesystem::path& path);

}  // namespace atelier
