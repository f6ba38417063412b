// Profile curves: Bezier evaluation/splitting against the curve itself,
// seed 001 eqs. (6)-(7) against their analytic consequences, seed 000 eq. (3)
// against the formula written out here, and strokes (seed 000 4.1.4) drawn as
// the camera projection of known 3D curves in known planes.
#include <atelier/systems/profile/profile_curve.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <atelier/storage/builder.h>
#include "support/shapes.h"
#include <atelier/storage/validate.h>

using namespace atelier;

namespace {


std::vector<Vec3d> random_points(std::mt19937& rng, std::size_t n, double scale = 1.0) {
  std::uniform_real_distribution<double> d(-scale, scale);
  std::vector<Vec3d> p(n);
  for (auto& q : p) q = Vec3d(d(rng), d(rng), d(rng));
  return p;
}

// Bernstein form, written independently of de Casteljau.
Vec3d bernstein(const std::vector<Vec3d>& P, double t) {
  const int n = int(P.size()) - 1;
  Vec3d c = Vec3d::Zero();
  for (int i = 0; i <= n; ++i) {
    double binom = 1;
    for (int k = 1; k <= i; ++k) binom = binom * (n - k + 1) / k;
    c += binom * std::pow(t, i) * std::pow(1 - t, n - i) * P[i];
  }
  return c;
}

Mat3d rotation(const Vec3d& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

}  // namespace

// ------------------------------------------------------------------ ProfileCurve

TEST(ProfileCurve, BezierEvalMatchesBernsteinAndHalvesReproduceTheCurve) {
  std::mt19937 rng(7);
  for (std::size_t npts : {2u, 4u, 5u}) {
    for (int trial = 0; trial < 20; ++trial) {
      const ProfileCurve c = ProfileCurve::bezier(random_points(rng, npts));
      const auto [l, r] = c.split_half();
      ASSERT_EQ(l.points.size(), npts);
      ASSERT_EQ(r.points.size(), npts);
      EXPECT_TRUE(l.end() == r.start());
      EXPECT_TRUE(l.end() == c.eval(0.5));
      EXPECT_TRUE(l.start() == c.start());
      EXPECT_TRUE(r.end() == c.end());
      for (int k = 0; k <= 50; ++k) {
        const double t = k / 50.0;
        EXPECT_LT((c.eval(t) - bernstein(c.points, t)).norm(), 1e-13);
        EXPECT_LT((l.eval(t) - c.eval(t / 2)).norm(), 1e-13) << "n=" << npts << " t=" << t;
        EXPECT_LT((r.eval(t) - c.eval(0.5 + t / 2)).norm(), 1e-13) << "n=" << npts << " t=" << t;
        EXPECT_LT((c.reversed().eval(t) - c.eval(1 - t)).norm(), 1e-13);
      }
    }
  }
}

TEST(ProfileCurve, PolylineChordLengthEvalSplitAndReverse) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const auto pts = random_points(rng, 3 + trial % 6);
    const ProfileCurve c = ProfileCurve::polyline(pts);
    ASSERT_TRUE(c.check());
    // Chord-length parameters: u_i = arc length to point i / total.
    double total = 0;
    for (std::size_t i = 1; i < pts.size(); ++i) total += (pts[i] - pts[i - 1]).norm();
    double acc = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (i) acc += (pts[i] - pts[i - 1]).norm();
      EXPECT_NEAR(c.u[i], acc / total, 1e-14);
      EXPECT_LT((c.eval(c.u[i]) - pts[i]).norm(), 1e-14);
    }
    // Unit-speed in arc length: eval(t) lies at arc length t * total.
    for (int k = 0; k <= 40; ++k) {
      const double t = k / 40.0, s = t * total;
      double run = 0;
      Vec3d expect = pts.back();
      for (std::size_t i = 1; i < pts.size(); ++i) {
        const double l = (pts[i] - pts[i - 1]).norm();
        if (run + l >= s) {
          expect = pts[i - 1] + (s - run) / l * (pts[i] - pts[i - 1]);
          break;
        }
        run += l;
      }
      EXPECT_LT((c.eval(t) - expect).norm(), 1e-12);
    }
    const auto [l, r] = c.split_half();
    ASSERT_TRUE(l.check());
    ASSERT_TRUE(r.check());
    EXPECT_TRUE(l.end() == r.start());
    EXPECT_TRUE(l.end() == c.eval(0.5));
    const ProfileCurve rev = c.reversed();
    ASSERT_TRUE(rev.check());
    for (int k = 0; k <= 64; ++k) {
      const double t = k / 64.0;
      EXPECT_LT((l.eval(t) - c.eval(t / 2)).norm(), 1e-13);
      EXPECT_LT((r.eval(t) - c.eval(0.5 + t / 2)).norm(), 1e-13);
      EXPECT_LT((rev.eval(t) - c.eval(1 - t)).norm(), 1e-13);
    }
  }
  // A point already at u = 1/2 is reused, not duplicated.
  const std::vector<Vec3d> sym{Vec3d(0, 0, 0), Vec3d(1, 1, 0), Vec3d(2, 0, 0)};
  const ProfileCurve c = ProfileCurve::polyline(sym);
  ASSERT_EQ(c.u[1], 0.5);
  const auto [l, r] = c.split_half();
  EXPECT_EQ(l.points.size(), 2u);
  EXPECT_EQ(r.points.size(), 2u);
  EXPECT_TRUE(l.end() == sym[1]);
}

