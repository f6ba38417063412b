// Profile curves (systems/profile/profile_curve.h): evaluation, halving,
// distance, the Bezier encoding (seed 001 eq. (7)) and attached point lists
// (seed 000 eq. (3)). Profiles from a sketched stroke are in
// profile_stroke.cpp.
#include <atelier/systems/profile/profile_curve.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <string>

#include "profile_curve_detail.h"


namespace atelier {

namespace {


[[nodiscard]] Vec3d lerp(const Vec3d& a, const Vec3d& b, double t) noexcept {
  return (1.0 - t) * a + t * b;
}

/// Scratch for de Casteljau: on the stack up to degree 7 (profiles are cubic),
/// so evaluation in the distance search does not allocate.
class Scratch {
 public:
  explicit Scratch(std::span<const Vec3d> p) {
    if (p.size() > small_.size()) {
      big_.assign(p.begin(), p.end());
      data_ = big_.data();
    } else {
      std::copy(p.begin(), p.end(), small_.begin());
      data_ = small_.data();
    }
  }
  Vec3d& operator[](std::size_t i) noexcept { return data_[i]; }

 private:
  std::array<Vec3d, 8> small_;
  std::vector<Vec3d> big_;
  Vec3d* data_ = nullptr;
};

/// De Casteljau value and first/second derivatives of a Bezier at t.
struct BezierJet {
  Vec3d c, d1, d2;
};
[[nodiscard]] BezierJet bezier_jet(std::span<const Vec3d> P, double t) {
  const std::size_t n = P.size() - 1;
  Scratch b(P);
  BezierJet j{Vec3d::Zero(), Vec3d::Zero(), Vec3d::Zero()};
  // After n-2 levels three points remain: C'' = n(n-1)(q2 - 2 q1 + q0); after
  // n-1 levels two: C' = n(q1 - q0).
  for (std::size_t r = 1; r <= n; ++r) {
    const std::size_t left = n + 2 - r;  // points before this level
    if (left == 3) j.d2 = double(n) * double(n - 1) * (b[2] - 2.0 * b[1] + b[0]);
    if (left == 2) j.d1 = double(n) * (b[1] - b[0]);
    for (std::size_t i = 0; i + 1 < left; ++i) b[i] = lerp(b[i], b[i + 1], t);
  }
  j.c = b[0];
  return j;
}

[[nodiscard]] double point_segment_distance2(const Vec3d& p, const Vec3d& a, const Vec3d& b) noexcept {
  const Vec3d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

[[nodiscard]] bool is_profile_node(const Model& m, std::uint32_t i) noexcept {
  const auto& an = m.attrib_nodes;
  return m.alive(AttribNodeIdx{i}) && an.kind[i] == AttribNodeKind::kEdge && !an.owner[i].valid();
}

using profile_curve_detail::chord_params;

}  // namespace

// ------------------------------------------------------------------ ProfileCurve

Vec3d ProfileCurve::eval(double t) const {
  t = std::clamp(t, 0.0, 1.0);
  if (points.size() == 1) return points[0];
  if (kind == Kind::kBezier) {
    Scratch b(points);
    for (std::size_t left = points.size(); left > 1; --left)
      for (std::size_t i = 0; i + 1 < left; ++i) b[i] = lerp(b[i], b[i + 1], t);
    return b[0];
  }
  // Segment k with u[k] <= t < u[k+1] (the last segment for t = 1).
  const auto it = std::upper_bound(u.begin(), u.end(), t);
  std::size_t k = it == u.begin() ? 0 : std::size_t(it - u.begin()) - 1;
  k = std::min(k, points.size() - 2);
  const double du = u[k + 1] - u[k];
  if (!(du > 0)) return points[t >= u[k + 1] ? k + 1 : k];
  const double f = (t - u[k]) / du;
  if (f == 0.0) return points[k];
  if (f == 1.0) return points[k + 1];
  return lerp(points[k], points[k + 1], f);
}

std::pair<ProfileCurve, ProfileCurve> ProfileCurve::split_half() const {
  ProfileCurve l, r;
  l.kind = r.kind = kind;
  const Vec3d mid = eval(0.5);
  if (kind == Kind::kBezier) {
    // seed 000 section 4.2 / Fig. 6b: the two halves of the de Casteljau pyramid at t = 1/2.
    const std::size_t n1 = points.size();
    std::vector<Vec3d> b = points;
    l.points.resize(n1);
    r.points.resize(n1);
    for (std::size_t level = 0; level < n1; ++level) {
      const std::size_t left = n1 - level;
      l.points[level] = b[0];
      r.points[n1 - 1 - level] = b[left - 1];
      for (std::size_t i = 0; i + 1 < left; ++i) b[i] = lerp(b[i], b[i + 1], 0.5);
    }
    // The apex equals eval(0.5) up to contraction; make the shared end exact.
    l.points.back() = mid;
    r.points.front() = mid;
    return {std::move(l), std::move(r)};
  }
  // Polyline: cut at u = 1/2. Points with u < 1/2 go left, u > 1/2 right;
  // the cut point is shared (an existing point at exactly 1/2 is reused).
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (u[i] < 0.5) {
      l.points.push_back(points[i]);
      l.u.push_back(2.0 * u[i]);
    }
  }
  l.points.push_back(mid);
  l.u.push_back(1.0);
  r.points.push_back(mid);
  r.u.push_back(0.0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (u[i] > 0.5) {
      r.points.push_back(points[i]);
      r.u.push_back(2.0 * u[i] - 1.0);
    }
  }
  l.u.front() = 0.0;
  r.u.back() = 1.0;
  return {std::move(l), std::move(r)};
}

ProfileCurve ProfileCurve::reversed() const {
  ProfileCurve c;
  c.kind = kind;
  c.points.assign(points.rbegin(), points.rend());
  if (kind == Kind::kPolyline) {
    c.u.resize(u.size());
    for (std::size_t i = 0; i < u.size(); ++i) c.u[i] = 1.0 - u[u.size() - 1 - i];
  }
  return c;
}

double ProfileCurve::distance(const Vec3d& p) const {
  if (points.empty()) return std::numeric_limits<double>::infinity();
  if (points.size() == 1) return (points[0] - p).norm();
  if (kind == Kind::kPolyline) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k + 1 < points.size(); ++k)
      best = std::min(best, point_segment_distance2(p, points[k], points[k + 1]));
    return std::sqrt(best);
  }
  const std::size_t n = points.size() - 1;
  const std::size_t samples = std::max<std::size_t>(32, 16 * n);
  auto d2 = [&](double t) { return (eval(t) - p).squaredNorm(); };
  std::vector<double> s(samples + 1);
  for (std::size_t k = 0; k <= samples; ++k) s[k] = d2(double(k) / double(samples));
  double best = std::min(s.front(), s.back());
  const double h = 1.0 / double(samples);
  constexpr double kInvPhi = 0.6180339887498949;
  for (std::size_t k = 0; k <= samples; ++k) {
    const bool local_min = (k == 0 || s[k] <= s[k - 1]) && (k == samples || s[k] <= s[k + 1]);
    if (!local_min) continue;
    // Golden section on the bracket around the sampled minimum...
    double lo = std::max(0.0, double(k) * h - h), hi = std::min(1.0, double(k) * h + h);
    double x1 = hi - kInvPhi * (hi - lo), x2 = lo + kInvPhi * (hi - lo);
    double f1 = d2(x1), f2 = d2(x2);
    while (hi - lo > 1e-10) {
      if (f1 < f2) {
        hi = x2;
        x2 = x1;
        f2 = f1;
        x1 = hi - kInvPhi * (hi - lo);
        f1 = d2(x1);
      } else {
        lo = x1;
        x1 = x2;
        f1 = f2;
        x2 = lo + kInvPhi * (hi - lo);
        f2 = d2(x2);
      }
    }
    double t = 0.5 * (lo + hi), ft = d2(t);
    // ...then Newton on g(t) = (C - p).C' = 0, kept when it improves.
    for (int it = 0; it < 4; ++it) {
      const BezierJet j = bezier_jet(points, t);
      const double g = (j.c - p).dot(j.d1), dg = j.d1.squaredNorm() + (j.c - p).dot(j.d2);
      if (!(dg > 0)) break;
      const double tn = std::clamp(t - g / dg, 0.0, 1.0);
      const double fn = d2(tn);
      if (!(fn < ft)) break;
      t = tn;
      ft = fn;
    }
    best = std::min({best, ft, s[k]});
  }
  return std::sqrt(best);
}

