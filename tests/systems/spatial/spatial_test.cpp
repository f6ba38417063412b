// Spatial queries (systems/body_bvh.h, systems/sdf_grid.h) against analytic
// bodies built here (UV sphere, capsule, torus), brute force over all
// triangles, and the generalized winding number as an independent inside
// oracle near the surface.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <numbers>
#include <tuple>
#include <vector>

#include <atelier/storage/builder.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/spatial/sdf_grid.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/mesh/fan_triangulation.h>

namespace atelier {
namespace {


// Tiny deterministic generator (SplitMix64).
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform(double lo = 0.0, double hi = 1.0) { return lo + (hi - lo) * double(next() >> 11) * 0x1.0p-53; }
  Vec3d in_box(const Box3d& b) { return {uniform(b.lo.x(), b.hi.x()), uniform(b.lo.y(), b.hi.y()), uniform(b.lo.z(), b.hi.z())}; }
  Vec3d direction() {
    for (;;) {
      const Vec3d v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const double n = v.norm();
      if (n > 0.1 && n <= 1.0) return v / n;
    }
  }
};

/// A triangle mesh with its analytic signed distance.
struct Body {
  std::vector<Vec3d> positions;
  std::vector<Triangle> triangles;
  std::function<double(const Vec3d&)> sdf;  // analytic, negative inside
  double approx = 0.0;                      // bound on |mesh sdf - analytic sdf|
  Box3d box;