TEST(ProfileCurve, DistanceAgreesWithDenseSamplingAndWithKnownFootPoints) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(0, 1);
  for (std::size_t npts : {4u, 5u}) {
    for (int trial = 0; trial < 10; ++trial) {
      const ProfileCurve c = ProfileCurve::bezier(random_points(rng, npts));
      const ProfileCurve poly = [&] {
        std::vector<Vec3d> s;
        for (int k = 0; k <= 7; ++k) s.push_back(c.eval(k / 7.0));
        return ProfileCurve::polyline(s);
      }();
      // Brute force: 2e4 samples bound the distance from above, and from
      // below by the sampling step times the speed.
      constexpr int kN = 20000;
      double speed = 0;
      for (std::size_t i = 0; i + 1 < c.points.size(); ++i)
        speed = std::max(speed, double(npts - 1) * (c.points[i + 1] - c.points[i]).norm());
      for (const Vec3d& p : random_points(rng, 10, 1.5)) {
        double brute = 1e300;
        for (int k = 0; k <= kN; ++k) brute = std::min(brute, (c.eval(double(k) / kN) - p).norm());
        const double d = c.distance(p);
        EXPECT_LE(d, brute + 1e-12);
        EXPECT_GE(d, brute - speed / kN);
        // Polyline: exact point-to-segment distances against dense sampling of each segment.
        double pbrute = 1e300;
        for (std::size_t i = 0; i + 1 < poly.points.size(); ++i)
          for (int k = 0; k <= 2000; ++k)
            pbrute =
                std::min(pbrute, (poly.points[i] + (k / 2000.0) * (poly.points[i + 1] - poly.points[i]) - p).norm());
        EXPECT_LE(poly.distance(p), pbrute + 1e-12);
        EXPECT_GE(poly.distance(p), pbrute - 1e-3);
      }
      // A point at a known small offset s along the normal at C(t0): its
      // distance is s (the foot point is C(t0) while s is below the curvature radius).
      for (int k = 0; k < 5; ++k) {
        const double t0 = 0.1 + 0.8 * uni(rng);
        const Vec3d c0 = c.eval(t0);
        const Vec3d tan = (c.eval(t0 + 1e-6) - c.eval(t0 - 1e-6)).normalized();
        Vec3d n = tan.cross(Vec3d(uni(rng), uni(rng), uni(rng))).normalized();
        const double s = 1e-4;
        const double d = c.distance(c0 + s * n);
        EXPECT_NEAR(d, s, 1e-9 * s + 1e-15) << "t0=" << t0;
      }
    }
  }
}

// ------------------------------------------------------------ seed 001 eqs. (6)-(7)

TEST(ProfileBezier, EncodeDecodeRoundTripTranslationAndStretch) {
  std::mt19937 rng(21);
  for (std::size_t npts : {2u, 4u, 5u}) {
    for (int trial = 0; trial < 10; ++trial) {
      const ProfileCurve c = ProfileCurve::bezier(random_points(rng, npts));
      const auto enc = encode_bezier_profile(c);
      ASSERT_TRUE(enc) << enc.status().to_string();
      ASSERT_EQ(enc->offsets.size(), npts);
      // ep vanishes at the edge's ends (eq. 6 with C(0) = a, C(1) = b).
      EXPECT_LT(enc->offsets.front().norm(), 1e-15);
      EXPECT_LT(enc->offsets.back().norm(), 1e-15);
      // ep(u) = C(u) - E(u) pointwise.
      const ProfileCurve ep = ProfileCurve::bezier(enc->offsets);
      for (int k = 0; k <= 20; ++k) {
        const double u = k / 20.0;
        EXPECT_LT((ep.eval(u) - (c.eval(u) - ((1 - u) * c.start() + u * c.end()))).norm(), 1e-13);
      }
      // Same ends: same control points.
      const ProfileCurve same = decode_bezier_profile(*enc, c.start(), c.end());
      for (std::size_t i = 0; i < npts; ++i) EXPECT_LT((same.points[i] - c.points[i]).norm(), 1e-14);
      // Translated ends: the curve translates; its encoding is unchanged.
      const Vec3d t(0.3, -1.2, 2.5);
      const ProfileCurve moved = decode_bezier_profile(*enc, c.start() + t, c.end() + t);
      for (int k = 0; k <= 20; ++k) EXPECT_LT((moved.eval(k / 20.0) - (c.eval(k / 20.0) + t)).norm(), 1e-13);
      std::vector<Vec3d> shifted = c.points;
      for (auto& p : shifted) p += t;
      const auto enc2 = encode_bezier_profile(ProfileCurve::bezier(shifted));
      ASSERT_TRUE(enc2);
      for (std::size_t i = 0; i < npts; ++i) EXPECT_LT((enc2->offsets[i] - enc->offsets[i]).norm(), 1e-13);
      // Stretched edge b* = a + 2 (b - a): E*(u) - E(u) = u (b - a), so C*(u) = C(u) + u (b - a).
      const Vec3d a = c.start(), b = c.end();
      const ProfileCurve str = decode_bezier_profile(*enc, a, a + 2.0 * (b - a));
      EXPECT_LT((str.start() - a).norm(), 1e-14);
      EXPECT_LT((str.end() - (a + 2.0 * (b - a))).norm(), 1e-14);
      for (int k = 0; k <= 20; ++k) {
        const double u = k / 20.0;
        EXPECT_LT((str.eval(u) - (c.eval(u) + u * (b - a))).norm(), 1e-13);
      }
    }
  }
  // Polylines are not eq. (6) material.
  const std::vector<Vec3d> pts{Vec3d(0, 0, 0), Vec3d(1, 0, 0)};
  EXPECT_EQ(encode_bezier_profile(ProfileCurve::polyline(pts)).status().code(), ErrorCode::kInvalidArgument);
  // Explicit edge ends that differ from the curve's: the end offsets carry the difference.
  const ProfileCurve c =
      ProfileCurve::bezier(std::vector<Vec3d>{Vec3d(0, 0, 0), Vec3d(1, 1, 0), Vec3d(2, 1, 0), Vec3d(3, 0, 0)});
  const auto e = encode_bezier_profile(c, Vec3d(0, 0, 1), Vec3d(3, 0, 1));
  ASSERT_TRUE(e);
  EXPECT_LT((e->offsets.front() - Vec3d(0, 0, -1)).norm(), 1e-15);
  EXPECT_LT((decode_bezier_profile(*e, Vec3d(0, 0, 1), Vec3d(3, 0, 1)).eval(0.3) - c.eval(0.3)).norm(), 1e-14);
}

