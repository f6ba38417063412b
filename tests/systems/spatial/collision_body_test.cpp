// The collision body (Embree culls, the rest is exact): every answer must be
// the same bits as a brute-force search over all triangles with the same
// exact functions (closest_point_on_triangle, the tie rule, the pseudo-normal
// sign): distance, closest point, normal, triangle and barycentric, with and
// without hints, singly and in parallel batches, on scenes refit from another
// body's layout, with several bodies (scenes) alive at once. BodyBvh (an
// independent Embree search) agrees on the distances.
#include <atelier/systems/spatial/collision_body.h>

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>

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

CollisionBody body_of(const std::shared_ptr<const CollisionTopology>& topo, std::span<const Vec3d> p) {
  CollisionBody cb;
  if (Status s = cb.build(topo, p); !s) throw Error(s);
  return cb;
}

// The answer by brute force: every triangle, smallest squared distance then
// smallest index, sign and outward direction by the contract of
// collision_body.h (the distance gradient off the surface, the unit
// pseudo-normal on it).
BodyDistance brute_force(const CollisionTopology& topo, std::span<const Vec3d> pos, const Vec3d& p) {
  double best = std::numeric_limits<double>::infinity();
  std::uint32_t bt = kNoTriangle;
  TrianglePoint br{Vec3d::Zero(), Vec3d::Zero(), TriFeature::kFace};
  const auto tris = topo.triangles();
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    const TrianglePoint r = closest_point_on_triangle(p, pos[tris[t][0]], pos[tris[t][1]], pos[tris[t][2]]);
    const double d2 = (p - r.point).squaredNorm();
    if (d2 < best) best = d2, bt = t, br = r;
  }
  const Vec3d pn = pseudo_normal(topo.triangle_topology(), pos, bt, br.feature);
  const Vec3d d = p - br.point;
  const double len = d.norm(), sign = pseudo_normal_sign(p, br.point, pn), pl = pn.norm();
  BodyDistance out;
  out.distance = sign * len;
  out.closest = br.point;
  out.normal = len > 1e-12 ? Vec3d(sign * d / len) : (pl > 0 ? Vec3d(pn / pl) : Vec3d::UnitZ());
  out.triangle = bt;
  out.barycentric = br.barycentric;
  return out;
}

// Query points: random in and around the body's box, near the surface on
// both sides (within 2 cm), exactly on it (corners, edge midpoints), far
// away, and on the axis (where the closest feature is a pole or a ring
// vertex shared by many triangles: the tie rule decides).
std::vector<Vec3d> probe_points(const TriBody& b, SplitMix64& rng, int n = 600) {
  Box3d box;
  for (const Vec3d& q : b.p) box.extend(q);
  const Vec3d c = 0.5 * (box.lo + box.hi), h = 0.65 * (box.hi - box.lo);
  std::vector<Vec3d> out;
  for (int i = 0; i < n; ++i)
    out.push_back(c + Vec3d(rng.uniform(-1, 1) * h.x(), rng.uniform(-1, 1) * h.y(), rng.uniform(-1, 1) * h.z()));
  for (int i = 0; i < n; ++i) {
    const Triangle& t = b.t[static_cast<std::size_t>(rng.uniform(0, static_cast<double>(b.t.size()) - 1))];
    double u = rng.uniform(), v = rng.uniform();
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vec3d on = (1 - u - v) * b.p[t[0]] + u * b.p[t[1]] + v * b.p[t[2]];
    const Vec3d n = (b.p[t[1]] - b.p[t[0]]).cross(b.p[t[2]] - b.p[t[0]]).normalized();
    out.push_back(on + rng.uniform(-0.02, 0.02) * n);
    if (i % 3 == 0) out.push_back(b.p[t[(i / 3) % 3]]);
    if (i % 3 == 1) out.push_back(0.5 * (b.p[t[0]] + b.p[t[1]]));
  }
  for (int i = 0; i < n / 6; ++i) {
    const Vec3d d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    out.push_back(c + 10 * (box.hi - box.lo).norm() * d.normalized());
  }
  for (int i = 0; i <= 40; ++i)
    out.push_back(Vec3d(c.x(), c.y(), box.lo.z() - 0.1 + (box.hi.z() - box.lo.z() + 0.2) * i / 40));
  return out;
}

