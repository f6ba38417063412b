// Profiles from a sketched stroke (systems/profile/profile_curve.h, seed 000
// section 4.1.4): the edges a stroke selects on screen, the projection plane
// (the dihedral bisector of one edge, the least-squares plane of several, or
// facing the camera), and a point list per edge cut from the stroke
// projected on that plane.
#include <atelier/systems/profile/profile_curve.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "profile_curve_detail.h"

namespace atelier {

namespace {

using profile_curve_detail::chord_params;

/// Closest point of polyline pts to p as a real index s (segment floor(s), fraction s - floor(s)).
[[nodiscard]] double closest_polyline_param(std::span<const Vec3d> pts, const Vec3d& p) noexcept {
  if (pts.size() == 1) return 0;
  double best = std::numeric_limits<double>::infinity(), best_s = 0;
  for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
    const Vec3d ab = pts[k + 1] - pts[k];
    const double l2 = ab.squaredNorm();
    const double t = l2 > 0 ? std::clamp((p - pts[k]).dot(ab) / l2, 0.0, 1.0) : 0.0;
    const double d = (pts[k] + t * ab - p).squaredNorm();
    if (d < best) {
      best = d;
      best_s = double(k) + t;
    }
  }
  return best_s;
}

[[nodiscard]] double point_segment_distance2_2d(const Vec2d& p, const Vec2d& a, const Vec2d& b) noexcept {
  const Vec2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

[[nodiscard]] double stroke_distance2(std::span<const Vec2d> stroke, const Vec2d& p) noexcept {
  if (stroke.size() == 1) return (stroke[0] - p).squaredNorm();
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k + 1 < stroke.size(); ++k)
    best = std::min(best, point_segment_distance2_2d(p, stroke[k], stroke[k + 1]));
  return best;
}

/// Newell normal (area-weighted, unnormalised) of a face.
[[nodiscard]] Vec3d face_normal(const Model& m, std::span<const Vec3d> pos, FaceIdx f) {
  Vec3d n = Vec3d::Zero();
  m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
    const Vec3d& a = pos[m.tail(h).value];
    const Vec3d& b = pos[m.head(h).value];
    n += a.cross(b);
  });
  return n;
}

}  // namespace

// ------------------------------------------------------------------ strokes

std::vector<EdgeIdx> select_edges_by_stroke(const Model& m, std::span<const Vec3d> positions, const Camera& cam,
                                            std::span<const Vec2d> stroke, double tol_px,
                                            const std::function<bool(const Vec3d&)>& visible) {
  std::vector<EdgeIdx> out;
  if (stroke.empty()) return out;
  if (!positions.empty() && positions.size() < m.nodes.slots.capacity()) return out;  // one position per node slot
  const std::span<const Vec3d> pos = positions.empty() ? std::span<const Vec3d>(m.nodes.position) : positions;
  const double tol2 = tol_px * tol_px;
  // Screen-space box of the stroke grown by the tolerance: a cheap reject.
  Vec2d lo = stroke[0], hi = stroke[0];
  for (const Vec2d& s : stroke) {
    lo = lo.cwiseMin(s);
    hi = hi.cwiseMax(s);
  }
  lo.array() -= tol_px;
  hi.array() += tol_px;
  auto near_stroke = [&](const Vec3d& p) {
    const Vec3d q = cam.project(p);
    if (!q.allFinite()) return false;
    const Vec2d px = q.head<2>();
    if ((px.array() < lo.array()).any() || (px.array() > hi.array()).any()) return false;
    return stroke_distance2(stroke, px) <= tol2;
  };
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e})) continue;
    const HalfedgeIdx h = halfedge_of(EdgeIdx{e}, 0);
    const Vec3d& a = pos[m.tail(h).value];
    const Vec3d& b = pos[m.head(h).value];
    if (!near_stroke(a) || !near_stroke(b)) continue;
    if (visible && !(visible(a) && visible(b) && visible(0.5 * (a + b)))) continue;
    out.push_back(EdgeIdx{e});
  }
  return out;
}

namespace {

/// The plane through a line (point c, unit direction d) whose normal is as
/// close as possible to the viewing direction at c (seed 000 4.1.4: "the
/// sketched profile faces towards the camera as much as possible").
[[nodiscard]] Expected<Vec3d> camera_facing_normal(const Camera& cam, const Vec3d& c, const Vec3d& d) {
  const Vec3d q = cam.project(c);
  if (!q.allFinite()) return Status(ErrorCode::kDegenerate, "stroke plane: the edges are behind the camera");
  const Vec3d v = cam.ray(q.head<2>()).second;
  const Vec3d n = v - v.dot(d) * d;
  if (!(n.norm() > 1e-9)) return Status(ErrorCode::kDegenerate, "stroke plane: the edge points at the camera");
  return Vec3d(n.normalized());
}

}  // namespace