// ------------------------------------------------------------ seed 000 eq. (3)

namespace {

PointListProfile random_point_list(std::mt19937& rng, std::size_t n) {
  PointListProfile p;
  p.a = Vec3d(0.1, -0.2, 0.3);
  p.b = Vec3d(1.1, 0.4, -0.2);
  std::uniform_real_distribution<double> uni(0.02, 0.98);
  for (std::size_t i = 0; i < n; ++i) p.u.push_back(uni(rng));
  std::sort(p.u.begin(), p.u.end());
  for (double u : p.u)
    p.points.push_back((1 - u) * p.a + u * p.b + 0.3 * Vec3d(std::sin(7 * u), std::cos(5 * u), u * u));
  return p;
}

}  // namespace

TEST(ProfileShift, ScaleModeIsEquationThree) {
  std::mt19937 rng(5);
  const PointListProfile p = random_point_list(rng, 9);
  for (const auto& ends :
       {std::pair{Vec3d(0.5, 0.5, 0.5), Vec3d(2.0, -1.0, 0.7)}, std::pair{Vec3d(-1, 0, 0), Vec3d(-1.2, 0.1, 0.05)}}) {
    const auto& [an, bn] = ends;
    const ProfileCurve c = shift_point_list(p, an, bn, ShiftMode::kScale);
    ASSERT_TRUE(c.check());
    ASSERT_EQ(c.points.size(), p.points.size() + 2);
    EXPECT_TRUE(c.start() == an);
    EXPECT_TRUE(c.end() == bn);
    // eq. (3): p*(Q_i) = |v*_i v*_m| / |v_i v_m| {p(Q_i) - p(v_i) - u_i [p(v_m) - p(v_i)]} + p(v*_i) + u_i (p(v*_m) -
    // p(v*_i)).
    const double ratio = (bn - an).norm() / (p.b - p.a).norm();
    for (std::size_t i = 0; i < p.points.size(); ++i) {
      const double ui = p.u[i];
      const Vec3d expect = ratio * (p.points[i] - p.a - ui * (p.b - p.a)) + an + ui * (bn - an);
      EXPECT_LT((c.points[i + 1] - expect).norm(), 1e-14);
      EXPECT_EQ(c.u[i + 1], ui);
    }
  }
}

TEST(ProfileShift, SameEndsKeepThePointsAndRigidMotionsMoveThemRigidly) {
  std::mt19937 rng(9);
  const PointListProfile p = random_point_list(rng, 7);
  for (ShiftMode mode : {ShiftMode::kScale, ShiftMode::kScaleRotate}) {
    const ProfileCurve same = shift_point_list(p, p.a, p.b, mode);
    for (std::size_t i = 0; i < p.points.size(); ++i) EXPECT_LT((same.points[i + 1] - p.points[i]).norm(), 1e-14);
    const ProfileCurve orig = p.curve();
    for (std::size_t i = 0; i < orig.points.size(); ++i) EXPECT_LT((same.points[i] - orig.points[i]).norm(), 1e-14);
  }
  const Vec3d d = p.b - p.a, t(0.4, 1.5, -0.7);
  std::uniform_real_distribution<double> uni(-1, 1);
  for (int trial = 0; trial < 10; ++trial) {
    // A rotation whose axis is perpendicular to the edge is the minimal one
    // taking d to R d, so kScaleRotate reproduces it exactly.
    const Vec3d axis = d.cross(Vec3d(uni(rng), uni(rng), uni(rng)));
    const Mat3d R = rotation(axis, 0.3 + 2.0 * std::abs(uni(rng)));
    const ProfileCurve c = shift_point_list(p, R * p.a + t, R * p.b + t, ShiftMode::kScaleRotate);
    for (std::size_t i = 0; i < p.points.size(); ++i)
      EXPECT_LT((c.points[i + 1] - (R * p.points[i] + t)).norm(), 1e-13);
    // kScale keeps the offsets' orientation: it differs from the rigid motion.
    const ProfileCurve s = shift_point_list(p, R * p.a + t, R * p.b + t, ShiftMode::kScale);
    double worst = 0;
    for (std::size_t i = 0; i < p.points.size(); ++i)
      worst = std::max(worst, (s.points[i + 1] - (R * p.points[i] + t)).norm());
    EXPECT_GT(worst, 1e-3);
    // Any rigid motion (a twist about the edge cannot be seen from its ends):
    // the shifted profile is congruent to the original.
    const Mat3d G = rotation(Vec3d(uni(rng), uni(rng), uni(rng)), 3.0 * uni(rng));
    const ProfileCurve g = shift_point_list(p, G * p.a + t, G * p.b + t, ShiftMode::kScaleRotate);
    const ProfileCurve o = p.curve();
    for (std::size_t i = 0; i < o.points.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        EXPECT_NEAR((g.points[i] - g.points[j]).norm(), (o.points[i] - o.points[j]).norm(), 1e-13);
  }
  // Scaling the edge about a: offsets scale with it, in both modes.
  const ProfileCurve big = shift_point_list(p, p.a, p.a + 3.0 * d, ShiftMode::kScaleRotate);
  for (std::size_t i = 0; i < p.points.size(); ++i)
    EXPECT_LT((big.points[i + 1] - (p.a + 3.0 * (p.points[i] - p.a))).norm(), 1e-13);
}

// ------------------------------------------------------- ATTRIB_EDGENODE storage

namespace {

/// A 2 x 2 grid of quads in the z = 0 plane (nodes 0..8, row-major).
struct Grid {
  Model m;
  SurfaceIdx s;
};
Grid grid() {
  shapes::Soup soup;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) soup.p.emplace_back(i, j, 0);
  for (std::uint32_t j = 0; j < 2; ++j)
    for (std::uint32_t i = 0; i < 2; ++i) soup.face({3 * j + i, 3 * j + i + 1, 3 * j + i + 4, 3 * j + i + 3});
  Grid g;
  g.s = add_polygon_surface(g.m, "grid", soup.arrays()).value().idx;
  return g;
}

}  // namespace

