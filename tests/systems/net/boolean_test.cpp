// Net Booleans (seed 004 sections 2-3): volumes against analytic values,
// closed and oriented results, touching and coplanar cases, bad input.
#include <atelier/systems/net/boolean.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "net_shapes.h"

namespace atelier {
namespace {

using net_test::box;
using net_test::box_triangles;
using net_test::closed_model;

BooleanReport run(const PolygonSoup& a, const PolygonSoup& b, BooleanOp op, const ExecContext& ctx = {}) {
  BooleanOptions o;
  o.op = op;
  auto r = net_boolean(a, b, o, ctx);
  EXPECT_TRUE(r.has_value()) << r.status().to_string();
  return r.has_value() ? std::move(*r) : BooleanReport{};
}

TEST(NetBoolean, OverlappingCubes) {
  const auto a = box({0, 0, 0}, {1, 1, 1});
  const auto b = box({.5, .25, -.5}, {1.5, 1.25, .5});
  const struct {
    BooleanOp op;
    double volume;
  } cases[] = {{BooleanOp::kIntersection, 0.1875},
               {BooleanOp::kUnion, 1.8125},
               {BooleanOp::kAMinusB, 0.8125},
               {BooleanOp::kBMinusA, 0.8125}};
  for (const auto& c : cases) {
    const BooleanReport r = run(a, b, c.op);
    EXPECT_NEAR(r.volume, c.volume, 1e-12) << static_cast<int>(c.op);
    EXPECT_TRUE(closed_model(r.result)) << static_cast<int>(c.op);
    EXPECT_EQ(r.intersection_polygons, 1u);
  }
}

TEST(NetBoolean, CoplanarCubes) {
  const auto a = box({0, 0, 0}, {1, 1, 1});
  const auto b = box({.5, 0, 0}, {1.5, 1, 1});
  const struct {
    BooleanOp op;
    double volume;
  } cases[] = {{BooleanOp::kIntersection, 0.5},
               {BooleanOp::kUnion, 1.5},
               {BooleanOp::kAMinusB, 0.5},
               {BooleanOp::kBMinusA, 0.5}};
  for (const auto& c : cases) {
    const BooleanReport r = run(a, b, c.op);
    EXPECT_NEAR(r.volume, c.volume, 1e-12) << static_cast<int>(c.op);
    EXPECT_TRUE(closed_model(r.result)) << static_cast<int>(c.op);
  }
}

}  // namespace
}  // namespace atelier

