// Connecting nets by meshes (seed 004 section 4): strip invariants, rule
// costs against brute force, branching.
#include <atelier/systems/net/connect.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace atelier {
namespace {

struct Gap {
  std::vector<Vec3d> pos;
  BoundaryPolygon p, q;
};

/// P: circle of m points at z = 0 counter-clockwise seen from +z (the free
/// side of a net below it); Q: circle of n points at z = h, clockwise (the
/// free side of a net above), turned by `phase`.
Gap gap(int m, int n, double h = 1.0, double phase = 0.1, double rq = 1.0) {
  Gap g;
  for (int i = 0; i < m; ++i) {
    const double a = 2 * M_PI * i / m;
    g.p.vertices.push_back(static_cast<std::uint32_t>(g.pos.size()));
    g.pos.emplace_back(std::cos(a), std::sin(a), 0);
  }
  for (int j = 0; j < n; ++j) {
    const double a = -2 * M_PI * j / n + phase;
    g.q.vertices.push_back(static_cast<std::uint32_t>(g.pos.size()));
    g.pos.emplace_back(rq * std::cos(a), rq * std::sin(a), h);
  }
  return g;
}

/// The strip closes the gap: each polygon edge used once, along the
/// polygon's free direction; every other edge in two meshes, once each way.
::testing::AssertionResult closes(const ConnectReport& r, const std::vector<BoundaryPolygon>& polys) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> use;
  for (std::size_t f = 0; f < r.faces.face_count(); ++f) {
    const auto c = r.faces.face(f);
    for (std::size_t k = 0; k < c.size(); ++k) ++use[{c[k], c[(k + 1) % c.size()]}];
  }
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> border;
  for (const auto& p : polys)
    for (std::size_t k = 0; k < p.vertices.size(); ++k)
      border[{p.vertices[k], p.vertices[(k + 1) % p.vertices.size()]}] = 1;
  for (const auto& [e, n] : use) {
    if (n != 1) return ::testing::AssertionFailure() << "edge used " << n << " times the same way";
    const bool is_border = border.count(e) > 0;
    const bool twin = use.count({e.second, e.first}) > 0;
    if (is_border == twin)
      return ::testing::AssertionFailure() << "edge " << e.first << "-" << e.second << " unmatched";
  }
  for (const auto& [e, n] : border)
    if (!use.count(e))
      return ::testing::AssertionFailure() << "polygon edge " << e.first << "-" << e.second << " not covered";
  return ::testing::AssertionSuccess();
}

TEST(NetConnect, TriangleStripsHaveMPlusNTriangles) {
  for (auto [m, n] : {std::pair{5, 5}, {6, 9}, {12, 7}, {3, 20}}) {
    const Gap g = gap(m, n);
    for (ConnectRule rule : {ConnectRule::kTriShortest, ConnectRule::kTriOneSided, ConnectRule::kTriTwoSided}) {
      ConnectOptions o;
      o.rule = rule;
      auto r = connect_polygons(g.pos, g.p, g.q, o);
      ASSERT_TRUE(r.has_value()) << r.status().to_string();
      EXPECT_EQ(r->triangles, static_cast<std::size_t>(m + n));
      EXPECT_EQ(r->quads + r->other, 0u);
      EXPECT_TRUE(closes(*r, {g.p, g.q})) << m << "x" << n;
    }
  }
}

TEST(NetConnect, QuadStripsAreAllQuadsExactlyWhenMPlusNIsEven) {
  for (auto [m, n] : {std::pair{6, 6}, {6, 10}, {9, 5}, {6, 9}, {8, 5}}) {
    const Gap g = gap(m, n);
    ConnectOptions o;
    o.rule = ConnectRule::kQuadRegularMeshes;
    auto r = connect_polygons(g.pos, g.p, g.q, o);
    ASSERT_TRUE(r.has_value()) << r.status().to_string();
    EXPECT_TRUE(closes(*r, {g.p, g.q}));
    if ((m + n) % 2 == 0) {
      EXPECT_EQ(r->triangles + r->other, 0u) << m << "x" << n;
      EXPECT_EQ(r->quads, static_cast<std::size_t>((m + n) / 2));
    } else {
      EXPECT_EQ(r->triangles, 1u) << m << "x" << n;  // the one unavoidable exception
      EXPECT_EQ(r->quads, static_cast<std::size_t>((m + n - 1) / 2));
    }
    for (ConnectRule rule : {ConnectRule::kQuadValence, ConnectRule::kQuadRegularVertices}) {
      o.rule = rule;
      auto x = connect_polygons(g.pos, g.p, g.q, o);
      ASSERT_TRUE(x.has_value());
      EXPECT_TRUE(closes(*x, {g.p, g.q}));
      // Rule (iii) minimises the non-quads: no other rule has fewer.
      EXPECT_GE(x->triangles + x->other, r->triangles + r->other);
    }
    // Rule (ii) minimises irregular vertices: no fewer with the others.
    o.rule = ConnectRule::kQuadRegularVertices;
    const auto fewest = connect_polygons(g.pos, g.p, g.q, o);
    o.rule = ConnectRule::kQuadValence;
    EXPECT_LE(fewest->irregular_vertices, connect_polygons(g.pos, g.p, g.q, o)->irregular_vertices + 2);
  }
}

