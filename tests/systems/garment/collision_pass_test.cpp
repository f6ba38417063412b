// Collision pass (issue 7) on analytic bodies: a sphere and a capsule built
// here, garments as grid patches around them. Expectations come from the
// geometry (radii) and from BodyBvh, an independent signed distance.
#include <atelier/systems/garment/collision_pass.h>

#include <gtest/gtest.h>

#include <cmath>

#include <atelier/engine/random.h>
#include "support/closed_bodies.h"
#include "support/shapes.h"
#include <atelier/systems/spatial/body_bvh.h>

using namespace atelier;
using namespace atelier::test_bodies;

namespace {

/// Cap of a sphere (centre 0) at radius rr: theta in [0.3, 1.4], phi in [0, 1.5].
Patch sphere_cap(double rr, int n = 24) {
  return grid_patch(n, n, false, [&](int i, int j) {
    const double th = 0.3 + 1.1 * j / (n - 1), ph = 1.5 * i / (n - 1);
    return Vec3d(rr * std::sin(th) * std::cos(ph), rr * std::sin(th) * std::sin(ph), rr * std::cos(th));
  });
}

struct Scene {
  TriBody body;
  std::shared_ptr<const CollisionTopology> topo;
  CollisionBody cb;
  BodyBvh bvh;
};
std::unique_ptr<Scene> make_scene(TriBody body, const CollisionBodyParams& prm = {}) {
  auto s = std::make_unique<Scene>();
  s->body = std::move(body);
  auto topo = CollisionTopology::build(s->body.t, static_cast<std::uint32_t>(s->body.p.size()));
  if (!topo) throw Error(topo.status());
  s->topo = *topo;
  if (Status st = s->cb.build(s->topo, s->body.p, prm); !st) throw Error(st);
  if (Status st = s->bvh.build(s->body.p, s->body.t); !st) throw Error(st);
  return s;
}

std::vector<double> bvh_distances(const BodyBvh& bvh, std::span<const Vec3d> p) {
  std::vector<double> d(p.size());
  EXPECT_TRUE(bvh.signed_distances(p, d));
  return d;
}

TriBody sphere_body(double r) {
  return triangulate(shapes::uv_sphere(64, 32, r));
}

}  // namespace

TEST(CollisionBody, QueriesMatchBvhSignedDistanceWithAndWithoutHintsAndRoi) {
  const auto full = make_scene(capsule(0.1, 0.2, 48, 10, 20));
  CollisionBodyParams roi;
  roi.roi.extend(Vec3d(0.0, 0.0, 0.0));
  roi.roi.extend(Vec3d(0.12, 0.12, 0.1));
  const auto part = make_scene(capsule(0.1, 0.2, 48, 10, 20), roi);
  SplitMix64 rng(7);
  const auto nt = static_cast<std::uint32_t>(full->body.t.size());
  for (int i = 0; i < 3000; ++i) {
    // Half the points near the surface, half anywhere around the body.
    const Vec3d p = i % 2 ? Vec3d(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(-0.5, 0.5))
                          : Vec3d(rng.uniform(-0.12, 0.12), rng.uniform(-0.12, 0.12), rng.uniform(-0.35, 0.35));
    const SignedHit ref = full->bvh.signed_distance(p);
    const auto hint = static_cast<std::uint32_t>(rng.uniform(0, nt - 1e-9));
    for (const BodyDistance& q : {full->cb.query(p), full->cb.query(p, hint), part->cb.query(p),
                                  part->cb.query(p, hint), part->cb.query(p, ref.closest.triangle)}) {
      ASSERT_NEAR(q.distance, ref.distance, 1e-12) << p.transpose();
      ASSERT_NEAR((q.closest - ref.closest.point).norm(), 0, 1e-9);
      // The outward direction points from the surface to p outside, away inside.
      if (std::abs(q.distance) > 1e-6) {
        ASSERT_NEAR((q.closest + q.distance * q.normal - p).norm(), 0, 1e-9);
      }
    }
  }
}

