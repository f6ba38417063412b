// Stroke files: a camera and 2D strokes drawn through it, as data (JSON,
// docs/strokes.md), so that any front end (a web sketcher, a script, a test)
// drives the sketch tools of seed 001 section 5 (painting, penetrated
// painting, cutting, partitioning; systems/sketch/).
//
//   {"camera": {"view": [16 numbers, row-major], "projection": [16 numbers, row-major],
//               "viewport": [width, height]},
//    "strokes": [{"points": [[x, y], ...], "tool": "paint", "through": false}, ...]}
//
// Screen points are pixels with the origin at the top-left corner, y down
// (Camera::project). Tools: "paint" (visible painting), "paint-through"
// (penetrated painting), "cut", "partition" (their curve comes from visible
// painting, or penetrated painting with "through": true), "pick" (one
// point: the side that the preceding "cut" removes) and "extrude" (seed 002:
// a run of 2 or 3 consecutive extrude strokes is one extrusion, the base
// stroke then one or two extruding strokes). A stroke may carry its own
// "camera" (same keys as the file's), e.g. the extruding strokes drawn from
// a second view.
//
// Reads: bytes or a file. Writes: nothing (write_strokes: one file,
// atomically). Malformed input is refused with kParse naming the file and
// the JSON location (a JSON pointer such as /strokes/2/points/5/1, or
// line:column for syntax errors); nothing here can crash, hang or return a
// non-finite value on any input (the parser is a fuzzing entry point).
#pragma once

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/systems/view/camera.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace atelier {

enum class StrokeTool : std::uint8_t { kPaint, kPaintThrough, kCut, kPartition, kPick, kExtrude };

/// "paint", "paint-through", "cut", "partition", "pick", "extrude".
[[nodiscard]] const char* to_string(StrokeTool t) noexcept;

struct Stroke {
  std::vector<Vec2d> points;  // pixels, (0, 0) at the top-left corner, y down
  StrokeTool tool = StrokeTool::kPaint;
  /// Cut and partition: take the curve from penetrated painting (every
  /// layer the rays cross) instead of visible painting. Always true for
  /// kPaintThrough; "paint" with "through": true reads as kPaintThrough.
  bool through = false;
  std::string name;  // optional, for reports
  /// The camera this stroke was drawn through, when not the file's.
  std::optional<Camera> camera;
};

struct StrokeFile {
  Camera camera;
  std::vector<Stroke> strokes;
};

struct StrokeLimits {
  std::size_t max_bytes = std::size_t{64} << 20;  // larger inputs are refused before parsing
  std::size_t max_depth = 16;                     // JSON nesting (a valid file needs 4)
  std::size_t max_points = 1'000'000;             // over all strokes
  double max_coordinate = 1e7;                    // |x|, |y| in pixels
};

/// Parses and checks a stroke file held in memory; `file_name` names it in
/// messages. Checks: the keys (missing, unknown, wrong type), 16 finite
/// numbers per matrix, a positive integer viewport, Camera::check() (a
/// singular projection * view is refused), finite coordinates within
/// limits.max_coordinate, at least 2 distinct points for paint, cut and
/// partition and extrude strokes, exactly 1 for a pick, which must follow a
/// cut, runs of 2 or 3 extrude strokes, per-stroke cameras as the file's.
/// Errors: kParse "<file>: at <JSON pointer>: <problem>" or
/// "<file>:<line>:<column>: <problem>" for syntax errors.
[[nodiscard]] Expected<StrokeFile> parse_strokes(std::string_view bytes, std::string_view file_name,
                                                 const StrokeLimits& limits = {});
/// Reads a stroke file (kIo when it cannot be read, then as parse_strokes).
[[nodiscard]] Expected<StrokeFile> read_strokes(const std::filesystem::path& path, const StrokeLimits& limits = {});

/// The JSON text of a stroke file (numbers written so that they read back
/// bit-identical: parse_strokes(to_json(s)) == s). kInvalidArgument when a
/// number is not finite or a stroke would not pass parse_strokes.
[[nodiscard]] Expected<std::string> strokes_to_json(const StrokeFile& file);
/// Writes strokes_to_json(file) atomically (io/atomic_file.h).
[[nodiscard]] Status write_strokes(const StrokeFile& file, const std::filesystem::path& path);

}  // namespace atelier
