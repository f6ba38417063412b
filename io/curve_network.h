// Curve networks as polylines (seed 003's input): the `CURVE i` text format
// of ../shared/data/curve-networks/ and OBJ `l` polylines (io/obj.h).
//
// The `CURVE i` format: a header line `CURVE <integer id>` starts a curve,
// every following line until the next header holds one point `x y z`.
// Ids may have gaps and come in any order but must be unique. Blank lines,
// `#` comments, \r\n and tabs are accepted. Refused, with an error naming
// the file, the line and the curve: a point before any header, a point
// without exactly 3 finite numbers, a header without an integer id, a
// repeated id, a curve with fewer than 2 points, an empty file.
//
// Reading is a pure function of the bytes (parse_curve_network takes bytes
// and a display name and never throws for malformed input: a fuzzing entry
// point). Writing goes through an AtomicFile (all or nothing) with the
// shortest round-trip text for every coordinate.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>

namespace atelier {

/// Polylines in CSR form: curve c has points[offsets[c] .. offsets[c+1]).
struct PolylineSet {
  std::vector<Vec3d> points;
  std::vector<std::uint32_t> offsets{0};
  std::vector<std::int64_t> ids;     // the file's curve numbers (gaps allowed), one per curve
  std::vector<std::uint64_t> lines;  // 1-based line of each curve's header, 0 when built in memory
  std::string source;                // the file name used in messages ("" in memory)

  [[nodiscard]] std::size_t size() const noexcept { return offsets.size() - 1; }
  [[nodiscard]] std::span<const Vec3d> curve(std::size_t c) const noexcept {
    return {points.data() + offsets[c], offsets[c + 1] - offsets[c]};
  }
  /// Appends a curve (line 0: built in memory).
  void add(std::int64_t id, std::span<const Vec3d> pts, std::uint64_t line = 0);
  /// "CURVE 7 (file: line 120)" or "CURVE 7" for messages.
  [[nodiscard]] std::string describe(std::size_t c) const;
};

/// Parses the `CURVE i` format from bytes. Errors (kParse) name
/// `display_name`, the line and the curve; never throws for malformed text.
[[nodiscard]] Expected<PolylineSet> parse_curve_network(std::string_view bytes, std::string_view display_name);

/// Reads a curve network by extension: `.obj` reads the OBJ `l` polylines
/// (read_obj_polylines), anything else the `CURVE i` format. Throws
/// Error(kIo) for file-system failures and Error(kParse) for bad content.
[[nodiscard]] PolylineSet read_curve_network(const std::filesystem::path& path);

/// Writes the `CURVE i` format (ids from `curves.ids`, or 0..n-1 when empty).
/// Throws Error(kInvalidArgument) for a non-finite point or a curve with
/// fewer than 2 points (the file would not read back).
void write_curve_network(const PolylineSet& curves, const std::filesystem::path& path);

}  // namespace atelier