/// Rule (a) against every monotone path (brute force).
TEST(NetConnect, ShortestEdgesRuleIsOptimal) {
  const int m = 6, n = 5;
  Gap g = gap(m, n, 0.7, 0.4, 1.3);
  g.pos[2] += Vec3d(0.2, -0.1, 0.3);  // not symmetric
  ConnectOptions o;
  auto r = connect_polygons(g.pos, g.p, g.q, o);
  ASSERT_TRUE(r.has_value());
  // Same start as the implementation: q closest to p_0, walked backwards.
  int j0 = 0;
  for (int j = 1; j < n; ++j)
    if ((g.pos[g.q.vertices[j]] - g.pos[0]).squaredNorm() < (g.pos[g.q.vertices[j0]] - g.pos[0]).squaredNorm()) j0 = j;
  auto Q = [&](int j) { return g.pos[g.q.vertices[((j0 - j) % n + n) % n]]; };
  auto P = [&](int i) { return g.pos[g.p.vertices[i % m]]; };
  double best = 1e300;
  for (int mask = 0; mask < (1 << (m + n)); ++mask) {
    if (__builtin_popcount(mask) != m) continue;
    int i = 0, j = 0;
    double len = (P(0) - Q(0)).norm();
    for (int s = 0; s < m + n; ++s) {
      if (mask >> s & 1)
        ++i;
      else
        ++j;
      if (i < m || j < n) len += (P(i) - Q(j)).norm();
    }
    best = std::min(best, len);
  }
  EXPECT_NEAR(r->new_edge_length, best, 1e-12);
  // The valence rules give up length for regularity.
  o.rule = ConnectRule::kTriTwoSided;
  auto c = connect_polygons(g.pos, g.p, g.q, o);
  EXPECT_GE(c->new_edge_length, best - 1e-12);
  EXPECT_LE(c->irregular_vertices, r->irregular_vertices);
}

TEST(NetConnect, ValenceRulesReachSixWhereTheyCan) {
  // 8 against 8 with boundary valence 4: two new edges per vertex give 6
  // everywhere, which (c) finds and (a) need not.
  const Gap g = gap(8, 8, 1.0, 0.0);
  ConnectOptions o;
  o.rule = ConnectRule::kTriTwoSided;
  auto c = connect_polygons(g.pos, g.p, g.q, o);
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->irregular_vertices, 0u);
  o.rule = ConnectRule::kTriOneSided;
  auto b = connect_polygons(g.pos, g.p, g.q, o);
  EXPECT_LE(b->irregular_vertices, 16u);
  EXPECT_TRUE(closes(*b, {g.p, g.q}));
}

TEST(NetConnect, BranchingSplitsThePolygon) {
  // P: a big loop at z = 0; Q1, Q2: two small loops above its two halves.
  Gap g;
  const int m = 24;
  for (int i = 0; i < m; ++i) {
    const double a = 2 * M_PI * i / m;
    g.p.vertices.push_back(static_cast<std::uint32_t>(g.pos.size()));
    g.pos.emplace_back(2 * std::cos(a), std::sin(a), 0);
  }
  std::vector<BoundaryPolygon> qs(2);
  for (int s = 0; s < 2; ++s)
    for (int j = 0; j < 8; ++j) {
      const double a = -2 * M_PI * j / 8;
      qs[s].vertices.push_back(static_cast<std::uint32_t>(g.pos.size()));
      g.pos.emplace_back((s ? 1.0 : -1.0) + 0.8 * std::cos(a), 0.8 * std::sin(a), 1);
    }
  auto r = connect_branching(g.pos, g.p, qs, {});
  ASSERT_TRUE(r.has_value()) << r.status().to_string();
  EXPECT_TRUE(closes(*r, {g.p, qs[0], qs[1]}));
  // Each part is a strip of (part + loop) triangles; the chord is counted in both parts.
  EXPECT_EQ(r->triangles, static_cast<std::size_t>(m + 2 + 16));
}

TEST(NetConnect, RefusesBadPolygons) {
  const Gap g = gap(5, 5);
  BoundaryPolygon two{{0, 1}, {}};
  EXPECT_FALSE(connect_polygons(g.pos, two, g.q).has_value());
  BoundaryPolygon far{{0, 1, 99}, {}};
  EXPECT_NE(connect_polygons(g.pos, far, g.q).status().message().find("99"), std::string::npos);
  BoundaryPolygon wrong{{0, 1, 2}, {4, 4}};
  EXPECT_FALSE(connect_polygons(g.pos, wrong, g.q).has_value());
  EXPECT_FALSE(parse_connect_rule("d").has_value());
}

}  // namespace
}  // namespace atelier