  void finish() {
    for (const Vec3d& p : positions) box.extend(p);
    // The mesh is inscribed: the deviation is largest inside faces and on
    // edges; twice the largest deviation of centroids and edge midpoints is
    // a safe bound for these smooth, finely sampled shapes.
    double dev = 0.0;
    for (const Triangle& t : triangles) {
      const Vec3d& a = positions[t[0]];
      const Vec3d& b = positions[t[1]];
      const Vec3d& c = positions[t[2]];
      for (const Vec3d& q : {Vec3d((a + b + c) / 3.0), Vec3d((a + b) / 2), Vec3d((b + c) / 2), Vec3d((c + a) / 2)}) {
        dev = std::max(dev, std::abs(sdf(q)));
      }
    }
    approx = 2.0 * dev + 1e-12;
  }
};

/// Surface of revolution about z: rings (rho, z) from top to bottom between
/// two poles; faces counter-clockwise seen from outside.
Body revolve(const Vec3d& center, double z_top, double z_bottom, const std::vector<std::array<double, 2>>& rings,
             int n_lon) {
  Body b;
  b.positions.push_back(center + Vec3d(0, 0, z_top));
  for (const auto& r : rings) {
    for (int j = 0; j < n_lon; ++j) {
      const double phi = 2.0 * kPi * j / n_lon;
      b.positions.push_back(center + Vec3d(r[0] * std::cos(phi), r[0] * std::sin(phi), r[1]));
    }
  }
  b.positions.push_back(center + Vec3d(0, 0, z_bottom));
  const auto n_rings = static_cast<std::uint32_t>(rings.size());
  const std::uint32_t south = static_cast<std::uint32_t>(b.positions.size() - 1);
  auto id = [&](std::uint32_t i, int j) { return 1 + i * n_lon + static_cast<std::uint32_t>((j + n_lon) % n_lon); };
  for (int j = 0; j < n_lon; ++j) b.triangles.push_back({0, id(0, j), id(0, j + 1)});
  for (std::uint32_t i = 0; i + 1 < n_rings; ++i) {
    for (int j = 0; j < n_lon; ++j) {
      b.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      b.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  for (int j = 0; j < n_lon; ++j) b.triangles.push_back({id(n_rings - 1, j), south, id(n_rings - 1, j + 1)});
  return b;
}

Body uv_sphere(const Vec3d& c, double r, int n_lat, int n_lon) {
  std::vector<std::array<double, 2>> rings;
  for (int i = 1; i < n_lat; ++i) {
    const double th = kPi * i / n_lat;
    rings.push_back({r * std::sin(th), r * std::cos(th)});
  }
  Body b = revolve(c, r, -r, rings, n_lon);
  b.sdf = [c, r](const Vec3d& p) { return (p - c).norm() - r; };
  b.finish();
  return b;
}

/// Capsule: cylinder of radius r between z = -h and z = +h with hemispherical caps.
Body capsule(const Vec3d& c, double r, double h, int n_half, int n_cyl, int n_lon) {
  std::vector<std::array<double, 2>> rings;
  for (int i = 1; i <= n_half; ++i) {
    const double th = 0.5 * kPi * i / n_half;
    rings.push_back({r * std::sin(th), h + r * std::cos(th)});
  }
  for (int i = 1; i < n_cyl; ++i) rings.push_back({r, h - 2.0 * h * i / n_cyl});
  for (int i = 0; i < n_half; ++i) {
    const double th = 0.5 * kPi + 0.5 * kPi * i / n_half;
    rings.push_back({r * std::sin(th), -h + r * std::cos(th)});
  }
  Body b = revolve(c, h + r, -h - r, rings, n_lon);
  b.sdf = [c, r, h](const Vec3d& p) {
    const Vec3d q = p - c;
    const double z = std::clamp(q.z(), -h, h);
    return (q - Vec3d(0, 0, z)).norm() - r;
  };
  b.finish();
  return b;
}

Body torus(const Vec3d& c, double big, double small, int nu, int nv) {
  Body b;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      b.positions.push_back(c + Vec3d((big + small * std::cos(v)) * std::cos(u),
                                      (big + small * std::cos(v)) * std::sin(u), small * std::sin(v)));
    }
  }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      b.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      b.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  b.sdf = [c, big, small](const Vec3d& p) {
    const Vec3d q = p - c;
    const double rho = std::hypot(q.x(), q.y()) - big;
    return std::hypot(rho, q.z()) - small;
  };
  b.finish();
  return b;
}

Box3d grown(const Box3d& b, double r) {
  Box3d g = b;
  g.lo.array() -= r;
  g.hi.array() += r;
  return g;
}

ClosestHit brute_closest(const Body& b, const Vec3d& p) {
  ClosestHit best;
  for (std::uint32_t t = 0; t < b.triangles.size(); ++t) {
    const auto& tr = b.triangles[t];
    const TrianglePoint r = closest_point_on_triangle(p, b.positions[tr[0]], b.positions[tr[1]], b.positions[tr[2]]);
    const double d = (p - r.point).norm();
    if (d < best.distance) best = {r.point, r.barycentric, d, t, r.feature};
  }
  return best;
}

/// Inside oracle for a point: the analytic sign when the point is farther
/// from the analytic surface than the mesh deviates, else the winding number
/// of the mesh by brute force (an algorithm independent of pseudo-normals).
bool oracle_inside(const Body& b, const BodyBvh& bvh, const Vec3d& p) {
  const double s = b.sdf(p);
  if (std::abs(s) > b.approx) return s < 0.0;
  const double w = bvh.winding_number(p);
  EXPECT_TRUE(std::abs(w - 0.5) > 0.25) << "point too close to the mesh for a winding-number verdict";
  return w > 0.5;
}

BodyBvh make_bvh(const Body& b, const BvhParams& params = {}) {
  BodyBvh bvh;
  const Status s = bvh.build(b.positions, b.triangles, params);
  EXPECT_TRUE(s.is_ok()) << s.to_string();
  return bvh;
}

/// Points: half uniform in the grown box, half within `near` of the surface
/// along the analytic gradient-free radial direction (projected by sampling).
std::vector<Vec3d> sample_points(const Body& b, std::size_t n, double near, std::uint64_t seed, double grow = 0.3) {
  Rng rng{seed};
  std::vector<Vec3d> pts;
  const Box3d box = grown(b.box, grow * (b.box.hi - b.box.lo).maxCoeff());
  while (pts.size() < n) {
    const Vec3d p = rng.in_box(box);
    if (pts.size() % 2 == 0 || std::abs(b.sdf(p)) < near) pts.push_back(p);
  }
  return pts;
}

// ---------------------------------------------------------------- geometry

TEST(Spatial, PointTriangleMatchesProjectionOrEdges) {
  // Independent closest point: projection on the plane when it falls inside
  // the triangle, else the best of the three segment projections.
  Rng rng{7};
  auto seg = [](const Vec3d& p, const Vec3d& a, const Vec3d& b) {
    const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    return Vec3d(a + t * (b - a));
  };
  for (int it = 0; it < 20000; ++it) {
    const Vec3d a = rng.in_box({{-1, -1, -1}, {1, 1, 1}});
    const Vec3d b = rng.in_box({{-1, -1, -1}, {1, 1, 1}});
    const Vec3d c = rng.in_box({{-1, -1, -1}, {1, 1, 1}});
    const Vec3d p = rng.in_box({{-2, -2, -2}, {2, 2, 2}});
    const Vec3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-3) continue;
    const Vec3d q = p - n * (p - a).dot(n) / n.squaredNorm();
    const double area = n.norm();
    const double u = (b - q).cross(c - q).dot(n) / (area * area);
    const double v = (c - q).cross(a - q).dot(n) / (area * area);
    const double w = 1.0 - u - v;
    Vec3d expect;
    if (u >= 0 && v >= 0 && w >= 0) {
      expect = q;
    } else {
      const Vec3d s0 = seg(p, a, b), s1 = seg(p, b, c), s2 = seg(p, c, a);
      expect = s0;
      if ((p - s1).norm() < (p - expect).norm()) expect = s1;
      if ((p - s2).norm() < (p - expect).norm()) expect = s2;
    }
    const TrianglePoint r = closest_point_on_triangle(p, a, b, c);
    ASSERT_NEAR((p - r.point).norm(), (p - expect).norm(), 1e-12) << it;
    ASSERT_LT((r.point - (r.barycentric[0] * a + r.barycentric[1] * b + r.barycentric[2] * c)).norm(), 1e-12);
    ASSERT_NEAR(r.barycentric.sum(), 1.0, 1e-12);
  }
  // Degenerate triangle (collinear corners) falls back on its edges.
  const TrianglePoint r = closest_point_on_triangle({0.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0});
  EXPECT_NEAR((r.point - Vec3d(0.5, 0, 0)).norm(), 0.0, 1e-15);
}