// Every kind of query over one set of positions against brute force.
void expect_exact(const TriBody& b, const std::shared_ptr<const CollisionTopology>& topo, const CollisionBody& cb,
                  std::uint64_t seed, int n = 300) {
  SplitMix64 rng(seed);
  const std::vector<Vec3d> pts = probe_points(b, rng, n);
  const auto nt = static_cast<std::uint32_t>(b.t.size());
  BodyBvh bvh;
  ASSERT_TRUE(bvh.build(std::span<const Vec3d>(b.p), b.t));
  std::vector<BodyDistance> truth(pts.size());
  std::vector<std::uint32_t> good(pts.size()), random_hint(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    truth[i] = brute_force(*topo, b.p, pts[i]);
    ASSERT_TRUE(same(truth[i], cb.query(pts[i]))) << "no hint, point " << i << " at " << pts[i].transpose();
    ASSERT_EQ(bits(bvh.signed_distance(pts[i]).distance), bits(truth[i].distance)) << i;
    good[i] = truth[i].triangle;
    random_hint[i] = static_cast<std::uint32_t>(rng.uniform(0, nt - 1.0));
    // Hints: the answer's own triangle, a neighbour of it, any triangle.
    const std::uint32_t neighbour = topo->triangle_topology().across(good[i], static_cast<int>(i % 3));
    for (std::uint32_t hint : {good[i], neighbour, random_hint[i]})
      ASSERT_TRUE(same(truth[i], cb.query(pts[i], hint))) << "hint " << hint << ", point " << i;
  }
  // Parallel batches, with and without hints.
  ExecContext two;
  two.threads = 2;
  for (const std::vector<std::uint32_t>* hints : {&good, &random_hint, static_cast<decltype(&good)>(nullptr)}) {
    std::vector<BodyDistance> out(pts.size());
    ASSERT_TRUE(cb.query_many(pts, hints ? std::span<const std::uint32_t>(*hints) : std::span<const std::uint32_t>(),
                              out, two));
    for (std::size_t i = 0; i < pts.size(); ++i) ASSERT_TRUE(same(truth[i], out[i])) << "query_many, point " << i;
  }
}

TEST(CollisionBody, AnswersEqualBruteForceBitForBitOnACapsuleAndASphere) {
  for (const TriBody& b :
       {test_bodies::capsule(0.3, 0.5, 48, 12, 20), test_bodies::triangulate(shapes::uv_sphere(64, 32, 0.4))}) {
    const auto topo = topology_of(b);
    expect_exact(b, topo, body_of(topo, b.p), 5);
    if (HasFatalFailure()) return;
  }
}

// Embree's scene is built on the first body and refit on the next ones
// (each a strong deformation of the first), one body object rebuilt: still
// exact; the first body, alive meanwhile (its own scene), is undisturbed.
TEST(CollisionBody, RefitScenesOnDeformedBodiesStayExact) {
  const TriBody rest = test_bodies::capsule(0.1, 0.2, 48, 10, 20);
  const auto topo = topology_of(rest);
  const CollisionBody first = body_of(topo, rest.p);
  CollisionBody reused;
  std::vector<TriBody> shapes;
  for (int shape = 0; shape < 3; ++shape) {
    TriBody b = rest;
    for (Vec3d& q : b.p) {
      const double z = q.z();
      const double bulge = 1 + 0.5 * std::exp(-z * z / 0.01) * (shape == 2);
      q.x() *= (shape == 0 ? 1.6 : 1.0) * bulge;
      q.y() *= (shape == 0 ? 0.7 : 1.0) * bulge;
      if (shape == 1) q.x() += 0.8 * z * z;  // bent like a banana
    }
    shapes.push_back(std::move(b));
  }
  for (int round = 0; round < 2; ++round)
    for (std::size_t k = 0; k < shapes.size(); ++k) {
      ASSERT_TRUE(reused.build(topo, shapes[k].p));
      expect_exact(shapes[k], topo, reused, 17 + k, 100);
      if (HasFatalFailure()) return;
    }
  expect_exact(rest, topo, first, 3, 100);
}

TEST(CollisionBody, RejectsCoordinatesBeyondFloatRangeAndWrongSizes) {
  TriBody b = test_bodies::capsule(0.1, 0.2, 16, 4, 4);
  const auto topo = topology_of(b);
  b.p[3].x() = 1e35;
  CollisionBody cb;
  const Status s = cb.build(topo, b.p);
  EXPECT_EQ(s.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(s.message().find("float range"), std::string::npos) << s.message();
  EXPECT_TRUE(cb.empty());
  EXPECT_EQ(cb.build(topo, std::span(b.p).first(5)).code(), ErrorCode::kMismatch);
  b.p[3].x() = std::nan("");
  EXPECT_EQ(cb.build(topo, b.p).code(), ErrorCode::kDegenerate);
}

}  // namespace
}  // namespace atelier
