// B-spline curves of a curve network: input curves given by control points
// (sampled into polylines), and the control polygons of the network's
// segments, whose Catmull-Clark crease limit is the uniform cubic B-spline
// with interpolated ends (systems/curvenet/catmull_clark.h).
//
// Reads: its arguments. Writes: nothing else.
#pragma once

#include <span>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>

namespace atelier {

/// A B-spline curve: degree p, knot vector of control.size() + p + 1
/// non-decreasing values, defined on [knots[p], knots[control.size()]].
struct BSplineCurve {
  int degree = 3;
  std::vector<double> knots;
  std::vector<Vec3d> control;
};

/// Points of the curve at `samples_per_span` equal parameter steps in
/// every non-empty knot span (de Boor's algorithm), end points included.
/// Errors (kInvalidArgument): degree < 1, fewer than degree + 1 control
/// points, a knot vector of the wrong size, decreasing or non-finite knots,
/// an empty parameter domain, a non-finite control point.
[[nodiscard]] Expected<std::vector<Vec3d>> sample_bspline(const BSplineCurve& curve, int samples_per_span = 8);

/// The uniform cubic B-spline of a crease polygon P_0 .. P_m at t in [0, m],
/// with phantom points P_{-1} = 2 P_0 - P_1 and P_{m+1} = 2 P_m - P_{m-1}
/// (what Catmull-Clark's crease rules converge to between two corners).
[[nodiscard]] Vec3d crease_spline_point(std::span<const Vec3d> polygon, double t);

/// The crease polygon of `count` points (count >= 2) whose spline best fits
/// the polyline in the least-squares sense (chord-length parameters), with
/// P_0 and P_m equal to the polyline's end points bit for bit. The
/// polyline is first resampled at 8 points per polygon edge so that the
/// fit is determined; a tiny second-difference term keeps it well posed.
[[nodiscard]] std::vector<Vec3d> fit_crease_polygon(std::span<const Vec3d> polyline, std::size_t count);

/// The largest distance between the polyline, resampled as for the fit,
/// and the spline at the same (chord-length) parameters: an upper bound of
/// the polyline's distance to the spline at those points.
[[nodiscard]] double crease_fit_error(std::span<const Vec3d> polyline, std::span<const Vec3d> polygon);

}  // namespace atelier