// ---------------------------------------------------------- closest points

TEST(Spatial, ClosestPointMatchesBruteForce) {
  const Body sphere = uv_sphere({0.3, -0.2, 0.5}, 1.0, 100, 100);
  ASSERT_EQ(sphere.triangles.size(), 19800u);
  const BodyBvh bvh = make_bvh(sphere);
  ASSERT_TRUE(bvh.closed());
  const Body tor = torus({0, 0, 0}, 1.0, 0.3, 120, 40);
  const BodyBvh tbvh = make_bvh(tor);
  for (const auto& [body, tree] : {std::pair{&sphere, &bvh}, std::pair{&tor, &tbvh}}) {
    const std::vector<Vec3d> pts = sample_points(*body, 3000, 0.05, 11, 1.0);
    std::vector<ClosestHit> hits(pts.size());
    ASSERT_TRUE(tree->closest_points(pts, hits).is_ok());
    const double scale = (body->box.hi - body->box.lo).maxCoeff();
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const ClosestHit e = brute_closest(*body, pts[i]);
      ASSERT_NEAR(hits[i].distance, e.distance, 1e-9 * std::max(1.0, e.distance)) << i;
      ASSERT_LT((hits[i].point - e.point).norm(), 1e-9 * scale) << i;
      ASSERT_EQ(hits[i].triangle, e.triangle) << "ties go to the smallest index, point " << i;
      ASSERT_EQ(hits[i].feature, e.feature);
      // A distance bound (right or wrong) changes the cost, not the answer.
      for (double f : {0.5, 1.0, 1.0 + 1e-12, 3.0}) {
        const ClosestHit b = tree->closest_point(pts[i], f * e.distance);
        ASSERT_EQ(b.triangle, e.triangle) << i << " bound factor " << f;
        ASSERT_EQ(b.distance, hits[i].distance);
      }
    }
  }
}

// --------------------------------------------------------- signed distance

TEST(Spatial, SignedDistanceMatchesAnalyticBodies) {
  const std::vector<Body> bodies = {uv_sphere({0.1, 0.2, -0.3}, 1.0, 100, 100),
                                    capsule({0, 0, 0}, 0.4, 0.6, 24, 30, 96), torus({0, 0, 0.1}, 1.0, 0.35, 160, 48)};
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const Body& b = bodies[k];
    const BodyBvh bvh = make_bvh(b);
    ASSERT_TRUE(bvh.closed()) << k;
    // Many points close to the surface: within 3 times the mesh deviation.
    const std::vector<Vec3d> pts = sample_points(b, 4000, 3.0 * b.approx, 100 + k);
    std::vector<double> sd(pts.size());
    ASSERT_TRUE(bvh.signed_distances(pts, sd).is_ok());
    std::size_t near = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double analytic = b.sdf(pts[i]);
      ASSERT_NEAR(sd[i], analytic, b.approx) << "body " << k << " point " << i;
      if (std::abs(sd[i]) <= 1e-6) continue;  // on the mesh: no sign to check
      near += std::abs(analytic) <= b.approx;
      ASSERT_EQ(sd[i] < 0.0, oracle_inside(b, bvh, pts[i])) << "body " << k << " point " << i << " sd " << sd[i];
      const SignedHit h = bvh.signed_distance(pts[i]);
      ASSERT_EQ(h.distance, sd[i]);
      ASSERT_NEAR(h.normal.norm(), 1.0, 1e-12);
    }
    EXPECT_GT(near, 100u) << "the sample must probe the ambiguous band";
  }
}

TEST(Spatial, PseudoNormalSignAtVerticesAndEdges) {
  // Points straight off vertices and edge midpoints of the torus (both the
  // convex outer side and the saddle-shaped inner side): the closest feature
  // is a vertex or an edge, where a face normal alone can give the wrong sign.
  const Body tor = torus({0, 0, 0}, 1.0, 0.35, 40, 16);
  const BodyBvh bvh = make_bvh(tor);
  std::size_t vertex_hits = 0, edge_hits = 0;
  for (const Triangle& t : tor.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Vec3d& a = tor.positions[t[k]];
      const Vec3d& b = tor.positions[t[(k + 1) % 3]];
      for (const Vec3d& base : {a, Vec3d((a + b) / 2)}) {
        const Vec3d q = base;
        const Vec3d rc(q.x(), q.y(), 0);
        const Vec3d ring = rc.normalized() * 1.0;
        const Vec3d n = (q - ring).normalized();  // analytic outward normal
        for (double off : {-0.01, 0.01}) {
          const Vec3d p = q + off * n;
          const SignedHit h = bvh.signed_distance(p);
          ASSERT_EQ(h.distance < 0.0, bvh.winding_number(p) > 0.5);
          ASSERT_EQ(h.distance < 0.0, off < 0.0);
          vertex_hits += h.closest.feature <= TriFeature::kVertex2;
          edge_hits += h.closest.feature >= TriFeature::kEdge01 && h.closest.feature <= TriFeature::kEdge20;
        }
      }
    }
  }
  EXPECT_GT(vertex_hits, 0u);
  EXPECT_GT(edge_hits, 0u);
}