namespace atelier {
namespace {

double lens(double r, double d) {
  return M_PI * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0;
}

/// Smallest distance from the centre to a face plane: the polyhedron holds
/// the ball of that radius (and lies in the sphere it is inscribed in).
double inradius(const PolygonSoup& s, const Vec3d& c) {
  double r = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const auto v = s.face(f);
    const Vec3d n = (s.positions[v[1]] - s.positions[v[0]]).cross(s.positions[v[2]] - s.positions[v[0]]).normalized();
    for (std::uint32_t x : v) r = std::min(r, std::abs(n.dot(s.positions[x] - c)));
  }
  return r;
}

TEST(NetBoolean, SpheresLensAndInclusionExclusion) {
  const double R = 1.0, d = 0.8;
  // Triangles (icosphere) against quads and fans (UV sphere): n-gons too.
  const PolygonSoup a = net_test::icosphere(3, R, {0, 0, 0});
  const PolygonSoup b = net_test::from_shapes(shapes::uv_sphere(40, 20, R, {d, 0.0123, -0.0071}));
  const double dd = Vec3d(d, 0.0123, -0.0071).norm();
  const BooleanReport in = run(a, b, BooleanOp::kIntersection);
  const BooleanReport un = run(a, b, BooleanOp::kUnion);
  const BooleanReport ab = run(a, b, BooleanOp::kAMinusB);
  const BooleanReport ba = run(a, b, BooleanOp::kBMinusA);
  for (const BooleanReport* r : {&in, &un, &ab, &ba}) {
    EXPECT_TRUE(closed_model(r->result));
    EXPECT_EQ(r->intersection_polygons, 1u);
  }
  const double ra = inradius(a, {0, 0, 0}), rb = inradius(b, {d, 0.0123, -0.0071});
  EXPECT_GE(in.volume, lens(std::min(ra, rb), dd));
  EXPECT_LE(in.volume, lens(R, dd));
  const double sum = in.volume_a + in.volume_b;
  EXPECT_NEAR(un.volume + in.volume, sum, 1e-12 * sum);
  EXPECT_NEAR(ab.volume + in.volume, in.volume_a, 1e-12 * sum);
  EXPECT_NEAR(ba.volume + in.volume, in.volume_b, 1e-12 * sum);
}

TEST(NetBoolean, SameBitsForAnyThreadCount) {
  const PolygonSoup a = net_test::icosphere(3, 1.0, {0, 0, 0});
  const PolygonSoup b = net_test::icosphere(3, 1.0, {0.7, 0.2, 0.1});
  ExecContext one = ExecContext::sequential();
  ExecContext many;
  many.threads = 2;
  many.sequential_threshold = 1;
  many.grain = 7;
  const BooleanReport r1 = run(a, b, BooleanOp::kUnion, one);
  const BooleanReport r2 = run(a, b, BooleanOp::kUnion, many);
  ASSERT_EQ(r1.result.positions.size(), r2.result.positions.size());
  EXPECT_EQ(0, std::memcmp(r1.result.positions.data(), r2.result.positions.data(),
                           r1.result.positions.size() * sizeof(Vec3d)));
  EXPECT_EQ(r1.result.face_nodes, r2.result.face_nodes);
  EXPECT_EQ(r1.result.face_offsets, r2.result.face_offsets);
}

// Above ExecContext::sequential_threshold polygons (10^4) the default
// context runs the parallel paths as they are used in practice (grain and
// threshold untouched): two level-4 icospheres, 10,240 triangles in all.
TEST(NetBoolean, SameBitsForAnyThreadCountAtDefaultSettings) {
  const PolygonSoup a = net_test::icosphere(4, 1.0, {0, 0, 0});
  const PolygonSoup b = net_test::icosphere(4, 1.0, {0.61, 0.23, 0.17});
  ASSERT_GE(a.face_count() + b.face_count(), ExecContext{}.sequential_threshold);
  ExecContext two;
  two.threads = 2;
  const BooleanReport r1 = run(a, b, BooleanOp::kAMinusB, ExecContext::sequential());
  const BooleanReport r2 = run(a, b, BooleanOp::kAMinusB, two);
  ASSERT_EQ(r1.result.positions.size(), r2.result.positions.size());
  EXPECT_EQ(0, std::memcmp(r1.result.positions.data(), r2.result.positions.data(),
                           r1.result.positions.size() * sizeof(Vec3d)));
  EXPECT_EQ(r1.result.face_nodes, r2.result.face_nodes);
  EXPECT_GT(r1.intersection_points, 0u);
}

// Below the sequential threshold the two nets are still prepared side by
// side when the caller allows two threads (each task sequential inside):
// the same bits as one thread in all four operations, and with both nets
// bad the error is still A's, whichever task ends first.
TEST(NetBoolean, SmallPairsPreparedSideBySideGiveTheSequentialBits) {
  const PolygonSoup a = net_test::icosphere(2, 1.0, {0, 0, 0});
  const PolygonSoup b = net_test::icosphere(2, 0.9, {0.43, 0.17, -0.11});
  ASSERT_LT(a.face_count() + b.face_count(), ExecContext{}.sequential_threshold);
  ExecContext two;
  two.threads = 2;
  for (BooleanOp op : {BooleanOp::kUnion, BooleanOp::kIntersection, BooleanOp::kAMinusB, BooleanOp::kBMinusA}) {
    const BooleanReport r1 = run(a, b, op, ExecContext::sequential());
    const BooleanReport r2 = run(a, b, op, two);
    ASSERT_EQ(r1.result.positions.size(), r2.result.positions.size()) << static_cast<int>(op);
    ASSERT_GT(r1.result.positions.size(), 0u);
    EXPECT_EQ(0, std::memcmp(r1.result.positions.data(), r2.result.positions.data(),
                             r1.result.positions.size() * sizeof(Vec3d)));
    EXPECT_EQ(r1.result.face_nodes, r2.result.face_nodes);
    EXPECT_EQ(std::memcmp(&r1.volume, &r2.volume, sizeof(double)), 0);
    EXPECT_TRUE(closed_model(r2.result));
  }
  // A open (a face missing), B crossing itself: A's error every time.
  PolygonSoup open = box({0, 0, 0}, {1, 1, 1});
  open.face_offsets.pop_back();
  open.face_nodes.resize(open.face_offsets.back());
  const PolygonSoup crossing = net_test::two_boxes_in_one_net();
  for (int k = 0; k < 20; ++k) {
    auto r = net_boolean(open, crossing, {}, two);
    ASSERT_FALSE(r.has_value());
    EXPECT_NE(r.status().message().find("net A is open"), std::string::npos) << r.status().message();
  }
}

TEST(NetBoolean, TouchingAndNestedCases) {
  const auto a = box({0, 0, 0}, {1, 1, 1});
  // Face to face from outside: the union is one box, the shared face goes.
  const auto side = box({1, 0, 0}, {2, 1, 1});
  EXPECT_NEAR(run(a, side, BooleanOp::kUnion).volume, 2.0, 1e-12);
  EXPECT_TRUE(closed_model(run(a, side, BooleanOp::kUnion).result));
  EXPECT_EQ(run(a, side, BooleanOp::kIntersection).result.face_count(), 0u);
  EXPECT_NEAR(run(a, side, BooleanOp::kAMinusB).volume, 1.0, 1e-12);
  EXPECT_TRUE(closed_model(run(a, side, BooleanOp::kAMinusB).result));
  // Identical nets.
  EXPECT_NEAR(run(a, a, BooleanOp::kUnion).volume, 1.0, 1e-12);
  EXPECT_NEAR(run(a, a, BooleanOp::kIntersection).volume, 1.0, 1e-12);
  EXPECT_EQ(run(a, a, BooleanOp::kAMinusB).result.face_count(), 0u);
  // Inside, sharing a face (same orientation): a pocket.
  const auto inner = box_triangles({0.25, 0.25, 0}, {0.75, 0.75, 0.5});
  const BooleanReport pocket = run(a, inner, BooleanOp::kAMinusB);
  EXPECT_NEAR(pocket.volume, 1.0 - 0.125, 1e-12);
  EXPECT_TRUE(closed_model(pocket.result));
  EXPECT_NEAR(run(a, inner, BooleanOp::kUnion).volume, 1.0, 1e-12);
  EXPECT_NEAR(run(a, inner, BooleanOp::kIntersection).volume, 0.125, 1e-12);
  // Strictly inside: no intersection polygon, the union is A.
  const auto deep = box({0.25, 0.25, 0.25}, {0.75, 0.75, 0.75});
  const BooleanReport hole = run(a, deep, BooleanOp::kAMinusB);
  EXPECT_EQ(hole.intersection_polygons, 0u);
  EXPECT_NEAR(hole.volume, 1.0 - 0.125, 1e-12);
  EXPECT_NEAR(run(a, deep, BooleanOp::kUnion).volume, 1.0, 1e-12);
  // Disjoint.
  const auto far = box({3, 3, 3}, {4, 4, 4});
  EXPECT_NEAR(run(a, far, BooleanOp::kUnion).volume, 2.0, 1e-12);
  EXPECT_EQ(run(a, far, BooleanOp::kIntersection).result.face_count(), 0u);
  // A vertex of B on a face of A, B reaching inside (a tetrahedron's tip).
  PolygonSoup tet;
  tet.positions = {{0.5, 0.5, 0.5}, {0.2, 0.2, 1.5}, {0.8, 0.2, 1.5}, {0.5, 0.8, 1.5}};
  tet.add_face(std::array<std::uint32_t, 3>{0, 2, 1});
  tet.add_face(std::array<std::uint32_t, 3>{0, 3, 2});
  tet.add_face(std::array<std::uint32_t, 3>{0, 1, 3});
  tet.add_face(std::array<std::uint32_t, 3>{1, 2, 3});
  const BooleanReport tu = run(a, tet, BooleanOp::kUnion), ti = run(a, tet, BooleanOp::kIntersection);
  EXPECT_TRUE(closed_model(tu.result));
  EXPECT_TRUE(closed_model(ti.result));
  EXPECT_NEAR(tu.volume + ti.volume, tu.volume_a + tu.volume_b, 1e-12);
}

TEST(NetBoolean, RefusesBadNets) {
  const auto good = box({0, 0, 0}, {1, 1, 1});
  auto error = [&](const PolygonSoup& bad) {
    auto r = net_boolean(good, bad, {});
    EXPECT_FALSE(r.has_value());
    return r.has_value() ? std::string() : r.status().message();
  };
  // Open: a face missing.
  PolygonSoup open = box({.5, .5, .5}, {2, 2, 2});
  open.face_offsets.pop_back();
  open.face_nodes.resize(open.face_offsets.back());
  EXPECT_NE(error(open).find("open"), std::string::npos);
  // Self-intersecting: two overlapping boxes in one net.
  const PolygonSoup two = net_test::two_boxes_in_one_net();
  const std::string self = error(two);
  EXPECT_NE(self.find("intersects itself: faces"), std::string::npos) << self;
  // Non-manifold: a face used twice.
  PolygonSoup twice = box_triangles({.5, .5, .5}, {2, 2, 2});
  twice.add_face(std::vector<std::uint32_t>(twice.face(0).begin(), twice.face(0).end()));
  EXPECT_NE(error(twice).find("non-manifold"), std::string::npos);
  // Duplicate vertices.
  PolygonSoup dup = box({.5, .5, .5}, {2, 2, 2});
  dup.positions.push_back(dup.positions[0]);
  dup.face_nodes[0] = 8;
  EXPECT_NE(error(dup).find("duplicate"), std::string::npos);
  // Duplicates equal as doubles but not as bits (-0 and +0): the hashed
  // search compares with ==, and the message names both, smaller first.
  PolygonSoup signed_zero = box({0, 0, 0}, {2, 2, 2});
  std::uint32_t origin = 0;
  while (signed_zero.positions[origin] != Vec3d(0, 0, 0)) ++origin;
  signed_zero.positions.push_back(Vec3d(-0.0, 0.0, -0.0));
  for (auto& v : signed_zero.face_nodes)
    if (v == origin) {
      v = 8;
      break;
    }
  const std::string zero = error(signed_zero);
  EXPECT_NE(zero.find("vertex " + std::to_string(origin) + " of face"), std::string::npos) << zero;
  EXPECT_NE(zero.find("vertex 8 of face"), std::string::npos) << zero;
  EXPECT_NE(zero.find("duplicate"), std::string::npos) << zero;
  // Inward.
  PolygonSoup inward = box({.5, .5, .5}, {2, 2, 2});
  for (std::size_t f = 0; f < inward.face_count(); ++f)
    std::reverse(inward.face_nodes.begin() + inward.face_offsets[f],
                 inward.face_nodes.begin() + inward.face_offsets[f + 1]);
  EXPECT_NE(error(inward).find("inwards"), std::string::npos);
  // Not finite, out of range.
  PolygonSoup nan = box({.5, .5, .5}, {2, 2, 2});
  nan.positions[3].x() = std::nan("");
  EXPECT_NE(error(nan).find("not finite"), std::string::npos);
  PolygonSoup range = box({.5, .5, .5}, {2, 2, 2});
  range.face_nodes[5] = 99;
  EXPECT_NE(error(range).find("names vertex 99"), std::string::npos);
}

}  // namespace
}  // namespace atelier