TEST(ProfileAttach, RoundTripThroughAttribEdgeNodes) {
  Grid g = grid();
  Model& m = g.m;
  const HalfedgeIdx h = m.find_halfedge(NodeIdx{4}, NodeIdx{5});
  ASSERT_TRUE(h.valid());
  // Unsorted input; points off the edge.
  const std::vector<double> u{0.7, 0.2, 0.45};
  const std::vector<Vec3d> pts{Vec3d(1.7, 1.1, 0.3), Vec3d(1.2, 0.9, 0.1), Vec3d(1.45, 1.0, 0.2)};
  ASSERT_TRUE(attach_point_list(m, g.s, h, u, pts));
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_EQ(m.num_attrib_nodes(), 3u);

  const PointListProfile p = read_point_list(m, h);
  EXPECT_TRUE(p.a == m.position(NodeIdx{4}));
  EXPECT_TRUE(p.b == m.position(NodeIdx{5}));
  ASSERT_EQ(p.u.size(), 3u);
  const std::vector<std::size_t> order{1, 2, 0};
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(p.u[k], u[order[k]]);
    EXPECT_TRUE(p.points[k] == pts[order[k]]);
  }
  // From the twin: reversed order, u -> 1 - u, ends swapped.
  const PointListProfile q = read_point_list(m, twin(h));
  EXPECT_TRUE(q.a == p.b && q.b == p.a);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(q.u[k], 1.0 - p.u[2 - k]);
    EXPECT_TRUE(q.points[k] == p.points[2 - k]);
  }
  // Attaching from the twin replaces the list.
  const std::vector<double> u2{0.5};
  const std::vector<Vec3d> pts2{Vec3d(1.5, 1.0, -0.4)};
  ASSERT_TRUE(attach_point_list(m, g.s, twin(h), u2, pts2));
  ASSERT_TRUE(validate(m));
  EXPECT_EQ(m.num_attrib_nodes(), 1u);
  EXPECT_EQ(read_point_list(m, h).points.size(), 1u);
  // A feature-curve node (owned by an ATTRIB_EDGE) on the same edge is neither read nor cleared.
  const AttribNodeIdx fa = m.new_attrib_node(g.s, AttribNodeKind::kEdge, h.value, Vec3d(0.3, 0, 0), Vec3d::Zero());
  (void)m.new_attrib_edge(g.s, 1, std::vector<AttribNodeIdx>{fa});
  ASSERT_TRUE(validate(m));
  EXPECT_EQ(read_point_list(m, h).points.size(), 1u);
  // Another edge, then the bulk reader.
  const HalfedgeIdx h2 = m.find_halfedge(NodeIdx{1}, NodeIdx{4});
  const std::vector<double> u3{0.25, 0.75};
  const std::vector<Vec3d> pts3{Vec3d(1, 0.25, 0.1), Vec3d(1, 0.75, 0.1)};
  ASSERT_TRUE(attach_point_list(m, g.s, h2, u3, pts3));
  ASSERT_TRUE(validate(m));
  const auto all = read_all_point_lists(m);
  ASSERT_EQ(all.size(), 2u);
  for (const auto& l : all) {
    const PointListProfile r = read_point_list(m, halfedge_of(l.edge, 0));
    EXPECT_EQ(l.profile.u, r.u);
    EXPECT_EQ(l.profile.points, r.points);
    EXPECT_TRUE(l.profile.a == r.a && l.profile.b == r.b);
  }
  EXPECT_EQ(clear_point_list(m, edge_of(h)), 1u);
  EXPECT_TRUE(m.alive(fa));
  ASSERT_TRUE(validate(m));
  // Refusals.
  const std::vector<double> bad_u{1.5};
  EXPECT_EQ(attach_point_list(m, g.s, h, bad_u, pts2).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(attach_point_list(m, g.s, h, u3, pts2).code(), ErrorCode::kMismatch);
  EXPECT_EQ(attach_point_list(m, SurfaceIdx{g.s.value + 1}, h, u2, pts2).code(), ErrorCode::kInvalidArgument);
}