TEST(Spatial, WindingNumberIsOneInsideZeroOutside) {
  const Body tor = torus({0, 0, 0}, 1.0, 0.3, 60, 24);
  const BodyBvh bvh = make_bvh(tor);
  const std::vector<Vec3d> pts = sample_points(tor, 400, 0.1, 5);
  std::vector<double> w(pts.size());
  ASSERT_TRUE(bvh.winding_numbers(pts, w).is_ok());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const double s = tor.sdf(pts[i]);
    if (std::abs(s) <= tor.approx) continue;
    EXPECT_NEAR(w[i], s < 0 ? 1.0 : 0.0, 1e-6) << i;
  }
}

// --------------------------------------------------------------------- rays

TEST(Spatial, RayHitsMatchAnalyticSphere) {
  const Vec3d c(0.2, 0.1, -0.4);
  const double r = 1.0;
  const Body sphere = uv_sphere(c, r, 100, 100);
  const BodyBvh bvh = make_bvh(sphere);
  Rng rng{21};
  std::size_t hits = 0, misses = 0;
  for (int i = 0; i < 5000; ++i) {
    // From outside, aimed at a random point of a ball of radius 1.5 r.
    const Vec3d o = c + 3.0 * rng.direction();
    const Vec3d target = c + 1.5 * r * rng.uniform() * rng.direction();
    const Vec3d d = (target - o).normalized();
    // Analytic: |o + t d - c| = r.
    const Vec3d oc = o - c;
    const double bq = oc.dot(d), cq = oc.squaredNorm() - r * r, disc = bq * bq - cq;
    const RayHit h = bvh.ray_first_hit(o, d);
    const double miss_margin = std::sqrt(std::max(0.0, -disc)) ;
    if (disc < 0.0) {
      // The inscribed mesh lies inside the sphere: an analytic miss is a miss.
      ASSERT_FALSE(h.hit) << i << " " << miss_margin;
      ++misses;
      continue;
    }
    const double t_analytic = -bq - std::sqrt(disc);
    const double cos_incidence = std::sqrt(disc) / r;  // |d . n| at the analytic hit
    if (cos_incidence < 0.2) continue;                 // grazing: the inscribed mesh may be missed
    ASSERT_TRUE(h.hit) << i;
    ++hits;
    ASSERT_GE(h.t, t_analytic - 1e-9) << i;  // the mesh is inside the sphere
    ASSERT_LE(h.t - t_analytic, sphere.approx / cos_incidence + 1e-9) << i;
    ASSERT_LT(bvh.closest_point(h.point).distance, 1e-9) << "the hit point lies on the mesh";
    ASSERT_GT(h.normal.dot(-d), 0.0) << "outside rays hit front faces";
  }
  EXPECT_GT(hits, 1000u);
  EXPECT_GT(misses, 100u);
  // From inside, every ray hits at the analytic distance.
  for (int i = 0; i < 2000; ++i) {
    const Vec3d o = c + 0.5 * r * rng.uniform() * rng.direction();
    const Vec3d d = rng.direction() * 2.5;  // non-unit direction: t in units of d
    const Vec3d oc = o - c;
    const double a2 = d.squaredNorm(), bq = oc.dot(d), cq = oc.squaredNorm() - r * r;
    const double t_analytic = (-bq + std::sqrt(bq * bq - a2 * cq)) / a2;
    const RayHit h = bvh.ray_first_hit(o, d);
    ASSERT_TRUE(h.hit);
    ASSERT_LE(h.t, t_analytic + 1e-12);
    ASSERT_GE(h.t, t_analytic - 2.0 * sphere.approx / d.norm());
    EXPECT_FALSE(bvh.ray_first_hit(o, d, 0.5 * h.t).hit) << "tmax cuts the ray";
  }
}

// ------------------------------------------------------------------ SdfGrid

TEST(Spatial, SdfGridInsideHasNoWrongAnswers) {
  const Body sphere = uv_sphere({0.05, -0.1, 0.2}, 1.0, 100, 100);
  const BodyBvh bvh = make_bvh(sphere);
  SdfParams params;
  params.voxel_size = 0.02;  // 100 voxels across
  SdfGrid grid;
  ASSERT_TRUE(grid.build(bvh, params).is_ok());
  EXPECT_GT(grid.stats().active_voxels, 0u);
  EXPECT_EQ(grid.stats().source_triangles, sphere.triangles.size());
  // 100k points, half of them within one voxel of the surface.
  const std::vector<Vec3d> pts = sample_points(sphere, 100000, params.voxel_size, 3);
  std::vector<std::uint8_t> in(pts.size());
  std::vector<double> d(pts.size());
  InsideStats st;
  ASSERT_TRUE(grid.inside_many(pts, in, {}, &st).is_ok());
  ASSERT_TRUE(grid.sample_many(pts, d, {}).is_ok());
  EXPECT_GT(st.exact, 1000u);
  EXPECT_GT(st.from_grid, 40000u);
  std::size_t wrong = 0, raw_wrong = 0, within_voxel = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const bool truth = oracle_inside(sphere, bvh, pts[i]);
    within_voxel += std::abs(sphere.sdf(pts[i])) < params.voxel_size;
    wrong += (in[i] != 0) != truth;
    if ((d[i] < 0.0) != truth) {
      ++raw_wrong;
      // The raw trilinear sign may only be wrong close to the surface.
      ASSERT_LT(std::abs(sphere.sdf(pts[i])), std::sqrt(3.0) * params.voxel_size + sphere.approx) << i;
    }
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_GT(within_voxel, 40000u);
  std::printf("[ sdf ] %zu exact fallbacks, %zu from the grid, raw trilinear sign wrong for %zu points\n", st.exact,
              st.from_grid, raw_wrong);
  // Single-point paths agree with the batched ones.
  SdfGrid::Sampler s = grid.sampler();
  for (std::size_t i = 0; i < 2000; ++i) {
    ASSERT_EQ(s.inside(pts[i]), in[i] != 0);
    ASSERT_EQ(grid.inside(pts[i]), in[i] != 0);
    ASSERT_EQ(s.sample(pts[i]), d[i]);
  }
}

