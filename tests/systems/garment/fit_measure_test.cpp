// measure_fit against analytic answers: a box body, whose signed distances
// are known in closed form, and an affine stretch of it, under which a
// garment that follows the skin has zero excess strain.
#include <atelier/systems/garment/fit_measure.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace atelier;

namespace {

// The box [-a, a]^3, 12 outward triangles.
struct Box {
  std::vector<Vec3d> p;
  std::vector<Triangle> t;
};
Box box(Vec3d a) {
  Box b;
  for (int i = 0; i < 8; ++i)
    b.p.emplace_back((i & 1 ? 1 : -1) * a.x(), (i & 2 ? 1 : -1) * a.y(), (i & 4 ? 1 : -1) * a.z());
  const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) {
    b.t.push_back({std::uint32_t(f[0]), std::uint32_t(f[1]), std::uint32_t(f[2])});
    b.t.push_back({std::uint32_t(f[0]), std::uint32_t(f[2]), std::uint32_t(f[3])});
  }
  return b;
}

// An n x n grid of vertices at height z over [-0.5, 0.5]^2, edges along x and y.
struct Grid {
  std::vector<Vec3d> p;
  std::vector<std::array<std::uint32_t, 2>> e;
  std::size_t x_edges = 0;
};
Grid grid(int n, double z) {
  Grid g;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) g.p.emplace_back(-0.5 + i / double(n - 1), -0.5 + j / double(n - 1), z);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i + 1 < n; ++i) g.e.push_back({std::uint32_t(j * n + i), std::uint32_t(j * n + i + 1)});
  g.x_edges = g.e.size();
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i < n; ++i) g.e.push_back({std::uint32_t(j * n + i), std::uint32_t((j + 1) * n + i)});
  return g;
}

}  // namespace

TEST(FitMeasure, PenetrationAndClearanceOnABox) {
  const Box b = box({1, 1, 1});
  // Known signed distances: 0.5, -0.5, -0.1, 0.25 (corner region: distance
  // to the corner point), 0.
  const std::vector<Vec3d> g = {{0, 0, 1.5}, {0, 0, 0.5}, {0.9, 0, 0}, {1.0, 1.0 + 0.15, 1.0 + 0.2}, {1, 0.2, 0.3}};
  const std::vector<double> expect = {0.5, -0.5, -0.1, 0.25, 0};
  FitInput in;
  in.body_points = b.p;
  in.body_triangles = b.t;
  in.garment = g;
  const auto m = measure_fit(in);
  ASSERT_TRUE(m) << m.status().to_string();
  EXPECT_EQ(m->vertices, 5u);
  EXPECT_EQ(m->inside, 2u);
  EXPECT_EQ(m->inside_tolerance, 2u);
  EXPECT_NEAR(m->max_depth, 0.5, 1e-12);
  EXPECT_NEAR(m->clearance_min, -0.5, 1e-12);
  double mean = 0;
  for (double d : expect) mean += d / 5;
  EXPECT_NEAR(m->clearance_mean, mean, 1e-12);
  EXPECT_NEAR(m->clearance_p50, 0.0, 1e-12);  // sorted: -0.5 -0.1 0 0.25 0.5, index 2
  EXPECT_NEAR(m->clearance_p95, 0.5, 1e-12);  // index floor(4.75) = 4
  EXPECT_FALSE(m->has_source);

  // A tolerance of 0.2 m keeps only the deep vertex.
  const auto m2 = measure_fit(in, {.inside_tolerance = 0.2});
  ASSERT_TRUE(m2);
  EXPECT_EQ(m2->inside_tolerance, 1u);
}