Expected<StrokeProfiles> profiles_from_stroke(const Model& m, std::span<const Vec3d> positions, const Camera& cam,
                                              std::span<const Vec2d> stroke, double tol_px,
                                              const std::function<bool(const Vec3d&)>& visible) {
  const std::span<const Vec3d> pos = positions.empty() ? std::span<const Vec3d>(m.nodes.position) : positions;
  if (!positions.empty() && positions.size() < m.nodes.slots.capacity())
    return Status(ErrorCode::kMismatch, "profiles_from_stroke: " + std::to_string(positions.size()) +
                                            " positions for " + std::to_string(m.nodes.slots.capacity()) + " nodes");
  if (stroke.size() < 2) return Status(ErrorCode::kInvalidArgument, "profiles_from_stroke: the stroke needs 2 points");
  const std::vector<EdgeIdx> sel = select_edges_by_stroke(m, pos, cam, stroke, tol_px, visible);
  if (sel.empty())
    return Status(ErrorCode::kInvalidArgument, "profiles_from_stroke: no visible edge has both ends within " +
                                                   std::to_string(tol_px) + " px of the stroke");

  StrokeProfiles out;
  // ---- the projection plane
  std::vector<NodeIdx> ends;
  for (EdgeIdx e : sel) {
    ends.push_back(m.tail(halfedge_of(e, 0)));
    ends.push_back(m.head(halfedge_of(e, 0)));
  }
  std::sort(ends.begin(), ends.end());
  ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
  Vec3d centre = Vec3d::Zero();
  for (NodeIdx v : ends) centre += pos[v.value];
  centre /= double(ends.size());
  Vec3d normal = Vec3d::Zero();
  if (sel.size() == 1) {
    const HalfedgeIdx h0 = halfedge_of(sel[0], 0), h1 = halfedge_of(sel[0], 1);
    const Vec3d d = (pos[m.head(h0).value] - pos[m.tail(h0).value]).normalized();
    if (m.face(h0).valid() && m.face(h1).valid()) {
      // Bisector of the dihedral angle: the plane holding the edge and the
      // mean of the two unit face normals (both perpendicular to the edge).
      const Vec3d nm = face_normal(m, pos, m.face(h0)).normalized() + face_normal(m, pos, m.face(h1)).normalized();
      const Vec3d w = nm - nm.dot(d) * d;
      if (w.norm() > 1e-9) normal = d.cross(w).normalized();
    }
    if (normal == Vec3d::Zero()) {
      auto n = camera_facing_normal(cam, centre, d);
      if (!n) return n.status();
      normal = *n;
    }
  } else {
    // Least-squares plane of the end points: normal = eigenvector of the
    // smallest eigenvalue of their covariance.
    Mat3d cov = Mat3d::Zero();
    for (NodeIdx v : ends) {
      const Vec3d r = pos[v.value] - centre;
      cov += r * r.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Mat3d> es(cov);
    const Vec3d ev = es.eigenvalues();
    if (ev(1) <= 1e-12 * std::max(ev(2), std::numeric_limits<double>::min())) {
      // Collinear end points: any plane through the line fits; face the camera.
      auto n = camera_facing_normal(cam, centre, es.eigenvectors().col(2).normalized());
      if (!n) return n.status();
      normal = *n;
    } else {
      normal = es.eigenvectors().col(0).normalized();
    }
  }
  {
    const Vec3d q = cam.project(centre);
    if (q.allFinite() && normal.dot(cam.ray(q.head<2>()).second) > 0) normal = -normal;
  }
  out.plane_point = centre;
  out.plane_normal = normal;

  // ---- the stroke on the plane
  for (const Vec2d& px : stroke) {
    const auto [o, dir] = cam.ray(px);
    const double den = normal.dot(dir);
    if (!(std::abs(den) > 1e-12)) continue;  // ray parallel to the plane
    const double t = normal.dot(centre - o) / den;
    out.stroke_points.push_back(o + t * dir);
  }
  // Repeated pixels of a slow stroke would repeat points: cut a copy without them.
  std::vector<Vec3d> Y = out.stroke_points;
  Y.erase(std::unique(Y.begin(), Y.end(), [](const Vec3d& p, const Vec3d& q) { return p == q; }), Y.end());
  if (Y.size() < 2)
    return Status(ErrorCode::kDegenerate, "profiles_from_stroke: the stroke misses the projection plane");

  // ---- cut per edge: the points strictly between the closest stroke points to its ends
  for (EdgeIdx e : sel) {
    HalfedgeIdx h = halfedge_of(e, 0);
    double sa = closest_polyline_param(Y, pos[m.tail(h).value]);
    double sb = closest_polyline_param(Y, pos[m.head(h).value]);
    if (sb < sa) {
      h = twin(h);
      std::swap(sa, sb);
    }
    const Vec3d a = pos[m.tail(h).value], b = pos[m.head(h).value];
    const double snap = 1e-9 * (b - a).norm();
    std::vector<Vec3d> chain{a};
    for (std::size_t k = 0; k < Y.size(); ++k) {
      const double s = double(k);
      if (!(s > sa && s < sb)) continue;
      if ((Y[k] - a).norm() <= snap || (Y[k] - b).norm() <= snap) continue;
      chain.push_back(Y[k]);
    }
    chain.push_back(b);
    const std::vector<double> u = chord_params(chain);
    PointListProfile p;
    p.a = a;
    p.b = b;
    p.points.assign(chain.begin() + 1, chain.end() - 1);
    p.u.assign(u.begin() + 1, u.end() - 1);
    out.edges.push_back(h);
    out.profiles.push_back(std::move(p));
  }
  return out;
}

Status attach_stroke_profiles(Model& m, const StrokeProfiles& sp) {
  if (sp.edges.size() != sp.profiles.size())
    return {ErrorCode::kMismatch, "attach_stroke_profiles: edges and profiles differ in number"};
  for (std::size_t i = 0; i < sp.edges.size(); ++i) {
    const HalfedgeIdx h = sp.edges[i];
    if (!h.valid() || h.value >= m.halfedges.tail.size() || !m.alive(h))
      return {ErrorCode::kStaleHandle, "attach_stroke_profiles: halfedge " + std::to_string(h.value) + " is dead"};
    if (Status s = attach_point_list(m, m.surface_of(edge_of(h)), h, sp.profiles[i].u, sp.profiles[i].points); !s)
      return s;
  }
  return {};
}

}  // namespace atelier