namespace atelier {
namespace {

TEST(NetBoolean, SolidsTouchingAlongAnEdgeStayManifold) {
  const auto a = box({0, 0, 0}, {1, 1, 1});
  const auto b = box_triangles({1, 1, 0}, {2, 2, 1});
  const BooleanReport u = run(a, b, BooleanOp::kUnion);
  EXPECT_NEAR(u.volume, 2.0, 1e-12);
  EXPECT_TRUE(closed_model(u.result));
  EXPECT_EQ(run(a, b, BooleanOp::kIntersection).result.face_count(), 0u);
  const BooleanReport d = run(a, b, BooleanOp::kAMinusB);
  EXPECT_NEAR(d.volume, 1.0, 1e-12);
  EXPECT_TRUE(closed_model(d.result));
  // Touching at one corner only.
  const auto c = box({1, 1, 1}, {2, 2, 2});
  const BooleanReport uc = run(a, c, BooleanOp::kUnion);
  EXPECT_NEAR(uc.volume, 2.0, 1e-12);
  EXPECT_TRUE(closed_model(uc.result));
}

}  // namespace
}  // namespace atelier

namespace atelier {
namespace {

/// Boxes on a coarse grid: faces coplanar, edges collinear, vertices on
/// faces all the time. Volumes against the analytic box intersection.
TEST(NetBoolean, DegenerateGridBoxesAgreeWithAnalyticVolumes) {
  std::uint64_t seed = 12345;
  for (int trial = 0; trial < 60; ++trial) {
    Vec3d lo[2], hi[2];
    net_test::grid_box_pair(seed, lo, hi);
    const PolygonSoup a = trial % 2 ? box(lo[0], hi[0]) : box_triangles(lo[0], hi[0]);
    const PolygonSoup b = trial % 3 ? box_triangles(lo[1], hi[1]) : box(lo[1], hi[1]);
    double inter = 1;
    for (int k = 0; k < 3; ++k) inter *= std::max(0.0, std::min(hi[0][k], hi[1][k]) - std::max(lo[0][k], lo[1][k]));
    const double va = (hi[0] - lo[0]).prod(), vb = (hi[1] - lo[1]).prod();
    const BooleanReport u = run(a, b, BooleanOp::kUnion), i = run(a, b, BooleanOp::kIntersection),
                        d = run(a, b, BooleanOp::kAMinusB), e = run(a, b, BooleanOp::kBMinusA);
    EXPECT_NEAR(u.volume, va + vb - inter, 1e-12) << trial;
    EXPECT_NEAR(i.volume, inter, 1e-12) << trial;
    EXPECT_NEAR(d.volume, va - inter, 1e-12) << trial;
    EXPECT_NEAR(e.volume, vb - inter, 1e-12) << trial;
    for (const BooleanReport* r : {&u, &i, &d, &e})
      if (r->result.face_count()) {
        EXPECT_TRUE(closed_model(r->result)) << trial;
      }
  }
}

/// Spheres sharing vertices (B is A moved by a vertex-to-vertex offset)
/// and spheres touching A's vertices with theirs.
TEST(NetBoolean, SpheresWithSharedVertices) {
  const PolygonSoup a = net_test::icosphere(2, 1.0, {0, 0, 0});
  const Vec3d shift = a.positions[5] - a.positions[0];
  PolygonSoup b = a;
  for (auto& p : b.positions) p += shift;  // vertex 0 of B is vertex 5 of A, and more
  const BooleanReport u = run(a, b, BooleanOp::kUnion), i = run(a, b, BooleanOp::kIntersection);
  EXPECT_TRUE(closed_model(u.result));
  EXPECT_TRUE(closed_model(i.result));
  EXPECT_NEAR(u.volume + i.volume, u.volume_a + u.volume_b, 1e-12 * (u.volume_a + u.volume_b));
}

}  // namespace
}  // namespace atelier