TEST(Spatial, SdfGridOnTorusAndRoiMatchesFullGrid) {
  const Body tor = torus({0, 0, 0}, 1.0, 0.35, 160, 48);
  const BodyBvh bvh = make_bvh(tor);
  SdfParams params;
  params.voxel_size = 0.025;
  params.half_width = 5.0;
  SdfGrid full;
  ASSERT_TRUE(full.build(bvh, params).is_ok());
  // The ROI straddles the tube on the +x side, through the hole and outside.
  SdfParams roi_params = params;
  roi_params.roi = {Box3d{{0.3, -0.5, -0.6}, {1.6, 0.4, 0.6}}, Box3d{{-0.5, 0.8, -0.2}, {0.5, 1.5, 0.5}}};
  SdfGrid roi;
  ASSERT_TRUE(roi.build(bvh, roi_params).is_ok());
  EXPECT_LT(roi.stats().source_triangles, full.stats().source_triangles / 2);
  EXPECT_LT(roi.stats().active_voxels, full.stats().active_voxels);
  Rng rng{77};
  std::vector<Vec3d> pts;
  for (const Box3d& b : roi_params.roi) {
    for (int i = 0; i < 25000; ++i) {
      Vec3d p = rng.in_box(b);
      if (i % 2) {  // pull half of them near the surface
        for (int k = 0; k < 50 && std::abs(tor.sdf(p)) > 2 * params.voxel_size; ++k) p = rng.in_box(b);
      }
      pts.push_back(p);
    }
  }
  std::vector<std::uint8_t> a(pts.size()), b(pts.size());
  InsideStats sa, sb;
  ASSERT_TRUE(full.inside_many(pts, a, {}, &sa).is_ok());
  ASSERT_TRUE(roi.inside_many(pts, b, {}, &sb).is_ok());
  std::size_t wrong_full = 0, wrong_roi = 0, differ = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_TRUE(roi.covers(pts[i]));
    const bool truth = oracle_inside(tor, bvh, pts[i]);
    wrong_full += (a[i] != 0) != truth;
    wrong_roi += (b[i] != 0) != truth;
    differ += a[i] != b[i];
  }
  EXPECT_EQ(wrong_full, 0u);
  EXPECT_EQ(wrong_roi, 0u);
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(sb.from_grid, pts.size() / 4) << "the ROI grid must answer most queries itself";
  std::printf("[ roi ] full grid: %zu exact, %zu from grid; ROI grid (%zu of %zu triangles): %zu exact, %zu from grid\n",
              sa.exact, sa.from_grid, roi.stats().source_triangles, full.stats().source_triangles, sb.exact,
              sb.from_grid);
  // Inside the band both grids interpolate (nearly) the exact signed
  // distances of the voxel centres (trilinear of BodyBvh::signed_distance at
  // the 8 corners).
  std::size_t compared = 0;
  double err_full[2] = {0, 0}, err_roi[2] = {0, 0};
  const double h = params.voxel_size;
  for (const Vec3d& p : pts) {
    const double s = std::abs(tor.sdf(p));
    if (!(s < (params.half_width - 2) * h)) continue;
    const int layer = s < 1.5 * h ? 0 : 1;
    const Vec3d g = p / h;
    const Vec3d f(std::floor(g.x()), std::floor(g.y()), std::floor(g.z()));
    const Vec3d t = g - f;
    double expect = 0.0;
    for (int k = 0; k < 8; ++k) {
      const Vec3d o((k >> 2) & 1, (k >> 1) & 1, k & 1);
      const double wgt = (o.x() ? t.x() : 1 - t.x()) * (o.y() ? t.y() : 1 - t.y()) * (o.z() ? t.z() : 1 - t.z());
      expect += wgt * bvh.signed_distance((f + o) * h).distance;
    }
    err_full[layer] = std::max(err_full[layer], std::abs(full.sample(p) - expect));
    err_roi[layer] = std::max(err_roi[layer], std::abs(roi.sample(p) - expect));
    ++compared;
  }
  std::printf("[ roi ] max |trilinear - trilinear of exact voxel values| / h, within 1.5 h of the surface: full %.3g, "
              "roi %.3g; farther: full %.3g, roi %.3g\n",
              err_full[0] / h, err_roi[0] / h, err_full[1] / h, err_roi[1] / h);
  EXPECT_GT(compared, 1000u);
  // OpenVDB widens the band from each voxel's neighbours' closest triangles,
  // so values off the first layers may overestimate the distance a little
  // (documented in sdf_grid.h); they stay well inside the exact band margin.
  for (int layer = 0; layer < 2; ++layer) {
    EXPECT_LT(err_roi[layer], 0.5 * h);
    EXPECT_LT(err_full[layer], 0.5 * h);
  }
  // Outside the ROI the grid defers to the BVH and stays exact.
  const Vec3d far_inside(-1.0, 0.0, 0.0);
  EXPECT_FALSE(roi.covers(far_inside));
  EXPECT_TRUE(roi.inside(far_inside));
  EXPECT_FALSE(roi.inside(Vec3d(0, 0, 0)));  // the hole
}