TEST(FitMeasure, GarmentThatFollowsAStretchedBodyHasNoExcessStrain) {
  const Box b0 = box({1, 1, 1});
  const Box b1 = box({2, 1, 1});  // the body stretched by 2 along x
  const Grid src = grid(9, 1.1);  // 0.1 above the top face
  Grid follow = src;              // carried by the body's affine map
  for (auto& p : follow.p) p.x() *= 2;
  Grid rigid = src;  // not stretched, lifted 0.05
  for (auto& p : rigid.p) p.z() += 0.05;

  FitInput in;
  in.body_points = b1.p;
  in.body_triangles = b1.t;
  in.garment_edges = src.e;
  in.source_garment = src.p;
  in.source_body_points = b0.p;

  in.garment = follow.p;
  auto m = measure_fit(in);
  ASSERT_TRUE(m) << m.status().to_string();
  ASSERT_TRUE(m->has_source && m->has_source_body);
  // Half the edges (along x) are stretched by 100 %: p95 is 1.
  EXPECT_NEAR(m->edge_strain_p95, 1.0, 1e-12);
  EXPECT_NEAR(m->excess_strain_p95, 0.0, 1e-12);
  EXPECT_NEAR(m->clearance_change_rms, 0.0, 1e-12);

  in.garment = rigid.p;
  m = measure_fit(in);
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->edge_strain_p95, 0.0, 1e-12);
  // The x edges kept their length on a skin that doubled: excess strain 1.
  EXPECT_NEAR(m->excess_strain_p95, 1.0, 1e-12);
  EXPECT_NEAR(m->clearance_change_rms, 0.05, 1e-12);

  // Without the source body only the plain strain is known.
  in.source_body_points = {};
  m = measure_fit(in);
  ASSERT_TRUE(m);
  EXPECT_TRUE(m->has_source);
  EXPECT_FALSE(m->has_source_body);
  EXPECT_NEAR(m->edge_strain_p95, 0.0, 1e-12);
}

TEST(FitMeasure, SameResultForAnyThreadCount) {
  const Box b0 = box({1, 1, 1});
  const Box b1 = box({1.3, 0.9, 1.1});
  const Grid src = grid(40, 1.02);
  Grid g = src;
  for (std::size_t i = 0; i < g.p.size(); ++i)
    g.p[i] += Vec3d(0.01 * std::sin(double(i)), 0.02 * std::cos(3.0 * i), 0.03 * std::sin(7.0 * i));
  FitInput in{b1.p, b1.t, g.p, g.e, src.p, b0.p};
  ExecContext one;
  one.threads = 1;
  ExecContext two;
  two.threads = 2;
  two.sequential_threshold = 1;
  two.grain = 1;
  const auto a = measure_fit(in, {}, one), c = measure_fit(in, {}, two);
  ASSERT_TRUE(a && c);
  EXPECT_EQ(a->inside, c->inside);
  EXPECT_EQ(a->clearance_mean, c->clearance_mean);
  EXPECT_EQ(a->clearance_p95, c->clearance_p95);
  EXPECT_EQ(a->excess_strain_p95, c->excess_strain_p95);
  EXPECT_EQ(a->edge_strain_p95, c->edge_strain_p95);
  EXPECT_GT(a->excess_strain_p95, 0.0);
}

TEST(FitMeasure, BadInputIsNamed) {
  const Box b = box({1, 1, 1});
  std::vector<Vec3d> g = {{0, 0, 2}, {0, 0, 3}};
  std::vector<std::array<std::uint32_t, 2>> e = {{0, 5}};
  FitInput in{b.p, b.t, g, e, {}, {}};
  auto m = measure_fit(in);
  ASSERT_FALSE(m);
  EXPECT_NE(m.status().message().find("edge 0 names vertex 5"), std::string::npos) << m.status().message();

  in.garment_edges = {};
  g[1].y() = std::nan("");
  m = measure_fit(in);
  ASSERT_FALSE(m);
  EXPECT_NE(m.status().message().find("garment vertex 1"), std::string::npos) << m.status().message();

  g[1].y() = 0;
  std::vector<Triangle> open(b.t.begin(), b.t.end() - 1);  // one triangle missing
  in.body_triangles = open;
  m = measure_fit(in);
  ASSERT_FALSE(m);
  EXPECT_NE(m.status().message().find("body"), std::string::npos) << m.status().message();

  in.body_triangles = b.t;
  std::vector<Vec3d> short_source = {{0, 0, 2}};
  in.source_garment = short_source;
  m = measure_fit(in);
  ASSERT_FALSE(m);
  EXPECT_EQ(m.status().code(), ErrorCode::kMismatch);

  in.source_garment = {};
  in.garment = {};
  EXPECT_FALSE(measure_fit(in));
}