// ------------------------------------------------------------------ camera

TEST(ProfileCamera, RaysThroughPixelsProjectBackToThem) {
  const Camera persp = Camera::look_at(Vec3d(3, -2, 1.5), Vec3d(0, 0, 0.5), Vec3d(0, 0, 1), 45, 800, 600);
  const Camera ortho = Camera::orthographic(Vec3d(3, -2, 1.5), Vec3d(0, 0, 0.5), Vec3d(0, 0, 1), 1.5, 800, 600);
  for (const Camera* cam : {&persp, &ortho}) {
    const Vec3d c = cam->project(Vec3d(0, 0, 0.5));
    EXPECT_NEAR(c.x(), 400, 1e-9);
    EXPECT_NEAR(c.y(), 300, 1e-9);
    // Up in the world is up on screen (y grows downwards).
    EXPECT_LT(cam->project(Vec3d(0, 0, 1)).y(), 300);
    for (const Vec2d& px : {Vec2d(10, 20), Vec2d(400, 300), Vec2d(790.5, 12.25)}) {
      const auto [o, d] = cam->ray(px);
      EXPECT_NEAR(d.norm(), 1, 1e-14);
      for (double t : {0.5, 2.0, 5.0}) {
        const Vec3d q = cam->project(o + t * d);
        EXPECT_NEAR(q.x(), px.x(), 1e-8);
        EXPECT_NEAR(q.y(), px.y(), 1e-8);
      }
    }
  }
  // Perspective: the ray through the centre starts towards the target from the eye.
  const auto [o, d] = persp.ray(Vec2d(400, 300));
  EXPECT_LT(d.cross((Vec3d(0, 0, 0.5) - Vec3d(3, -2, 1.5)).normalized()).norm(), 1e-12);
  EXPECT_LT((o - Vec3d(3, -2, 1.5)).cross(d).norm(), 1e-12);
}

// ------------------------------------------------------------------ strokes

namespace {

// A piece of a cylinder (radius 1, axis z): rings z = 0, 1, 2 at angles
// k * 15 deg, k = 0..5, quads split into triangles.
constexpr int kCols = 6;
constexpr double kStep = 15.0 * kPi / 180.0;
std::uint32_t cyl_node(int ring, int k) {
  return std::uint32_t(ring * kCols + k);
}

struct Cylinder {
  Model m;
  SurfaceIdx s;
};
Cylinder cylinder() {
  shapes::Soup soup;
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < kCols; ++k) soup.p.emplace_back(std::cos(k * kStep), std::sin(k * kStep), double(j));
  for (int j = 0; j < 2; ++j)
    for (int k = 0; k + 1 < kCols; ++k) {
      soup.face({cyl_node(j, k), cyl_node(j, k + 1), cyl_node(j + 1, k + 1)});
      soup.face({cyl_node(j, k), cyl_node(j + 1, k + 1), cyl_node(j + 1, k)});
    }
  Cylinder c;
  c.s = add_polygon_surface(c.m, "cylinder", soup.arrays()).value().idx;
  return c;
}

// The known 3D curve in the plane z = 1: r(t) = 1 + 0.1 sin(pi (t - phi_1) / step),
// through the ring-1 nodes at phi_1..phi_4 (r = 1 there).
Vec3d ring_curve(double t) {
  const double r = 1.0 + 0.1 * std::sin(kPi * (t - kStep) / kStep);
  return Vec3d(r * std::cos(t), r * std::sin(t), 1.0);
}

Camera cylinder_camera() {
  const double mid = 2.5 * kStep;
  return Camera::look_at(Vec3d(4 * std::cos(mid), 4 * std::sin(mid), 2.5), Vec3d(std::cos(mid), std::sin(mid), 1.0),
                         Vec3d(0, 0, 1), 40, 1024, 1024);
}

}  // namespace