// -------------------------------------------------------------- determinism

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(Spatial, BatchedQueriesIdenticalForOneAndTwoThreads) {
  const Body sphere = uv_sphere({0, 0, 0}, 1.0, 60, 80);
  const BodyBvh bvh = make_bvh(sphere);
  SdfParams params;
  params.voxel_size = 0.03;
  SdfGrid grid;
  ASSERT_TRUE(grid.build(bvh, params).is_ok());
  const std::vector<Vec3d> pts = sample_points(sphere, 20000, 0.05, 9);
  ExecContext one = ExecContext::sequential();
  ExecContext two;
  two.threads = 2;
  two.sequential_threshold = 1;
  two.grain = 97;
  auto run = [&](const ExecContext& ctx) {
    std::vector<double> dist, px, sd, sdf;
    std::vector<std::uint32_t> tri;
    std::vector<std::uint8_t> in;
    std::vector<ClosestHit> hits(pts.size());
    EXPECT_TRUE(bvh.closest_points(pts, hits, ctx).is_ok());
    for (const ClosestHit& h : hits) {
      dist.push_back(h.distance);
      px.insert(px.end(), {h.point.x(), h.point.y(), h.point.z(), h.barycentric.x(), h.barycentric.y()});
      tri.push_back(h.triangle);
    }
    sd.resize(pts.size());
    EXPECT_TRUE(bvh.signed_distances(pts, sd, ctx).is_ok());
    sdf.resize(pts.size());
    EXPECT_TRUE(grid.sample_many(pts, sdf, ctx).is_ok());
    in.resize(pts.size());
    EXPECT_TRUE(grid.inside_many(pts, in, ctx).is_ok());
    return std::tuple{dist, px, tri, sd, sdf, in};
  };
  const auto a = run(one);
  const auto b = run(two);
  EXPECT_TRUE(same_bytes(std::get<0>(a), std::get<0>(b)));
  EXPECT_TRUE(same_bytes(std::get<1>(a), std::get<1>(b)));
  EXPECT_TRUE(same_bytes(std::get<2>(a), std::get<2>(b)));
  EXPECT_TRUE(same_bytes(std::get<3>(a), std::get<3>(b)));
  EXPECT_TRUE(same_bytes(std::get<4>(a), std::get<4>(b)));
  EXPECT_TRUE(same_bytes(std::get<5>(a), std::get<5>(b)));
  // A grid built with 1 or 2 threads answers identically.
  SdfGrid grid2;
  ASSERT_TRUE(grid2.build(bvh, params, one).is_ok());
  std::vector<double> s1(pts.size()), s2(pts.size());
  ASSERT_TRUE(grid.sample_many(pts, s1).is_ok());
  ASSERT_TRUE(grid2.sample_many(pts, s2).is_ok());
  EXPECT_TRUE(same_bytes(s1, s2));
}

// --------------------------------------------------------- refit / commit

TEST(Spatial, CommitAfterMovingVerticesMatchesScaledSphere) {
  const Vec3d c(0.1, 0.2, 0.3);
  for (bool refit : {true, false}) {
    Body sphere = uv_sphere(c, 1.0, 60, 80);
    BodyBvh bvh;
    BvhParams params;
    params.refit_on_commit = refit;
    ASSERT_TRUE(bvh.build(sphere.positions, sphere.triangles, params).is_ok());
    EXPECT_FALSE(bvh.zero_copy()) << "doubles are copied to floats for Embree";
    for (Vec3d& p : sphere.positions) p = c + 1.2 * (p - c);
    ASSERT_TRUE(bvh.commit().is_ok());
    Body scaled = uv_sphere(c, 1.2, 60, 80);
    const std::vector<Vec3d> pts = sample_points(scaled, 2000, 0.05, 13);
    for (const Vec3d& p : pts) {
      const SignedHit h = bvh.signed_distance(p);
      ASSERT_NEAR(h.distance, scaled.sdf(p), scaled.approx);
      ASSERT_NEAR(h.closest.distance, brute_closest(scaled, p).distance, 1e-9);
    }
    const RayHit r = bvh.ray_first_hit(c, Vec3d(1, 0, 0));
    ASSERT_TRUE(r.hit);
    EXPECT_NEAR(r.t, 1.2, scaled.approx);
  }
}