// Batched queries (in parallel) must give exactly what single queries give:
// the same triangle, closest point and distance bits, whatever the hints
// (good, bad, missing) and wherever the points; checked against the BVH's
// answer too.
TEST(CollisionBody, BatchedQueriesEqualSingleQueries) {
  const auto scene = make_scene(capsule(0.1, 0.2, 48, 10, 20));
  const auto nt = static_cast<std::uint32_t>(scene->body.t.size());
  SplitMix64 rng(17);
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> hint;
  for (int i = 0; i < 4000; ++i) {
    // Mostly a garment-like shell 0-20 mm off the surface, with good hints;
    // some points inside, far away, or with a wrong or no hint.
    const double a = rng.uniform(0, 2 * M_PI), z = rng.uniform(-0.3, 0.3);
    const double off = i % 10 == 0 ? rng.uniform(-0.05, 0.3) : rng.uniform(0.0, 0.02);
    Vec3d q(std::cos(a), std::sin(a), 0);
    if (std::abs(z) > 0.2) {
      const Vec3d c(0, 0, z > 0 ? 0.2 : -0.2);
      const Vec3d dir = (Vec3d(std::cos(a), std::sin(a), (z - c.z()) / 0.1)).normalized();
      q = c + (0.1 + off) * dir;
    } else {
      q = (0.1 + off) * q + Vec3d(0, 0, z);
    }
    p.push_back(q);
    const std::uint32_t good = scene->bvh.signed_distance(q).closest.triangle;
    hint.push_back(i % 7 == 3 ? kNoTriangle
                              : (i % 7 == 5 ? static_cast<std::uint32_t>(rng.uniform(0, nt - 1e-9)) : good));
  }
  // Neighbours in index order are not neighbours in space.
  for (std::size_t i = p.size(); i-- > 1;) {
    const auto j = static_cast<std::size_t>(rng.uniform(0, static_cast<double>(i) + 1 - 1e-9));
    std::swap(p[i], p[j]);
    std::swap(hint[i], hint[j]);
  }
  for (int threads : {1, 2}) {
    ExecContext ctx;
    ctx.threads = threads;
    std::vector<BodyDistance> many(p.size());
    ASSERT_TRUE(scene->cb.query_many(p, hint, many, ctx));
    for (std::size_t i = 0; i < p.size(); ++i) {
      const BodyDistance one = scene->cb.query(p[i], hint[i]);
      ASSERT_EQ(many[i].triangle, one.triangle) << i;
      ASSERT_EQ(many[i].distance, one.distance) << i;
      ASSERT_EQ(many[i].closest, one.closest) << i;
      ASSERT_EQ(many[i].normal, one.normal) << i;
      ASSERT_NEAR(one.distance, scene->bvh.signed_distance(p[i]).distance, 1e-12) << i;
    }
  }
  std::vector<BodyDistance> short_out(p.size() - 1);
  EXPECT_EQ(scene->cb.query_many(p, hint, short_out).code(), ErrorCode::kMismatch);
  EXPECT_EQ(CollisionBody().query_many(p, {}, short_out).code(), ErrorCode::kInvalidArgument);
}

