// Body measurements along feature curves (seed 001 section 4: bodies are
// described by their feature curves): girths as a tape measure takes them,
// raw curve lengths, and heights of feature points; CSV export for body sets.
//
// Reads: a ReferenceBody's feature tables and node positions (or a position
// array of another body with the same topology). Writes: nothing but the
// returned values / the output stream.
#pragma once

#include <cstdint>
#include <functional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/systems/body/reference_body.h>

namespace atelier {

/// Length of a polyline (closed adds the closing segment).
[[nodiscard]] double polyline_length(std::span<const Vec3d> pts, bool closed) noexcept;

/// Tape-measure girth of a closed curve: perimeter of the convex hull of the
/// curve projected onto its least-squares plane (a tape bridges concavities).
[[nodiscard]] double tape_girth(std::span<const Vec3d> closed_curve);

struct CurveMeasure {
  std::int32_t id = -1;
  std::string name;
  bool closed = false;
  double girth = 0;   // tape girth (closed curves; NaN for open ones)
  double length = 0;  // raw polyline length
};

struct PointMeasure {
  std::int32_t id = -1;
  std::string name;
  double height = 0;  // above the lowest skin node (the floor)
};

struct BodyMeasurements {
  double stature = 0;  // vertical extent of the skin (y up)
  std::vector<CurveMeasure> curves;  // in the body's curve-table order
  std::vector<PointMeasure> points;  // in the body's point-table order
};

[[nodiscard]] Expected<BodyMeasurements> measure_body(const ReferenceBody& body);
/// Measures another body of the same topology given by its node positions.
[[nodiscard]] Expected<BodyMeasurements> measure_body(const ReferenceBody& features, std::span<const Vec3d> positions);

/// CSV column names (after the leading "body" column): stature, then
/// <curve>_girth for closed curves, <curve>_length for all, <point>_height.
[[nodiscard]] std::vector<std::string> measurement_columns(const ReferenceBody& features);
[[nodiscard]] std::vector<double> measurement_row(const BodyMeasurements& m);

/// Writes a header and one row per body: body i has node positions
/// positions(i) on the topology and features of `features`. Rows are
/// computed in parallel (by ctx) and written in order; streaming callers
/// can call it chunk by chunk with first_index and header = false.
[[nodiscard]] Status measurements_csv(std::ostream& out, const ReferenceBody& features, std::size_t count,
                                      const std::function<std::vector<Vec3d>(std::size_t)>& positions,
                                      const ExecContext& ctx = {}, bool header = true, std::size_t first_index = 0);
/// Bodies that share one feature definition (checked by curve names).
[[nodiscard]] Status measurements_csv(std::ostream& out, std::span<const ReferenceBody> bodies,
                                      const ExecContext& ctx = {});

}  // namespace atelier