TEST(Spatial, ZeroCopyPaddedFloatsFollowCommit) {
  const Vec3d c(0, 0, 0);
  const Body sphere = uv_sphere(c, 1.0, 40, 60);
  // xyzw records: stride 16 bytes, so Embree's 16-byte loads stay inside.
  std::vector<float> xyzw;
  for (const Vec3d& p : sphere.positions) xyzw.insert(xyzw.end(), {float(p.x()), float(p.y()), float(p.z()), 0.f});
  BodyBvh bvh;
  ASSERT_TRUE(bvh.build(StridedPoints::floats(xyzw.data(), 16, sphere.positions.size()), sphere.triangles).is_ok());
  EXPECT_TRUE(bvh.zero_copy());
  // A tightly packed float array is not padded: copied.
  std::vector<Vec3f> packed;
  for (const Vec3d& p : sphere.positions) packed.push_back(p.cast<float>());
  BodyBvh copy;
  ASSERT_TRUE(copy.build(StridedPoints::of(std::span<const Vec3f>(packed)), sphere.triangles).is_ok());
  EXPECT_FALSE(copy.zero_copy());
  for (std::size_t i = 0; i < xyzw.size(); ++i) {
    if (i % 4 != 3) xyzw[i] *= 1.2f;
  }
  ASSERT_TRUE(bvh.commit().is_ok());
  Rng rng{3};
  for (int i = 0; i < 500; ++i) {
    const Vec3d p = 2.0 * rng.direction() * rng.uniform();
    EXPECT_NEAR(bvh.signed_distance(p).distance, p.norm() - 1.2, 0.02);
  }
  // Commit through a new view of the same size.
  std::vector<Vec3d> moved = sphere.positions;
  for (Vec3d& p : moved) p += Vec3d(0, 0, 5);
  ASSERT_TRUE(bvh.commit(StridedPoints::of(std::span<const Vec3d>(moved))).is_ok());
  EXPECT_NEAR(bvh.closest_point(Vec3d(0, 0, 7)).distance, 1.0, 1e-9);  // the pole vertex at z = 6
  EXPECT_EQ(bvh.commit(StridedPoints::of(std::span<const Vec3d>(moved).first(3))).code(), ErrorCode::kMismatch);
}

// --------------------------------------------------------------- Model input

TEST(Spatial, FanTriangulatedModelSurface) {
  // The sphere as quads and cap triangles in a Model, then fan-triangulated.
  const Body sphere = uv_sphere({0, 0, 0}, 1.0, 30, 40);
  std::vector<std::uint32_t> offsets{0}, nodes;
  for (std::size_t t = 0; t < sphere.triangles.size();) {
    const Triangle& a = sphere.triangles[t];
    if (t + 1 < sphere.triangles.size() && sphere.triangles[t + 1][0] == a[0] && sphere.triangles[t + 1][1] == a[2] &&
        a[0] != 0 && a[1] != sphere.positions.size() - 1) {
      const Triangle& b = sphere.triangles[t + 1];
      nodes.insert(nodes.end(), {a[0], a[1], a[2], b[2]});
      t += 2;
    } else {
      nodes.insert(nodes.end(), a.begin(), a.end());
      t += 1;
    }
    offsets.push_back(static_cast<std::uint32_t>(nodes.size()));
  }
  Model m;
  const auto s = add_polygon_surface(m, "sphere", PolygonSoupView{sphere.positions, offsets, nodes});
  ASSERT_TRUE(s.has_value()) << s.status().to_string();
  ASSERT_TRUE(validate(m).is_ok());
  const auto tris = fan_triangulate(m);
  ASSERT_TRUE(tris.has_value());
  EXPECT_EQ(tris->triangles.size(), sphere.triangles.size());
  ASSERT_EQ(tris->face.size(), tris->triangles.size());
  BodyBvh bvh;
  ASSERT_TRUE(bvh.build(std::span<const Vec3d>(m.nodes.position), tris->triangles).is_ok());
  EXPECT_TRUE(bvh.closed());
  const BodyBvh ref = make_bvh(sphere);
  Rng rng{1};
  for (int i = 0; i < 500; ++i) {
    const Vec3d p = rng.in_box({{-2, -2, -2}, {2, 2, 2}});
    EXPECT_NEAR(bvh.closest_point(p).distance, ref.closest_point(p).distance, 1e-12);
    EXPECT_EQ(bvh.inside(p), ref.inside(p));
  }
  const SurfaceIdx dead{99};
  EXPECT_FALSE(fan_triangulate(m, std::span<const SurfaceIdx>(&dead, 1)).has_value());
}

// ----------------------------------------------------------------- bad input