// Embree's hierarchy is built on the first body of a topology and only refit
// on the next ones: answers on a strongly deformed body of the same
// topology (stretched, bent, bulged) must still be exact.
TEST(CollisionBody, RefitOnDeformedBodiesOfTheSameTopologyIsExact) {
  const TriBody rest = capsule(0.1, 0.2, 48, 10, 20);
  auto topo = CollisionTopology::build(rest.t, static_cast<std::uint32_t>(rest.p.size()));
  ASSERT_TRUE(topo);
  CollisionBody first;
  ASSERT_TRUE(first.build(*topo, rest.p));
  SplitMix64 rng(11);
  for (int shape = 0; shape < 3; ++shape) {
    TriBody b = rest;
    for (Vec3d& q : b.p) {
      const double z = q.z();
      const double bulge = 1 + 0.5 * std::exp(-z * z / 0.01) * (shape == 2);
      q.x() *= (shape == 0 ? 1.6 : 1.0) * bulge;
      q.y() *= (shape == 0 ? 0.7 : 1.0) * bulge;
      if (shape == 1) q.x() += 0.8 * z * z;  // bent like a banana
    }
    CollisionBody cb;
    ASSERT_TRUE(cb.build(*topo, b.p));
    BodyBvh bvh;
    ASSERT_TRUE(bvh.build(b.p, b.t));
    for (int i = 0; i < 1500; ++i) {
      const Vec3d p(rng.uniform(-0.3, 0.5), rng.uniform(-0.3, 0.3), rng.uniform(-0.4, 0.4));
      const SignedHit ref = bvh.signed_distance(p);
      const BodyDistance q = cb.query(p, static_cast<std::uint32_t>(i % b.t.size()));
      ASSERT_NEAR(q.distance, ref.distance, 1e-12) << "shape " << shape << " at " << p.transpose();
      ASSERT_NEAR((q.closest - ref.closest.point).norm(), 0, 1e-9);
    }
  }
}

TEST(CollisionPass, GarmentPushedIntoSphereComesOutAtItsEncodedClearance) {
  const double r = 0.3, c = 0.006;
  const auto s = make_scene(sphere_body(r));
  Patch g = sphere_cap(r + c);
  auto enc = encode_clearance(g.p, s->cb);
  ASSERT_TRUE(enc);
  const auto d0 = bvh_distances(s->bvh, g.p);
  for (std::size_t v = 0; v < g.p.size(); ++v) ASSERT_NEAR(enc->clearance[v], d0[v], 1e-6);
  // Push a disc of the garment 1 cm into the sphere (a bump inward).
  const Vec3d centre = g.p[12 * 24 + 12];
  std::size_t pushed_in = 0;
  for (auto& q : g.p) {
    const double w = std::max(0.0, 1 - (q - centre).norm() / 0.06);
    q *= (r + c - 0.016 * w) / (r + c);
    pushed_in += w > 0.4;
  }
  const auto before = bvh_distances(s->bvh, g.p);
  std::size_t inside0 = 0;
  for (double x : before) inside0 += x < 0;
  ASSERT_GT(inside0, 10u);
  CollisionParams prm;
  auto rep = resolve_collisions(g.p, g.adj, *enc, s->cb, prm);
  ASSERT_TRUE(rep) << rep.status().to_string();
  EXPECT_EQ(rep->inside_before, inside0);
  EXPECT_EQ(rep->inside_after, 0u);
  EXPECT_GE(rep->pushed, pushed_in);
  const auto after = bvh_distances(s->bvh, g.p);
  double rms = 0;
  for (std::size_t v = 0; v < g.p.size(); ++v) {
    // Never below the encoded clearance; fairing may lift, not by much.
    ASSERT_GE(after[v], enc->clearance[v] - prm.tolerance - 1e-9) << v;
    rms += (after[v] - enc->clearance[v]) * (after[v] - enc->clearance[v]);
  }
  rms = std::sqrt(rms / g.p.size());
  EXPECT_LT(rms, 0.001);
  EXPECT_EQ(rep->inside_after, 0u);
}

