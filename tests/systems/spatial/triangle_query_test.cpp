// The one body-distance stack: the triangle queries and the sign rule of
// systems/spatial/triangle_query.h, and the three structures that use them
// (BodyBvh, CollisionBody, BodyCollider) answering the same bits.
#include <atelier/systems/spatial/triangle_query.h>

#include <gtest/gtest.h>

#include <random>

#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/spatial/collision_body.h>
#include "support/closed_bodies.h"

namespace atelier {
namespace {

TEST(TriangleQuery, ClosestPointBeatsDenseSampling) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Vec3d p(2 * u(rng), 2 * u(rng), 2 * u(rng));
    const TrianglePoint r = closest_point_on_triangle(p, a, b, c);
    EXPECT_LT((r.barycentric[0] * a + r.barycentric[1] * b + r.barycentric[2] * c - r.point).norm(), 1e-12);
    double best = 1e300;
    for (int i = 0; i <= 60; ++i)
      for (int j = 0; i + j <= 60; ++j) {
        const double s = i / 60.0, t = j / 60.0;
        best = std::min(best, (p - ((1 - s - t) * a + s * b + t * c)).norm());
      }
    EXPECT_LE((p - r.point).norm(), best + 1e-12);
  }
}

TEST(TriangleQuery, TopologyNamesTheFirstOpenEdge) {
  const std::vector<Triangle> tet = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  auto closed = TriangleTopology::build(tet, 4);
  ASSERT_TRUE(closed.has_value());
  EXPECT_TRUE(closed->closed());
  for (std::uint32_t t = 0; t < 4; ++t)
    for (int k = 0; k < 3; ++k) EXPECT_NE(closed->across(t, k), kNoTriangle);
  EXPECT_EQ(closed->triangles_around(0).size(), 3u);
  auto open = TriangleTopology::build(std::span(tet).first(3), 4);
  ASSERT_TRUE(open.has_value());
  EXPECT_FALSE(open->closed());
  EXPECT_NE(open->open_message().find("boundary edge"), std::string::npos) << open->open_message();
  std::vector<Triangle> flipped = tet;
  std::swap(flipped[3][1], flipped[3][2]);
  EXPECT_NE(TriangleTopology::build(flipped, 4)->open_message().find("same direction"), std::string::npos);
  EXPECT_FALSE(TriangleTopology::build(tet, 3).has_value());  // point 3 out of range
}

TEST(TriangleQuery, VertexPseudoNormalOfACubeCornerIsTheDiagonal) {
  // A cube's corner: three right angles of three faces, so the angle-weighted
  // normal points along the diagonal (the unweighted average of a triangulated
  // corner would not).
  const std::vector<Vec3d> p = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const std::vector<Triangle> t = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                   {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  auto topo = TriangleTopology::build(t, 8);
  ASSERT_TRUE(topo->closed());
  const Vec3d n = vertex_pseudo_normal(*topo, p, 6).normalized();
  EXPECT_LT((n - Vec3d(1, 1, 1).normalized()).norm(), 1e-12);
  EXPECT_EQ(pseudo_normal_sign(Vec3d(1.1, 1.1, 1.1), p[6], n), 1.0);
  EXPECT_EQ(pseudo_normal_sign(Vec3d(0.9, 0.9, 0.9), p[6], n), -1.0);
}

TEST(TriangleQuery, BvhAndCollisionBodyAgreeBitForBit) {
  const test_bodies::TriBody body = test_bodies::capsule(0.3, 0.5, 48, 12, 20);
  BodyBvh bvh;
  ASSERT_TRUE(bvh.build(std::span<const Vec3d>(body.p), body.t));
  auto topo = CollisionTopology::build(body.t, static_cast<std::uint32_t>(body.p.size()));
  ASSERT_TRUE(topo.has_value()) << topo.status().to_string();
  CollisionBody cb;
  ASSERT_TRUE(cb.build(*topo, body.p));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  int inside = 0;
  for (int i = 0; i < 3000; ++i) {
    // Half the points near the surface (within 2 cm), where signs are delicate.
    Vec3d q(0.5 * u(rng), 0.5 * u(rng), 1.0 * u(rng));
    if (i % 2) {
      const BodyDistance on = cb.query(q);
      q = on.closest + 0.02 * u(rng) * on.normal;
    }
    const SignedHit a = bvh.signed_distance(q);
    const BodyDistance b = cb.query(q);
    ASSERT_EQ(a.distance, b.distance) << i;
    // Ties (a closest point on an edge or vertex shared by triangles) may be
    // settled differently; the point itself is the same.
    ASSERT_LT((a.closest.point - b.closest).norm(), 1e-15) << i;
    inside += b.distance < 0;
  }
  EXPECT_GT(inside, 500);
}

}  // namespace
}  // namespace atelier
