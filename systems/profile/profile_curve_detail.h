// Internals shared by the sources of the profile curves
// (systems/profile/profile_curve.h):
//
//   profile_curve.cpp   curves, Bezier encoding, point lists
//   profile_stroke.cpp  profiles from a sketched stroke
#pragma once

#include <span>
#include <vector>

#include <atelier/engine/math.h>

namespace atelier::profile_curve_detail {

/// Chord-length parameters of a point sequence (uniform if it has no length).
[[nodiscard]] inline std::vector<double> chord_params(std::span<const Vec3d> pts) {
  std::vector<double> u(pts.size(), 0.0);
  if (pts.size() < 2) return u;
  for (std::size_t i = 1; i < pts.size(); ++i) u[i] = u[i - 1] + (pts[i] - pts[i - 1]).norm();
  const double total = u.back();
  for (std::size_t i = 0; i < pts.size(); ++i) u[i] = total > 0 ? u[i] / total : double(i) / double(pts.size() - 1);
  u.front() = 0.0;
  u.back() = 1.0;
  return u;
}

}  // namespace atelier::profile_curve_detail