TEST(CollisionPass, CapsuleTubeSqueezedInsideComesOutAtItsClearance) {
  const double r = 0.1, c = 0.004;
  const auto s = make_scene(capsule(r, 0.25, 48, 8, 30));
  Patch g = grid_patch(40, 30, true, [&](int i, int j) {
    const double ph = 2 * M_PI * (i + 0.25) / 40, z = -0.2 + 0.4 * j / 29;
    return Vec3d((r + c) * std::cos(ph), (r + c) * std::sin(ph), z);
  });
  auto enc = encode_clearance(g.p, s->cb);
  ASSERT_TRUE(enc);
  // Squeeze the middle of the tube into the capsule (a belt pulled tight).
  for (auto& q : g.p) {
    const double k = 1 - 0.12 * std::max(0.0, 1 - std::abs(q.z()) / 0.08);
    q.x() *= k;
    q.y() *= k;
  }
  std::vector<BodyDistance> fin;
  CollisionParams prm;
  prm.fair_rings = 2;  // the smoothing reaches unmoved neighbours too
  auto rep = resolve_collisions(g.p, g.adj, *enc, s->cb, prm, fin);
  ASSERT_TRUE(rep) << rep.status().to_string();
  EXPECT_GT(rep->inside_before, 50u);
  EXPECT_EQ(rep->inside_after, 0u);
  EXPECT_GT(rep->faired, rep->pushed);
  const auto after = bvh_distances(s->bvh, g.p);
  ASSERT_EQ(fin.size(), g.p.size());
  for (std::size_t v = 0; v < g.p.size(); ++v) {
    // The pass's final distances are exact at the final positions (pushed,
    // faired and untouched vertices alike): equal to BodyBvh's.
    ASSERT_NEAR(fin[v].distance, after[v], 1e-9) << v;
    ASSERT_GE(after[v], enc->clearance[v] - prm.tolerance - 1e-9);
    // Radially: back at the tube's radius (the cylinder is exact in z).
    ASSERT_NEAR(std::hypot(g.p[v].x(), g.p[v].y()), r + c, 0.0015) << v;
  }
}

TEST(CollisionPass, VerticesAlreadyOutsideAreNotMoved) {
  const double r = 0.3;
  const auto s = make_scene(sphere_body(r));
  Patch g = sphere_cap(r + 0.02);
  ClearanceEncoding enc;
  enc.clearance.assign(g.p.size(), 0.005f);  // a looser fit than the target everywhere
  const auto before = g.p;
  auto rep = resolve_collisions(g.p, g.adj, enc, s->cb, CollisionParams{});
  ASSERT_TRUE(rep);
  EXPECT_EQ(rep->pushed, 0u);
  EXPECT_EQ(rep->faired, 0u);
  for (std::size_t v = 0; v < g.p.size(); ++v) ASSERT_EQ(g.p[v], before[v]);
}

TEST(CollisionPass, NeverIncreasesPenetratingVerticesOnRandomPerturbations) {
  const auto s = make_scene(capsule(0.1, 0.15, 40, 8, 16));
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    SplitMix64 rng(seed);
    Patch g = grid_patch(32, 24, true, [&](int i, int j) {
      const double ph = 2 * M_PI * i / 32, z = -0.22 + 0.44 * j / 23;
      const double rho = 0.1 + rng.uniform(-0.004, 0.012);
      return Vec3d(rho * std::cos(ph), rho * std::sin(ph), z);
    });
    // Encoded on the unperturbed capsule: clearances from 0 to 12 mm, some negative.
    auto enc = encode_clearance(g.p, s->cb);
    ASSERT_TRUE(enc);
    for (auto& q : g.p) q += Vec3d(rng.normal(), rng.normal(), rng.normal()) * 0.006;
    const auto d0 = bvh_distances(s->bvh, g.p);
    const auto start = g.p;
    CollisionParams prm;
    prm.min_clearance = seed % 2 ? 0.0 : 0.001;
    prm.fair_iterations = std::array{0, 10, 200}[seed % 3];  // 200: the smoothing stays stable
    auto rep = resolve_collisions(g.p, g.adj, *enc, s->cb, prm);
    ASSERT_TRUE(rep);
    const auto d1 = bvh_distances(s->bvh, g.p);
    std::size_t in0 = 0, in1 = 0;
    for (std::size_t v = 0; v < g.p.size(); ++v) {
      in0 += d0[v] < 0;
      in1 += d1[v] < 0;
      // No vertex ends deeper (or nearer) than it started unless at its target.
      const double target = std::max(prm.min_clearance, static_cast<double>(enc->clearance[v]));
      ASSERT_TRUE(d1[v] >= std::min(d0[v], target - prm.tolerance) - 1e-9) << seed << " " << v;
    }
    EXPECT_LE(in1, in0) << seed;
    // Moves stay on the scale of the penetrations (a few noise sigmas).
    double max_move = 0;
    for (std::size_t v = 0; v < g.p.size(); ++v) max_move = std::max(max_move, (g.p[v] - start[v]).norm());
    EXPECT_LT(max_move, 0.03) << seed << " max move " << max_move;
    EXPECT_EQ(in1, 0u) << seed;
    EXPECT_EQ(rep->inside_after, in1);
  }
}

