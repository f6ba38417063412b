// The collision body's two backends (CollisionBackend): the hand-written
// hierarchy and Embree only cull, so every answer must be the same bits:
// distance, closest point, normal, triangle and barycentric, with and
// without hints, one by one, in clusters and in parallel batches, on bodies
// refit from another's layout, and through the whole collision pass. The
// distances are also checked against BodyBvh (an independent Embree search).
#include <atelier/systems/spatial/collision_body.h>

#include <gtest/gtest.h>

#include <bit>
#include <cmath>

#include <atelier/engine/random.h>
#include <atelier/systems/spatial/body_bvh.h>
#include "support/closed_bodies.h"
#include "support/shapes.h"

namespace atelier {
namespace {

using test_bodies::TriBody;

std::uint64_t bits(double x) {
  return std::bit_cast<std::uint64_t>(x);
}

// Bit-for-bit equality of two answers, naming the first field that differs.
::testing::AssertionResult same(const BodyDistance& a, const BodyDistance& b) {
  auto vec = [](const Vec3d& x, const Vec3d& y) {
    return bits(x[0]) == bits(y[0]) && bits(x[1]) == bits(y[1]) && bits(x[2]) == bits(y[2]);
  };
  if (a.triangle != b.triangle)
    return ::testing::AssertionFailure() << "triangle " << a.triangle << " vs " << b.triangle;
  if (bits(a.distance) != bits(b.distance))
    return ::testing::AssertionFailure() << "distance " << a.distance << " vs " << b.distance;
  if (!vec(a.closest, b.closest)) return ::testing::AssertionFailure() << "closest point";
  if (!vec(a.normal, b.normal)) return ::testing::AssertionFailure() << "normal";
  if (!vec(a.barycentric, b.barycentric)) return ::testing::AssertionFailure() << "barycentric";
  return ::testing::AssertionSuccess();
}

std::shared_ptr<const CollisionTopology> topology_of(const TriBody& b) {
  auto t = CollisionTopology::build(b.t, static_cast<std::uint32_t>(b.p.size()));
  if (!t) throw Error(t.status());
  return *t;
}

CollisionBody body_of(const std::shared_ptr<const CollisionTopology>& topo, std::span<const Vec3d> p,
                      CollisionBackend backend) {
  CollisionBodyParams prm;
  prm.backend = backend;
  CollisionBody cb;
  if (Status s = cb.build(topo, p, prm); !s) throw Error(s);
  return cb;
}

// Query points: random in and around the body's box, near the surface on
// both sides (within 2 cm), exactly on it (corners, edge midpoints), far
// away, and on the axis (where the closest feature is a pole or a ring
// vertex shared by many triangles: the tie rule decides).
std::vector<Vec3d> probe_points(const TriBody& b, SplitMix64& rng) {
  Box3d box;
  for (const Vec3d& q : b.p) box.extend(q);
  const Vec3d c = 0.5 * (box.lo + box.hi), h = 0.65 * (box.hi - box.lo);
  std::vector<Vec3d> out;
  for (int i = 0; i < 600; ++i)
    out.push_back(c + Vec3d(rng.uniform(-1, 1) * h.x(), rng.uniform(-1, 1) * h.y(), rng.uniform(-1, 1) * h.z()));
  for (int i = 0; i < 600; ++i) {
    const Triangle& t = b.t[static_cast<std::size_t>(rng.uniform(0, static_cast<double>(b.t.size()) - 1))];
    double u = rng.uniform(), v = rng.uniform();
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vec3d on = (1 - u - v) * b.p[t[0]] + u * b.p[t[1]] + v * b.p[t[2]];
    const Vec3d n = (b.p[t[1]] - b.p[t[0]]).cross(b.p[t[2]] - b.p[t[0]]).normalized();
    out.push_back(on + rng.uniform(-0.02, 0.02) * n);
    if (i % 3 == 0) out.push_back(b.p[t[(i / 3) % 3]]);
    if (i % 3 == 1) out.push_back(0.5 * (b.p[t[0]] + b.p[t[1]]));
  }
  for (int i = 0; i < 100; ++i) {
    const Vec3d d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    out.push_back(c + 10 * (box.hi - box.lo).norm() * d.normalized());
  }
  for (int i = 0; i <= 40; ++i) out.push_back(Vec3d(c.x(), c.y(), box.lo.z() - 0.1 + (box.hi.z() - box.lo.z() + 0.2) * i / 40));
  return out;
}

// Every kind of query on both backends over one set of positions.
void expect_backends_agree(const TriBody& b, const std::shared_ptr<const CollisionTopology>& topo,
                           const CollisionBody& hier, const CollisionBody& emb, std::uint64_t seed) {
  ASSERT_EQ(hier.backend(), CollisionBackend::kHierarchy);
  ASSERT_EQ(emb.backend(), CollisionBackend::kEmbree);
  SplitMix64 rng(seed);
  const std::vector<Vec3d> pts = probe_points(b, rng);
  const auto nt = static_cast<std::uint32_t>(b.t.size());
  BodyBvh bvh;
  ASSERT_TRUE(bvh.build(std::span<const Vec3d>(b.p), b.t));
  std::vector<std::uint32_t> good(pts.size()), random_hint(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const BodyDistance h = hier.query(pts[i]);
    const BodyDistance e = emb.query(pts[i]);
    ASSERT_TRUE(same(h, e)) << "no hint, point " << i << " at " << pts[i].transpose();
    ASSERT_EQ(bits(bvh.signed_distance(pts[i]).distance), bits(e.distance)) << i;
    good[i] = h.triangle;
    random_hint[i] = static_cast<std::uint32_t>(rng.uniform(0, nt - 1.0));
    // Hints: the answer's own triangle, a neighbour of it, any triangle.
    const std::uint32_t neighbour = topo->triangle_topology().across(h.triangle, static_cast<int>(i % 3));
    for (std::uint32_t hint : {h.triangle, neighbour, random_hint[i]}) {
      ASSERT_TRUE(same(hier.query(pts[i], hint), emb.query(pts[i], hint))) << "hint " << hint << ", point " << i;
      ASSERT_TRUE(same(e, emb.query(pts[i], hint))) << "the hint changed Embree's answer at point " << i;
    }
  }
  // Batches (clusters of neighbours by hint, in parallel) and clusters.
  for (const auto* hints : {&good, &random_hint}) {
    std::vector<BodyDistance> a(pts.size()), c(pts.size());
    ExecContext two;
    two.threads = 2;
    ASSERT_TRUE(hier.query_many(pts, *hints, a, two));
    ASSERT_TRUE(emb.query_many(pts, *hints, c, two));
    for (std::size_t i = 0; i < pts.size(); ++i) ASSERT_TRUE(same(a[i], c[i])) << "query_many, point " << i;
    std::vector<BodyDistance> d(8);
    for (std::size_t i = 0; i + 8 <= pts.size(); i += 8) {
      ASSERT_TRUE(emb.query_cluster(std::span(pts).subspan(i, 8), std::span(*hints).subspan(i, 8), d));
      for (std::size_t k = 0; k < 8; ++k) ASSERT_TRUE(same(a[i + k], d[k])) << "query_cluster, point " << i + k;
    }
  }
  std::vector<BodyDistance> a(pts.size()), c(pts.size());
  ASSERT_TRUE(hier.query_many(pts, {}, a));
  ASSERT_TRUE(emb.query_many(pts, {}, c));
  for (std::size_t i = 0; i < pts.size(); ++i) ASSERT_TRUE(same(a[i], c[i])) << "query_many without hints, " << i;
}

TEST(CollisionBackend, EmbreeAndHierarchyAgreeBitForBitOnACapsuleAndASphere) {
  for (const TriBody& b : {test_bodies::capsule(0.3, 0.5, 48, 12, 20),
                           test_bodies::triangulate(shapes::uv_sphere(64, 32, 0.4))}) {
    const auto topo = topology_of(b);
    const CollisionBody hier = body_of(topo, b.p, CollisionBackend::kHierarchy);
    const CollisionBody emb = body_of(topo, b.p, CollisionBackend::kEmbree);
    expect_backends_agree(b, topo, hier, emb, 5);
    if (HasFatalFailure()) return;
  }
}

// Embree's scene is built on the first body and refit on the next ones
// (each a strong deformation of the first): still the same answers, with
// two bodies alive at once (two scenes) and one body object rebuilt.
TEST(CollisionBackend, RefitSceneOnDeformedBodiesStillAgrees) {
  const TriBody rest = test_bodies::capsule(0.1, 0.2, 48, 10, 20);
  const auto topo = topology_of(rest);
  const CollisionBody first = body_of(topo, rest.p, CollisionBackend::kEmbree);
  CollisionBody reused;
  for (int shape = 0; shape < 3; ++shape) {
    TriBody b = rest;
    for (Vec3d& q : b.p) {
      const double z = q.z();
      const double bulge = 1 + 0.5 * std::exp(-z * z / 0.01) * (shape == 2);
      q.x() *= (shape == 0 ? 1.6 : 1.0) * bulge;
      q.y() *= (shape == 0 ? 0.7 : 1.0) * bulge;
      if (shape == 1) q.x() += 0.8 * z * z;  // bent like a banana
    }
    CollisionBodyParams prm;
    prm.backend = CollisionBackend::kEmbree;
    ASSERT_TRUE(reused.build(topo, b.p, prm));
    const CollisionBody hier = body_of(topo, b.p, CollisionBackend::kHierarchy);
    expect_backends_agree(b, topo, hier, reused, 17 + shape);
    if (HasFatalFailure()) return;
  }
  // The first body's scene was not disturbed by the others' refits.
  const CollisionBody hier0 = body_of(topo, rest.p, CollisionBackend::kHierarchy);
  SplitMix64 rng(3);
  for (const Vec3d& p : probe_points(rest, rng)) ASSERT_TRUE(same(hier0.query(p), first.query(p)));
}

TEST(CollisionBackend, EmbreeRejectsCoordinatesBeyondFloatRangeAndWrongSizes) {
  TriBody b = test_bodies::capsule(0.1, 0.2, 16, 4, 4);
  const auto topo = topology_of(b);
  CollisionBodyParams prm;
  prm.backend = CollisionBackend::kEmbree;
  b.p[3].x() = 1e35;
  CollisionBody cb;
  const Status s = cb.build(topo, b.p, prm);
  EXPECT_EQ(s.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(s.message().find("float range"), std::string::npos) << s.message();
  EXPECT_TRUE(cb.empty());
  EXPECT_EQ(cb.build(topo, std::span(b.p).first(5), prm).code(), ErrorCode::kMismatch);
}

// The collision pass through either backend: garment positions, reports
// and final distances bit for bit (a tube squeezed into a capsule, and a
// two-layer outfit).
TEST(CollisionBackend, CollisionPassGivesTheSameBitsOnBothBackends) {
  const double r = 0.1, c = 0.004;
  const TriBody body = test_bodies::capsule(r, 0.25, 48, 8, 30);
  const auto topo = topology_of(body);
  const CollisionBody hier = body_of(topo, body.p, CollisionBackend::kHierarchy);
  const CollisionBody emb = body_of(topo, body.p, CollisionBackend::kEmbree);
  auto tube = [&](double rr) {
    return test_bodies::grid_patch(40, 30, true, [&](int i, int j) {
      const double ph = 2 * M_PI * (i + 0.25) / 40, z = -0.2 + 0.4 * j / 29;
      return Vec3d(rr * std::cos(ph), rr * std::sin(ph), z);
    });
  };
  auto squeeze = [](test_bodies::Patch& g, double depth) {
    for (auto& q : g.p) {
      const double k = 1 - depth * std::max(0.0, 1 - std::abs(q.z()) / 0.08);
      q.x() *= k;
      q.y() *= k;
    }
  };
  test_bodies::Patch inner = tube(r + c), outer = tube(r + 3 * c);
  auto enc_in = encode_clearance(inner.p, hier);
  auto enc_out = encode_clearance(outer.p, hier);
  ASSERT_TRUE(enc_in && enc_out);
  squeeze(inner, 0.12);
  squeeze(outer, 0.15);
  CollisionParams prm;
  prm.fair_rings = 2;
  for (int layered = 0; layered < 2; ++layered) {
    test_bodies::Patch gi[2] = {inner, inner}, go[2] = {outer, outer};
    std::vector<CollisionReport> reps[2];
    std::vector<BodyDistance> fin[2];
    for (int k = 0; k < 2; ++k) {
      const CollisionBody& cb = k ? emb : hier;
      if (layered) {
        GarmentLayer layers[2] = {{go[k].p, &go[k].adj, &*enc_out, 1}, {gi[k].p, &gi[k].adj, &*enc_in, 0}};
        auto rr = resolve_layers(layers, cb, prm);
        ASSERT_TRUE(rr) << rr.status().to_string();
        reps[k] = *rr;
      } else {
        auto rr = resolve_collisions(gi[k].p, gi[k].adj, *enc_in, cb, prm, fin[k]);
        ASSERT_TRUE(rr) << rr.status().to_string();
        reps[k] = {*rr};
      }
    }
    EXPECT_GT(reps[0][0].inside_before, 50u);
    ASSERT_EQ(reps[0].size(), reps[1].size());
    for (std::size_t i = 0; i < reps[0].size(); ++i) {
      const CollisionReport &a = reps[0][i], &b = reps[1][i];
      EXPECT_EQ(a.pushed, b.pushed);
      EXPECT_EQ(a.faired, b.faired);
      EXPECT_EQ(a.queries, b.queries);
      EXPECT_EQ(a.refused_moves, b.refused_moves);
      EXPECT_EQ(a.inside_after, b.inside_after);
      EXPECT_EQ(a.below_after, b.below_after);
      EXPECT_EQ(bits(a.max_depth_after), bits(b.max_depth_after));
    }
    for (std::size_t v = 0; v < inner.p.size(); ++v)
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(bits(gi[0].p[v][a]), bits(gi[1].p[v][a])) << "inner vertex " << v << (layered ? ", layered" : "");
        if (layered) {
          ASSERT_EQ(bits(go[0].p[v][a]), bits(go[1].p[v][a])) << "outer vertex " << v;
        }
      }
    if (!layered) {
      ASSERT_EQ(fin[0].size(), fin[1].size());
      for (std::size_t v = 0; v < fin[0].size(); ++v) ASSERT_TRUE(same(fin[0][v], fin[1][v])) << v;
    }
  }
}

}  // namespace
}  // namespace atelier