namespace atelier {
namespace {

/// Section 4: the cut polygons are dropped and the gap is closed by
/// connecting meshes; the result is closed, and its volume stays near the
/// cut result (the gap is one ring of meshes wide).
TEST(NetBoolean, JoinByConnectingMeshes) {
  const PolygonSoup a = net_test::icosphere(3, 1.0, {0, 0, 0});
  const PolygonSoup b = net_test::icosphere(3, 0.8, {0.9, 0.05, 0.03});
  const double cut_volume = run(a, b, BooleanOp::kUnion).volume;
  for (ConnectRule rule : {ConnectRule::kTriShortest, ConnectRule::kTriTwoSided}) {
    BooleanOptions o;
    o.op = BooleanOp::kUnion;
    o.join = BooleanJoin::kMeshes;
    o.rule = rule;
    auto r = net_boolean(a, b, o);
    ASSERT_TRUE(r.has_value()) << r.status().to_string();
    EXPECT_TRUE(closed_model(r->result));
    EXPECT_EQ(r->gaps, 1u);
    EXPECT_GT(r->connecting.triangles, 0u);
    EXPECT_NEAR(r->volume, cut_volume, 0.05 * cut_volume);
  }
  // Quad nets joined by quads (UV spheres: quads with triangle fans at the poles).
  const PolygonSoup qa = net_test::from_shapes(shapes::uv_sphere(24, 12, 1.0, {0, 0, 0}));
  const PolygonSoup qb = net_test::from_shapes(shapes::uv_sphere(24, 12, 1.0, {0.05, 0.03, 1.3}));
  BooleanOptions o;
  o.join = BooleanJoin::kMeshes;
  o.rule = ConnectRule::kQuadRegularMeshes;
  auto q = net_boolean(qa, qb, o);
  ASSERT_TRUE(q.has_value()) << q.status().to_string();
  EXPECT_TRUE(closed_model(q->result));
  EXPECT_LE(q->connecting.triangles + q->connecting.other, 1u);  // all quads but at most one
}

}  // namespace
}  // namespace atelier