Status ProfileCurve::check() const {
  if (points.size() < 2) return {ErrorCode::kInvalidArgument, "profile curve needs at least 2 points"};
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!is_finite(points[i]))
      return {ErrorCode::kDegenerate, "profile curve point " + std::to_string(i) + " is not finite"};
  if (kind == Kind::kBezier) return {};
  if (u.size() != points.size())
    return {ErrorCode::kMismatch, "polyline profile has " + std::to_string(points.size()) + " points but " +
                                      std::to_string(u.size()) + " parameters"};
  if (u.front() != 0.0 || u.back() != 1.0)
    return {ErrorCode::kInvalidArgument, "polyline profile parameters must run from 0 to 1"};
  for (std::size_t i = 1; i < u.size(); ++i)
    if (!(u[i] >= u[i - 1]))
      return {ErrorCode::kInvalidArgument, "polyline profile parameter " + std::to_string(i) + " decreases"};
  return {};
}

ProfileCurve ProfileCurve::polyline(std::span<const Vec3d> pts) {
  ProfileCurve c;
  c.kind = Kind::kPolyline;
  c.points.assign(pts.begin(), pts.end());
  c.u = chord_params(pts);
  return c;
}

ProfileCurve ProfileCurve::bezier(std::span<const Vec3d> control_points) {
  ProfileCurve c;
  c.kind = Kind::kBezier;
  c.points.assign(control_points.begin(), control_points.end());
  return c;
}