TEST(CollisionPass, SameResultForAnyThreadCount) {
  const double r = 0.3;
  const auto s = make_scene(sphere_body(r));
  Patch g = sphere_cap(r + 0.003, 60);
  auto enc = encode_clearance(g.p, s->cb);
  ASSERT_TRUE(enc);
  SplitMix64 rng(3);
  for (auto& q : g.p) q *= 1 + rng.uniform(-0.04, 0.01);
  auto a = g.p, b = g.p;
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 1;
  two.grain = 7;
  auto ra = resolve_collisions(a, g.adj, *enc, s->cb, CollisionParams{}, one);
  auto rb = resolve_collisions(b, g.adj, *enc, s->cb, CollisionParams{}, two);
  ASSERT_TRUE(ra && rb);
  EXPECT_GT(ra->pushed, 100u);
  EXPECT_EQ(ra->queries, rb->queries);
  for (std::size_t v = 0; v < a.size(); ++v) ASSERT_EQ(a[v], b[v]) << v;
}

TEST(CollisionPass, LayersStayOrderedInnerFirst) {
  const double r = 0.3;
  const auto s = make_scene(sphere_body(r));
  // Inner: a tight shirt at 4 mm. Outer: a jacket encoded at 1 mm, so on its
  // own it would sit inside the shirt; it must end outside it.
  Patch inner = sphere_cap(r + 0.004, 30), outer = sphere_cap(r + 0.001, 20);
  auto ei = encode_clearance(inner.p, s->cb), eo = encode_clearance(outer.p, s->cb);
  ASSERT_TRUE(ei && eo);
  // Push parts of both into the body.
  for (auto& q : inner.p) q *= q.z() > 0.2 ? 0.97 : 1.0;
  for (auto& q : outer.p) q *= q.x() > 0.2 ? 0.98 : 1.0;
  CollisionParams prm;
  prm.layer_gap = 0.002;
  // Given outer first: the z_depth order must win.
  std::vector<GarmentLayer> layers = {{outer.p, &outer.adj, &*eo, 60}, {inner.p, &inner.adj, &*ei, 50}};
  auto reps = resolve_layers(layers, s->cb, prm);
  ASSERT_TRUE(reps) << reps.status().to_string();
  ASSERT_EQ(reps->size(), 2u);
  EXPECT_EQ((*reps)[0].inside_after, 0u);
  EXPECT_EQ((*reps)[1].inside_after, 0u);
  // Inner shell radius in the direction of each outer vertex: the inner cap
  // is a smooth radial height field; take its nearest vertex by direction.
  const auto di = bvh_distances(s->bvh, inner.p), dout = bvh_distances(s->bvh, outer.p);
  std::size_t covered = 0;
  for (std::size_t v = 0; v < outer.p.size(); ++v) {
    const Vec3d dir = outer.p[v].normalized();
    double best = -1;
    std::size_t bi = 0;
    for (std::size_t i = 0; i < inner.p.size(); ++i)
      if (const double cs = inner.p[i].normalized().dot(dir); cs > best) {
        best = cs;
        bi = i;
      }
    if (best < std::cos(0.01)) continue;  // outside the shirt's cap
    ++covered;
    EXPECT_GE(dout[v], di[bi] + prm.layer_gap - 0.0005) << v;
  }
  EXPECT_GT(covered, 100u);
  // Alone, the jacket would stay at its own 1 mm clearance, inside the shirt.
  Patch alone = sphere_cap(r + 0.001, 20);
  ASSERT_TRUE(resolve_collisions(alone.p, alone.adj, *eo, s->cb, prm));
  EXPECT_LT(bvh_distances(s->bvh, alone.p)[0], 0.002);
}