TEST(ProfileStroke, ThreeEdgesOfACylinderRingTakeTheCurveInTheirPlane) {
  Cylinder cyl = cylinder();
  Model& m = cyl.m;
  const Camera cam = cylinder_camera();
  constexpr int kN = 60;  // samples; the nodes sit at i = 0, 20, 40, 60
  std::vector<double> ts;
  std::vector<Vec2d> stroke;
  for (int i = 0; i <= kN; ++i) {
    ts.push_back(kStep + 3 * kStep * i / kN);
    stroke.push_back(cam.project(ring_curve(ts.back())).head<2>());
  }
  // Exactly the three ring edges.
  const std::vector<EdgeIdx> sel = select_edges_by_stroke(m, {}, cam, stroke, 4.0);
  std::vector<EdgeIdx> expect;
  for (int k = 1; k <= 3; ++k)
    expect.push_back(edge_of(m.find_halfedge(NodeIdx{cyl_node(1, k)}, NodeIdx{cyl_node(1, k + 1)})));
  std::sort(expect.begin(), expect.end());
  EXPECT_EQ(sel, expect);

  const auto sp = profiles_from_stroke(m, {}, cam, stroke, 4.0);
  ASSERT_TRUE(sp) << sp.status().to_string();
  // The least-squares plane of the four ring nodes is z = 1, facing the camera (up here).
  EXPECT_NEAR(sp->plane_normal.z(), 1.0, 1e-12);
  EXPECT_NEAR(sp->plane_point.z(), 1.0, 1e-12);
  ASSERT_EQ(sp->stroke_points.size(), stroke.size());
  for (std::size_t i = 0; i < ts.size(); ++i) EXPECT_LT((sp->stroke_points[i] - ring_curve(ts[i])).norm(), 1e-9);

  ASSERT_EQ(sp->edges.size(), 3u);
  for (std::size_t e = 0; e < 3; ++e) {
    const HalfedgeIdx h = sp->edges[e];
    // Runs with the stroke: from ring node k to k + 1.
    const int k = int(m.tail(h).value) - kCols;
    ASSERT_GE(k, 1);
    ASSERT_LE(k, 3);
    EXPECT_EQ(m.head(h).value, cyl_node(1, k + 1));
    const PointListProfile& p = sp->profiles[e];
    EXPECT_TRUE(p.a == m.position(m.tail(h)));
    EXPECT_TRUE(p.b == m.position(m.head(h)));
    // Cut at the nodes: the samples strictly inside (phi_k, phi_{k+1}), in order, on the curve.
    std::vector<double> inside;
    for (double t : ts)
      if (t > k * kStep + 1e-9 && t < (k + 1) * kStep - 1e-9) inside.push_back(t);
    ASSERT_EQ(p.points.size(), inside.size()) << "edge from ring node " << k;
    for (std::size_t i = 0; i < inside.size(); ++i) EXPECT_LT((p.points[i] - ring_curve(inside[i])).norm(), 1e-9);
    // u by chord length along a, Q_1..Q_n, b.
    std::vector<Vec3d> chain{p.a};
    chain.insert(chain.end(), p.points.begin(), p.points.end());
    chain.push_back(p.b);
    double total = 0;
    for (std::size_t i = 1; i < chain.size(); ++i) total += (chain[i] - chain[i - 1]).norm();
    double acc = 0;
    for (std::size_t i = 0; i < p.points.size(); ++i) {
      acc += (chain[i + 1] - chain[i]).norm();
      EXPECT_NEAR(p.u[i], acc / total, 1e-12);
    }
  }

  // Attached, read back, valid.
  ASSERT_TRUE(attach_stroke_profiles(m, *sp));
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  for (std::size_t e = 0; e < 3; ++e) {
    const PointListProfile r = read_point_list(m, sp->edges[e]);
    EXPECT_EQ(r.u, sp->profiles[e].u);
    EXPECT_EQ(r.points, sp->profiles[e].points);
  }

  // The reversed stroke gives the twins and the reversed lists.
  std::vector<Vec2d> back(stroke.rbegin(), stroke.rend());
  const auto rp = profiles_from_stroke(m, {}, cam, back, 4.0);
  ASSERT_TRUE(rp);
  ASSERT_EQ(rp->edges.size(), 3u);
  for (std::size_t e = 0; e < 3; ++e) {
    EXPECT_EQ(rp->edges[e], twin(sp->edges[e]));
    const auto& f = sp->profiles[e];
    const auto& r = rp->profiles[e];
    ASSERT_EQ(r.points.size(), f.points.size());
    for (std::size_t i = 0; i < f.points.size(); ++i) {
      EXPECT_LT((r.points[i] - f.points[f.points.size() - 1 - i]).norm(), 1e-9);
      EXPECT_NEAR(r.u[i], 1.0 - f.u[f.points.size() - 1 - i], 1e-12);
    }
  }
}

TEST(ProfileStroke, PixelRoundedStrokeStaysNearTheCurveAndVisibilityFilters) {
  Cylinder cyl = cylinder();
  const Camera cam = cylinder_camera();
  std::vector<Vec2d> stroke;
  for (int i = 0; i <= 120; ++i) {
    const Vec3d q = cam.project(ring_curve(kStep + 3 * kStep * i / 120));
    stroke.emplace_back(std::round(q.x()), std::round(q.y()));
  }
  const auto sp = profiles_from_stroke(cyl.m, {}, cam, stroke, 4.0);
  ASSERT_TRUE(sp) << sp.status().to_string();
  ASSERT_EQ(sp->edges.size(), 3u);
  // Half a pixel is about 1.2 mm here; the points stay within a few of them of
  // the curve (measured in its plane: radial deviation from r(t)).
  for (const auto& p : sp->profiles)
    for (const Vec3d& q : p.points) {
      const double t = std::atan2(q.y(), q.x());
      EXPECT_LT((q - ring_curve(t)).norm(), 5e-3);
    }
  // A slow stroke repeats pixels: the attached lists do not.
  std::vector<Vec2d> slow;
  for (const Vec2d& px : stroke) slow.insert(slow.end(), {px, px});
  const auto sp2 = profiles_from_stroke(cyl.m, {}, cam, slow, 4.0);
  ASSERT_TRUE(sp2);
  ASSERT_EQ(sp2->profiles.size(), sp->profiles.size());
  for (std::size_t e = 0; e < sp->profiles.size(); ++e) {
    EXPECT_EQ(sp2->profiles[e].points, sp->profiles[e].points);
    EXPECT_EQ(sp2->profiles[e].u, sp->profiles[e].u);
  }
  // Only the part with y < sin(3.5 step) is visible: the third edge drops out.
  const double ycut = std::sin(3.5 * kStep);
  const auto vis = [&](const Vec3d& p) { return p.y() < ycut; };
  const auto sel = select_edges_by_stroke(cyl.m, {}, cam, stroke, 4.0, vis);
  EXPECT_EQ(sel.size(), 2u);
  for (EdgeIdx e : sel) EXPECT_LT(cyl.m.position(cyl.m.head(halfedge_of(e, 0))).y(), ycut);
  // A stroke far from every edge selects nothing and is refused.
  const std::vector<Vec2d> away{Vec2d(1, 1), Vec2d(5, 5)};
  EXPECT_FALSE(profiles_from_stroke(cyl.m, {}, cam, away, 4.0));
}

