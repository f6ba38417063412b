// Trimming a net by a curve (seed 004 section 6, "Trimming"): the curve,
// lying on the net, is discretised and extended locally orthogonally to the
// net into a second net (a band of quads, curve point p_k -> p_k -/+ h n_k
// with n_k the normal of the net's triangle closest to p_k); the net is cut
// along its intersection with the band exactly as in the Booleans
// (sections 2-3, exact mode: cut.cpp) and the part the curve encloses is
// thrown away.
//
// The enclosed part: the pieces between cut edges that do not reach the
// net's boundary (an open net, e.g. a plane), or for a closed net the
// piece of smallest area. TrimOptions::keep_enclosed keeps it instead.
//
// Reads: the net (polygon soup, open or closed), the curve. Writes
// nothing (the trimmed net is returned). Errors: a curve of fewer than 3
// points or with non-finite points, a net the Booleans refuse (open nets
// are allowed here), a curve that does not cut the net into two parts.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>

#include <cstddef>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

namespace atelier {

struct TrimOptions {
  /// Half height h of the band; 0 picks twice the net's mean edge length.
  double height = 0.0;
  bool keep_enclosed = false;
};

struct TrimReport {
  PolygonSoup result;
  PolygonSoup band;  // the extruded curve (the second net)
  double area_before = 0, area_after = 0;
  std::size_t cut_points = 0;  // new points where the band meets the net
  std::size_t parts = 0;       // pieces the cut made
};

/// Trims `net` by the closed polyline `curve` (see above).
[[nodiscard]] Expected<TrimReport> trim_net(const PolygonSoupView& net, std::span<const Vec3d> curve,
                                            const TrimOptions& opt = {}, const ExecContext& ctx = {});

/// Reads a curve file: one point per line as "x y z" (blank lines and lines
/// starting with '#' ignored). Throws Error(kParse) naming the file and line
/// for anything else (wrong count, not a number, not finite), Error(kIo)
/// when it cannot be read.
[[nodiscard]] std::vector<Vec3d> read_curve(const std::filesystem::path& path);
[[nodiscard]] std::vector<Vec3d> parse_curve(std::string_view text, std::string_view display_name);

}  // namespace atelier