// ------------------------------------------------------------- Bezier encoding

Expected<BezierProfileEncoding> encode_bezier_profile(const ProfileCurve& c) {
  if (c.points.empty()) return Status(ErrorCode::kInvalidArgument, "empty profile curve");
  return encode_bezier_profile(c, c.start(), c.end());
}

Expected<BezierProfileEncoding> encode_bezier_profile(const ProfileCurve& c, const Vec3d& a, const Vec3d& b) {
  if (c.kind != ProfileCurve::Kind::kBezier)
    return Status(ErrorCode::kInvalidArgument, "eq. (6) encodes Bezier profiles only (got a polyline)");
  if (Status s = c.check(); !s) return s;
  if (!is_finite(a) || !is_finite(b)) return Status(ErrorCode::kDegenerate, "edge ends are not finite");
  // eq. (6): the chord E(u) as a degree-n Bezier has control points E(i/n),
  // so ep = C - E is the Bezier with control points P_i - E(i/n).
  const std::size_t n = c.points.size() - 1;
  BezierProfileEncoding e;
  e.offsets.resize(n + 1);
  for (std::size_t i = 0; i <= n; ++i) e.offsets[i] = c.points[i] - lerp(a, b, double(i) / double(n));
  return e;
}

ProfileCurve decode_bezier_profile(const BezierProfileEncoding& e, const Vec3d& a, const Vec3d& b) {
  // eq. (7): C*(u) = ep(u) + E*(u), control point by control point.
  ProfileCurve c;
  c.kind = ProfileCurve::Kind::kBezier;
  const std::size_t n = e.offsets.empty() ? 0 : e.offsets.size() - 1;
  c.points.resize(e.offsets.size());
  for (std::size_t i = 0; i < e.offsets.size(); ++i)
    c.points[i] = e.offsets[i] + (n ? lerp(a, b, double(i) / double(n)) : a);
  return c;
}

// ------------------------------------------------------------ point lists

ProfileCurve PointListProfile::curve() const {
  ProfileCurve c;
  c.kind = ProfileCurve::Kind::kPolyline;
  c.points.reserve(points.size() + 2);
  c.u.reserve(points.size() + 2);
  c.points.push_back(a);
  c.u.push_back(0.0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    c.points.push_back(points[i]);
    c.u.push_back(u[i]);
  }
  c.points.push_back(b);
  c.u.push_back(1.0);
  return c;
}

ProfileCurve shift_point_list(const PointListProfile& p, const Vec3d& a_new, const Vec3d& b_new, ShiftMode mode) {
  const Vec3d d = p.b - p.a, d_new = b_new - a_new;
  const double len = d.norm(), len_new = d_new.norm();
  const bool degenerate = !(len > 0);
  // eq. (3): p*(Q) = |a*b*|/|ab| {Q - a - u(b - a)} + a* + u(b* - a*).
  const double scale = degenerate ? 1.0 : len_new / len;
  Mat3d rot = Mat3d::Identity();
  if (mode == ShiftMode::kScaleRotate && !degenerate && len_new > 0)
    rot = Eigen::Quaterniond::FromTwoVectors(d, d_new).toRotationMatrix();
  const Mat3d lin = scale * rot;
  ProfileCurve c;
  c.kind = ProfileCurve::Kind::kPolyline;
  c.points.reserve(p.points.size() + 2);
  c.u.reserve(p.points.size() + 2);
  c.points.push_back(a_new);
  c.u.push_back(0.0);
  for (std::size_t i = 0; i < p.points.size(); ++i) {
    const double ui = p.u[i];
    const Vec3d off = p.points[i] - p.a - ui * d;
    c.points.push_back(lin * off + a_new + ui * d_new);
    c.u.push_back(ui);
  }
  c.points.push_back(b_new);
  c.u.push_back(1.0);
  return c;
}