namespace {

// Two triangles sharing the edge A = (0,0,0) -> B = (1,0,0), their apexes at
// angles 0 and theta about the x axis: a dihedral of angle theta.
struct Dihedral {
  Model m;
  EdgeIdx ab;
};
Dihedral dihedral(double theta) {
  shapes::Soup soup;
  soup.p = {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0.5, 1, 0), Vec3d(0.5, std::cos(theta), std::sin(theta))};
  soup.face({0, 1, 2});
  soup.face({1, 0, 3});
  Dihedral d;
  (void)add_polygon_surface(d.m, "dihedral", soup.arrays()).value();
  d.ab = edge_of(d.m.find_halfedge(NodeIdx{0}, NodeIdx{1}));
  return d;
}

}  // namespace

TEST(ProfileStroke, OneEdgeUsesTheDihedralBisectorPlane) {
  for (double deg : {60.0, 100.0, 150.0, 180.0}) {
    const double theta = deg * kPi / 180.0;
    Dihedral d = dihedral(theta);
    // The bisector plane holds the x axis and (0, cos theta/2, sin theta/2).
    const Vec3d bis(0, std::cos(theta / 2), std::sin(theta / 2));
    const Vec3d n_expect(0, -std::sin(theta / 2), std::cos(theta / 2));
    // Bulging away from the faces so no apex projects near the stroke.
    const auto curve = [&](double s) -> Vec3d { return Vec3d(s, 0, 0) - 0.25 * std::sin(kPi * s) * bis; };
    // Looking at the plane from its normal side, slightly off-axis.
    const Vec3d mid(0.5, 0, 0);
    const Camera cam =
        Camera::look_at(mid + 3.0 * n_expect + 0.4 * bis, mid, Vec3d(1, 0, 0).cross(n_expect), 35, 900, 900);
    std::vector<Vec2d> stroke;
    std::vector<double> ss;
    for (int i = 0; i <= 40; ++i) {
      ss.push_back(i / 40.0);
      stroke.push_back(cam.project(curve(ss.back())).head<2>());
    }
    const auto sp = profiles_from_stroke(d.m, {}, cam, stroke, 4.0);
    ASSERT_TRUE(sp) << sp.status().to_string();
    ASSERT_EQ(sp->edges.size(), 1u) << deg;
    EXPECT_EQ(edge_of(sp->edges[0]), d.ab);
    EXPECT_EQ(d.m.tail(sp->edges[0]), NodeIdx{0});
    EXPECT_NEAR(sp->plane_normal.dot(n_expect), 1.0, 1e-12) << deg;
    const auto& p = sp->profiles[0];
    ASSERT_EQ(p.points.size(), 39u);
    for (std::size_t i = 0; i < p.points.size(); ++i) EXPECT_LT((p.points[i] - curve(ss[i + 1])).norm(), 1e-9);
    // Attach and validate.
    ASSERT_TRUE(attach_stroke_profiles(d.m, *sp));
    ASSERT_TRUE(validate(d.m)) << validate(d.m).to_string();
  }
}

TEST(ProfileStroke, BoundaryEdgeUsesThePlaneFacingTheCamera) {
  Dihedral d = dihedral(kPi / 2);
  // Edge A -> apex (0.5, 1, 0) bounds one face only.
  const HalfedgeIdx h = d.m.find_halfedge(NodeIdx{0}, NodeIdx{2});
  ASSERT_TRUE(h.valid());
  ASSERT_TRUE(d.m.is_boundary(edge_of(h)));
  const Vec3d a(0, 0, 0), b(0.5, 1, 0);
  const Camera cam = Camera::look_at(Vec3d(-1.5, 2.0, 2.5), 0.5 * (a + b), Vec3d(0, 0, 1), 40, 800, 800);
  std::vector<Vec2d> stroke;
  for (int i = 0; i <= 20; ++i) {
    const double s = i / 20.0;
    // Any screen curve through the two ends (the plane is defined by the edge and the camera).
    const Vec3d q = cam.project((1 - s) * a + s * b);
    stroke.push_back(q.head<2>() + Vec2d(0, -30.0 * std::sin(kPi * s)));
  }
  const auto sp = profiles_from_stroke(d.m, {}, cam, stroke, 4.0);
  ASSERT_TRUE(sp) << sp.status().to_string();
  ASSERT_EQ(sp->edges.size(), 1u);
  const Vec3d dir = (b - a).normalized();
  const Vec3d view = cam.ray(cam.project(0.5 * (a + b)).head<2>()).second;
  const Vec3d n_expect = -(view - view.dot(dir) * dir).normalized();
  EXPECT_NEAR(sp->plane_normal.dot(n_expect), 1.0, 1e-12);
  // Every stroke point lies on that plane, and back-projects to its pixel.
  for (std::size_t i = 0; i < sp->stroke_points.size(); ++i) {
    EXPECT_NEAR((sp->stroke_points[i] - a).dot(n_expect), 0.0, 1e-12);
    EXPECT_LT((cam.project(sp->stroke_points[i]).head<2>() - stroke[i]).norm(), 1e-8);
  }
  ASSERT_TRUE(attach_stroke_profiles(d.m, *sp));
  ASSERT_TRUE(validate(d.m));
}