TEST(Spatial, BadInputGivesClearErrors) {
  Body sphere = uv_sphere({0, 0, 0}, 1.0, 10, 12);
  BodyBvh bvh;
  // Empty.
  Status s = bvh.build(std::span<const Vec3d>{}, std::span<const Triangle>{});
  EXPECT_EQ(s.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(s.message().find("empty"), std::string::npos) << s.message();
  EXPECT_TRUE(bvh.empty());
  std::vector<ClosestHit> out(1);
  const std::vector<Vec3d> one{Vec3d(0, 0, 0)};
  EXPECT_EQ(bvh.closest_points(one, out).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(bvh.closest_point(Vec3d(0, 0, 0)).triangle, kNoTriangle);
  // Index out of range.
  std::vector<Triangle> bad = sphere.triangles;
  bad[5][1] = static_cast<std::uint32_t>(sphere.positions.size());
  s = bvh.build(sphere.positions, bad);
  EXPECT_EQ(s.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(s.message().find("triangle 5"), std::string::npos) << s.message();
  // NaN vertex.
  std::vector<Vec3d> nan_pos = sphere.positions;
  nan_pos[7].y() = std::numeric_limits<double>::quiet_NaN();
  s = bvh.build(nan_pos, sphere.triangles);
  EXPECT_EQ(s.code(), ErrorCode::kDegenerate);
  EXPECT_NE(s.message().find("point 7"), std::string::npos) << s.message();
  // A NaN in an unreferenced slot (a dead node) is fine.
  nan_pos = sphere.positions;
  nan_pos.push_back(Vec3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_TRUE(bvh.build(nan_pos, sphere.triangles).is_ok());
  // NaN introduced before a commit.
  ASSERT_TRUE(bvh.build(sphere.positions, sphere.triangles).is_ok());
  sphere.positions[3].x() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(bvh.commit().code(), ErrorCode::kDegenerate);
  // Mismatched batch sizes.
  const Body closed = uv_sphere({0, 0, 0}, 1.0, 10, 12);
  ASSERT_TRUE(bvh.build(closed.positions, closed.triangles).is_ok());
  std::vector<ClosestHit> two(2);
  EXPECT_EQ(bvh.closest_points(one, two).code(), ErrorCode::kMismatch);
  // Open mesh: closest points work, inside tests refuse.
  std::vector<Triangle> open(closed.triangles.begin(), closed.triangles.end() - 1);
  ASSERT_TRUE(bvh.build(closed.positions, open).is_ok());
  EXPECT_FALSE(bvh.closed());
  EXPECT_EQ(bvh.require_closed().code(), ErrorCode::kTopology);
  EXPECT_NE(bvh.require_closed().message().find("boundary"), std::string::npos);
  std::vector<double> sd(1);
  EXPECT_EQ(bvh.signed_distances(one, sd).code(), ErrorCode::kTopology);
  SdfGrid grid;
  EXPECT_EQ(grid.build(bvh, {}).code(), ErrorCode::kTopology);
  EXPECT_TRUE(grid.empty());
  // Inconsistent orientation.
  std::vector<Triangle> flipped = closed.triangles;
  std::swap(flipped[0][1], flipped[0][2]);
  ASSERT_TRUE(bvh.build(closed.positions, flipped).is_ok());
  EXPECT_NE(bvh.require_closed().message().find("orientation"), std::string::npos) << bvh.require_closed().message();
  // SdfGrid parameters.
  ASSERT_TRUE(bvh.build(closed.positions, closed.triangles).is_ok());
  SdfParams p;
  p.voxel_size = 0.0;
  EXPECT_EQ(grid.build(bvh, p).code(), ErrorCode::kInvalidArgument);
  p.voxel_size = 0.1;
  p.half_width = 1.5;
  EXPECT_EQ(grid.build(bvh, p).code(), ErrorCode::kInvalidArgument);
  p.half_width = 3;
  p.roi = {Box3d{}};
  EXPECT_EQ(grid.build(bvh, p).code(), ErrorCode::kInvalidArgument);
  std::vector<std::uint8_t> in(1);
  EXPECT_EQ(grid.inside_many(one, in).code(), ErrorCode::kInvalidArgument);
  SdfGrid::Sampler unbuilt = grid.sampler();
  EXPECT_TRUE(std::isnan(unbuilt.sample(Vec3d(0, 0, 0))));
  EXPECT_FALSE(unbuilt.inside(Vec3d(0, 0, 0)));
  // Cancellation.
  ExecContext cancelled;
  cancelled.cancel.cancel();
  BodyBvh other;
  EXPECT_EQ(other.build(closed.positions, closed.triangles, {}, cancelled).code(), ErrorCode::kCancelled);
  p.roi.clear();
  EXPECT_EQ(grid.build(bvh, p, cancelled).code(), ErrorCode::kCancelled);
  // A ROI away from the body: no triangles, every query exact.
  p.roi = {Box3d{{5, 5, 5}, {6, 6, 6}}};
  ASSERT_TRUE(grid.build(bvh, p).is_ok());
  EXPECT_EQ(grid.stats().source_triangles, 0u);
  EXPECT_FALSE(grid.inside(Vec3d(5.5, 5.5, 5.5)));
  EXPECT_TRUE(grid.inside(Vec3d(0, 0, 0)));
}

}  // namespace
}  // namespace atelier