std::size_t clear_point_list(Model& m, EdgeIdx e) {
  std::size_t removed = 0;
  for (std::uint32_t i = 0; i < m.attrib_nodes.slots.capacity(); ++i) {
    if (!is_profile_node(m, i) || edge_of(HalfedgeIdx{m.attrib_nodes.element[i]}) != e) continue;
    m.delete_attrib_node(AttribNodeIdx{i});
    ++removed;
  }
  return removed;
}

Status attach_point_list(Model& m, SurfaceIdx s, HalfedgeIdx h, std::span<const double> u, std::span<const Vec3d> pts) {
  if (!h.valid() || h.value >= m.halfedges.tail.size() || !m.alive(h))
    return {ErrorCode::kStaleHandle, "attach_point_list: halfedge " + std::to_string(h.value) + " is dead"};
  if (m.surface_of(edge_of(h)) != s)
    return {ErrorCode::kInvalidArgument,
            "attach_point_list: halfedge " + std::to_string(h.value) + " is not in surface " + std::to_string(s.value)};
  if (u.size() != pts.size())
    return {ErrorCode::kMismatch, "attach_point_list: " + std::to_string(u.size()) + " parameters for " +
                                      std::to_string(pts.size()) + " points"};
  for (std::size_t i = 0; i < u.size(); ++i) {
    if (!(u[i] >= 0.0 && u[i] <= 1.0))
      return {ErrorCode::kInvalidArgument,
              "attach_point_list: parameter " + std::to_string(i) + " = " + std::to_string(u[i]) + " outside [0,1]"};
    if (!is_finite(pts[i]))
      return {ErrorCode::kDegenerate, "attach_point_list: point " + std::to_string(i) + " is not finite"};
  }
  (void)clear_point_list(m, edge_of(h));
  for (std::size_t i = 0; i < u.size(); ++i)
    (void)m.new_attrib_node(s, AttribNodeKind::kEdge, h.value, Vec3d(u[i], 0, 0), pts[i]);
  return {};
}

namespace {

/// Sorts (u, point) pairs by u, then by attribute index (stable, deterministic).
void sort_profile(PointListProfile& p, std::vector<std::uint32_t>& order_key) {
  std::vector<std::size_t> idx(p.u.size());
  std::iota(idx.begin(), idx.end(), std::size_t{0});
  std::sort(idx.begin(), idx.end(), [&](std::size_t x, std::size_t y) {
    return p.u[x] != p.u[y] ? p.u[x] < p.u[y] : order_key[x] < order_key[y];
  });
  PointListProfile q;
  q.a = p.a;
  q.b = p.b;
  for (std::size_t i : idx) {
    q.u.push_back(p.u[i]);
    q.points.push_back(p.points[i]);
  }
  p = std::move(q);
}

}  // namespace

PointListProfile read_point_list(const Model& m, HalfedgeIdx h) {
  PointListProfile p;
  p.a = m.position(m.tail(h));
  p.b = m.position(m.head(h));
  std::vector<std::uint32_t> key;
  const auto& an = m.attrib_nodes;
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i) {
    if (!is_profile_node(m, i)) continue;
    const HalfedgeIdx g{an.element[i]};
    if (edge_of(g) != edge_of(h)) continue;
    const double ui = an.param[i].x();
    p.u.push_back(g == h ? ui : 1.0 - ui);
    p.points.push_back(an.position[i]);
    key.push_back(i);
  }
  sort_profile(p, key);
  return p;
}

std::vector<EdgePointList> read_all_point_lists(const Model& m) {
  const auto& an = m.attrib_nodes;
  std::vector<std::uint32_t> ids;
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
    if (is_profile_node(m, i)) ids.push_back(i);
  std::stable_sort(ids.begin(), ids.end(), [&](std::uint32_t x, std::uint32_t y) {
    return edge_of(HalfedgeIdx{an.element[x]}) < edge_of(HalfedgeIdx{an.element[y]});
  });
  std::vector<EdgePointList> out;
  for (std::size_t k = 0; k < ids.size();) {
    const EdgeIdx e = edge_of(HalfedgeIdx{an.element[ids[k]]});
    const HalfedgeIdx h0 = halfedge_of(e, 0);
    EdgePointList l{e, {}};
    l.profile.a = m.position(m.tail(h0));
    l.profile.b = m.position(m.head(h0));
    std::vector<std::uint32_t> key;
    for (; k < ids.size() && edge_of(HalfedgeIdx{an.element[ids[k]]}) == e; ++k) {
      const std::uint32_t i = ids[k];
      const double ui = an.param[i].x();
      l.profile.u.push_back(HalfedgeIdx{an.element[i]} == h0 ? ui : 1.0 - ui);
      l.profile.points.push_back(an.position[i]);
      key.push_back(i);
    }
    sort_profile(l.profile, key);
    out.push_back(std::move(l));
  }
  return out;
}

}  // namespace atelier