namespace {

/// A chain of wire edges through the given points (one surface).
Model wire_chain(const std::vector<Vec3d>& p) {
  Model m;
  const SurfaceIdx s = m.add_surface("wire").idx;
  std::vector<NodeIdx> v;
  for (const Vec3d& q : p) v.push_back(m.new_node(s, q));
  for (std::size_t i = 0; i + 1 < v.size(); ++i) (void)m.new_edge(v[i], v[i + 1]);
  return m;
}

}  // namespace

TEST(ProfileStroke, NonCoplanarEdgesUseTheirLeastSquaresPlane) {
  const std::vector<Vec3d> nodes{Vec3d(0, 0, 0), Vec3d(1, 0, 0.1), Vec3d(2, 0.1, -0.05), Vec3d(3, 0, 0.08)};
  Model m = wire_chain(nodes);
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  const Camera cam = Camera::look_at(Vec3d(1.5, -1, 4), Vec3d(1.5, 0, 0), Vec3d(0, 1, 0), 50, 1000, 800);
  constexpr int kPer = 10;  // stroke samples per edge, 9 strictly inside
  std::vector<Vec2d> stroke;
  for (std::size_t e = 0; e + 1 < nodes.size(); ++e)
    for (int k = (e == 0 ? 0 : 1); k <= kPer; ++k) {
      const double t = double(k) / kPer;
      // Off the chord by a screen-visible bump so the stroke is not the edges themselves.
      const Vec3d q = (1 - t) * nodes[e] + t * nodes[e + 1] + Vec3d(0, 0.2 * std::sin(kPi * t), 0);
      stroke.push_back(cam.project(q).head<2>());
    }
  const auto sp = profiles_from_stroke(m, {}, cam, stroke, 3.0);
  ASSERT_TRUE(sp) << sp.status().to_string();
  ASSERT_EQ(sp->edges.size(), 3u);
  // The plane minimising the squared distances of the four nodes: through
  // their centroid, normal = the smallest right singular vector (SVD, not the
  // eigen-solver the implementation uses).
  Vec3d c = Vec3d::Zero();
  for (const Vec3d& q : nodes) c += q;
  c /= 4.0;
  Eigen::Matrix<double, 4, 3> A;
  for (int i = 0; i < 4; ++i) A.row(i) = (nodes[i] - c).transpose();
  const Vec3d n = Eigen::JacobiSVD<Eigen::Matrix<double, 4, 3>>(A, Eigen::ComputeFullV).matrixV().col(2);
  EXPECT_NEAR(std::abs(sp->plane_normal.dot(n)), 1.0, 1e-12);
  EXPECT_LT((sp->plane_point - c).norm(), 1e-15);
  EXPECT_GT(sp->plane_normal.dot(Vec3d(1.5, -1, 4) - c), 0.0);  // faces the camera
  ASSERT_EQ(sp->stroke_points.size(), stroke.size());
  for (std::size_t i = 0; i < stroke.size(); ++i) {
    EXPECT_NEAR((sp->stroke_points[i] - c).dot(n), 0.0, 1e-12);
    EXPECT_LT((cam.project(sp->stroke_points[i]).head<2>() - stroke[i]).norm(), 1e-8);
  }
  // Each edge receives the samples drawn inside it, in order.
  for (std::size_t e = 0; e < 3; ++e) {
    const HalfedgeIdx h = sp->edges[e];
    const std::uint32_t i = m.tail(h).value;
    EXPECT_EQ(m.head(h).value, i + 1);
    ASSERT_EQ(sp->profiles[e].points.size(), std::size_t(kPer - 1));
    const std::size_t first = i == 0 ? 1 : 1 + i * kPer;  // stroke index of the first inner sample
    for (std::size_t k = 0; k + 1 < kPer; ++k) EXPECT_TRUE(sp->profiles[e].points[k] == sp->stroke_points[first + k]);
  }
  ASSERT_TRUE(attach_stroke_profiles(m, *sp));
  ASSERT_TRUE(validate(m));
  EXPECT_EQ(read_all_point_lists(m).size(), 3u);
}

TEST(ProfileStroke, CollinearEdgesUseThePlaneFacingTheCamera) {
  const std::vector<Vec3d> nodes{Vec3d(0, 0, 0), Vec3d(1.25, 0, 0), Vec3d(2.5, 0, 0)};  // at stroke t = 0, 1/2, 1
  Model m = wire_chain(nodes);
  const Vec3d eye(1.0, -2.0, 3.0);
  const Camera cam = Camera::look_at(eye, Vec3d(1.2, 0, 0), Vec3d(0, 0, 1), 45, 800, 800);
  std::vector<Vec2d> stroke;
  for (int k = 0; k <= 30; ++k) {
    const double t = k / 30.0;
    stroke.push_back(cam.project(Vec3d(2.5 * t, 0, 0)).head<2>() + Vec2d(0, 25.0 * std::sin(2 * kPi * t)));
  }
  const auto sp = profiles_from_stroke(m, {}, cam, stroke, 3.0);
  ASSERT_TRUE(sp) << sp.status().to_string();
  ASSERT_EQ(sp->edges.size(), 2u);
  // Any plane through the x axis fits; the one whose normal is nearest the
  // viewing direction at the centroid is chosen.
  const Vec3d centroid(1.25, 0, 0);
  const Vec3d view = cam.ray(cam.project(centroid).head<2>()).second;
  const Vec3d expect = -(view - view.x() * Vec3d::UnitX()).normalized();
  EXPECT_NEAR(sp->plane_normal.dot(expect), 1.0, 1e-12);
  for (const Vec3d& q : sp->stroke_points) EXPECT_NEAR(q.dot(expect), 0.0, 1e-12);
}