TEST(CollisionPass, BadInputsGiveClearErrors) {
  // Open body: a sphere with one triangle removed.
  TriBody open = sphere_body(0.3);
  open.t.pop_back();
  auto topo = CollisionTopology::build(open.t, static_cast<std::uint32_t>(open.p.size()));
  ASSERT_FALSE(topo);
  EXPECT_EQ(topo.status().code(), ErrorCode::kTopology);
  EXPECT_NE(topo.status().message().find("not closed"), std::string::npos) << topo.status().message();
  // Inconsistent orientation: one triangle flipped.
  TriBody flipped = sphere_body(0.3);
  std::swap(flipped.t[5][1], flipped.t[5][2]);
  EXPECT_FALSE(CollisionTopology::build(flipped.t, static_cast<std::uint32_t>(flipped.p.size())));
  EXPECT_FALSE(CollisionTopology::build({}, 0));
  TriBody bad = sphere_body(0.3);
  bad.t[0][0] = 1'000'000;
  auto t2 = CollisionTopology::build(bad.t, static_cast<std::uint32_t>(bad.p.size()));
  ASSERT_FALSE(t2);
  EXPECT_NE(t2.status().message().find("triangle 0"), std::string::npos);

  const auto s = make_scene(sphere_body(0.3));
  std::vector<Vec3d> wrong(3);
  EXPECT_EQ(CollisionBody().build(s->topo, wrong).code(), ErrorCode::kMismatch);
  // Empty garment.
  std::vector<Vec3d> none;
  NodeAdjacency empty_adj;
  empty_adj.offset = {0};
  auto e1 = encode_clearance(none, s->cb);
  ASSERT_FALSE(e1);
  EXPECT_NE(e1.status().message().find("empty garment"), std::string::npos);
  auto r1 = resolve_collisions(none, empty_adj, ClearanceEncoding{}, s->cb, CollisionParams{});
  ASSERT_FALSE(r1);
  EXPECT_NE(r1.status().message().find("empty garment"), std::string::npos);
  // Sizes that do not match, bad parameters, unbuilt body, NaN vertex.
  Patch g = sphere_cap(0.31, 8);
  auto enc = encode_clearance(g.p, s->cb);
  ASSERT_TRUE(enc);
  ClearanceEncoding short_enc = *enc;
  short_enc.clearance.pop_back();
  EXPECT_EQ(resolve_collisions(g.p, g.adj, short_enc, s->cb, {}).status().code(), ErrorCode::kMismatch);
  CollisionParams neg;
  neg.min_clearance = -1;
  EXPECT_EQ(resolve_collisions(g.p, g.adj, *enc, s->cb, neg).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_FALSE(resolve_collisions(g.p, g.adj, *enc, CollisionBody(), {}));
  g.p[3].x() = std::nan("");
  auto r2 = resolve_collisions(g.p, g.adj, *enc, s->cb, {});
  ASSERT_FALSE(r2);
  EXPECT_NE(r2.status().message().find("vertex 3"), std::string::npos);
  const std::array<std::uint32_t, 2> out_of_range[] = {{0, 99}};
  EXPECT_FALSE(adjacency_from_edges(10, out_of_range));
}