namespace atelier {
namespace {

/// Paper mode (section 3, Fig. 2): pairs of A's and B's intersection points
/// merged at midpoints; still closed, fewer seam vertices, the volume close
/// to exact mode's; the topological correspondence merges at least as many
/// pairs as the visual one.
TEST(NetBoolean, PaperModeMergesCorrespondingPoints) {
  const PolygonSoup a = net_test::icosphere(3, 1.0, {0, 0, 0});
  const PolygonSoup b = net_test::from_shapes(shapes::uv_sphere(32, 16, 0.9, {0.85, 0.031, -0.017}));
  const BooleanReport exact = run(a, b, BooleanOp::kUnion);
  std::size_t visual = 0, topological = 0;
  for (Correspondence c : {Correspondence::kVisual, Correspondence::kTopological, Correspondence::kWindowSmall,
                           Correspondence::kWindowLarge}) {
    BooleanOptions o;
    o.op = BooleanOp::kUnion;
    o.mode = BooleanMode::kPaper;
    o.correspondence = c;
    auto r = net_boolean(a, b, o);
    ASSERT_TRUE(r.has_value()) << r.status().to_string();
    EXPECT_TRUE(closed_model(r->result)) << static_cast<int>(c);
    EXPECT_GT(r->merged_pairs, 0u);
    EXPECT_EQ(r->seam.size() + r->merged_pairs, exact.seam.size()) << static_cast<int>(c);
    EXPECT_EQ(r->valence.vertices, r->seam.size());
    EXPECT_GE(r->valence.mean, 3.0);
    EXPECT_NEAR(r->volume, exact.volume, 2e-3 * exact.volume);
    if (c == Correspondence::kVisual) visual = r->merged_pairs;
    if (c == Correspondence::kTopological) topological = r->merged_pairs;
  }
  EXPECT_GE(topological, visual);
}

}  // namespace
}  // namespace atelier
