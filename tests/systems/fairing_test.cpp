#include <gtest/gtest.h>

#include <cstring>

#include "engine/random.h"
#include "storage/builder.h"
#include "storage/validate.h"
#include "support/shapes.h"
#include "systems/fairing.h"

using namespace atelier;

namespace {

// Regular triangulated grid on [0,n]^2 (valence 6 inside), fixed border of two rings.
struct Grid {
  Model m;
  int n;
  std::vector<std::uint8_t> fixed;
  [[nodiscard]] std::uint32_t id(int i, int j) const { return static_cast<std::uint32_t>(i * (n + 1) + j); }
};

Grid grid(int n, const std::function<double(double, double)>& f) {
  shapes::Soup s;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) s.p.emplace_back(i, j, f(i, j));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      s.face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  Grid g;
  g.n = n;
  EXPECT_TRUE(add_polygon_surface(g.m, "grid", s.arrays()));
  g.fixed.assign(g.m.nodes.slots.capacity(), 0);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      if (i < 2 || j < 2 || i > n - 2 || j > n - 2) g.fixed[id(i, j)] = 1;
  return g;
}

}  // namespace

TEST(Fairing, ReproducesQuadraticsFromNoise) {
  // On a regular valence-6 grid the umbrella of a quadratic is constant, so
  // U2 vanishes: the faired interior must converge to the quadratic that the
  // fixed border rings sample.
  auto f = [](double x, double y) { return 0.01 * (x * x - 0.5 * x * y + 2 * y * y) + 0.3 * x; };
  Grid g = grid(14, f);
  SplitMix64 r(1);
  for (std::uint32_t v = 0; v < g.fixed.size(); ++v)
    if (!g.fixed[v]) g.m.nodes.position[v].z() += r.uniform(-1, 1);
  const Model before = g.m;
  FairParams prm;
  prm.iterations = 10000;
  prm.tolerance = 1e-13;
  auto rep = fair_umbrella(g.m, g.fixed, prm);
  ASSERT_TRUE(rep) << rep.status().to_string();
  EXPECT_TRUE(validate(g.m));
  double worst = 0;
  for (int i = 0; i <= g.n; ++i)
    for (int j = 0; j <= g.n; ++j) {
      const Vec3d& p = g.m.nodes.position[g.id(i, j)];
      worst = std::max(worst, std::abs(p.z() - f(p.x(), p.y())));
      if (g.fixed[g.id(i, j)]) EXPECT_EQ(std::memcmp(p.data(), before.nodes.position[g.id(i, j)].data(), 24), 0);
    }
  EXPECT_LT(worst, 1e-6) << "after " << rep->iterations << " iterations";  // from noise of amplitude 1
  const NodeAdjacency adj = build_adjacency(g.m);
  EXPECT_LT(umbrella2_norm(g.m.nodes.position, adj, g.fixed), 1e-7);
}

TEST(Fairing, BitIdenticalAcrossThreadCounts) {
  Grid a = grid(120, [](double x, double y) { return std::sin(0.3 * x) * std::cos(0.2 * y); });
  SplitMix64 r(2);
  for (std::uint32_t v = 0; v < a.fixed.size(); ++v)
    if (!a.fixed[v]) a.m.nodes.position[v] += 0.3 * Vec3d(r.normal(), r.normal(), r.normal());
  Grid b = a;
  FairParams prm;
  prm.iterations = 20;
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 64;
  ASSERT_TRUE(fair_umbrella(a.m, a.fixed, prm, one));
  ASSERT_TRUE(fair_umbrella(b.m, b.fixed, prm, two));
  EXPECT_EQ(std::memcmp(a.m.nodes.position.data(), b.m.nodes.position.data(), a.m.nodes.position.size() * 24), 0);
}

TEST(Fairing, CollisionKeepsATightPatchOutOfTheBody) {
  // A patch draped over a unit sphere, its border pinned below the sphere's
  // top: fairing alone pulls it through the sphere; with collision it stays out.
  const double R = 1.0;
  auto sphere_sd = [&](const Vec3d& p) { return p.norm() - R; };
  auto make = [&] {
    Grid g = grid(30, [](double, double) { return 0.0; });
    for (std::uint32_t v = 0; v < g.fixed.size(); ++v) {
      Vec3d& p = g.m.nodes.position[v];
      const double x = (p.x() - 15) / 10.0, y = (p.y() - 15) / 10.0;  // [-1.5, 1.5]^2
      const double rr = x * x + y * y;
      // Start on a cap 5 cm outside the sphere, flattening out to z = 0.5 at the rim.
      const double z = rr < 1.0 ? std::sqrt(std::max(0.0, (R + 0.05) * (R + 0.05) - rr)) : 0.5;
      p = Vec3d(x, y, std::max(z, 0.5));
    }
    return g;
  };
  Grid free_g = make(), safe_g = make();
  FairParams prm;
  prm.iterations = 600;
  ASSERT_TRUE(fair_umbrella(free_g.m, free_g.fixed, prm));
  std::size_t inside_free = 0;
  for (const auto& p : free_g.m.nodes.position) inside_free += sphere_sd(p) < 0;
  EXPECT_GT(inside_free, 10u) << "the test needs fairing alone to penetrate";
  prm.signed_distance = sphere_sd;
  prm.clearance = 0.01;
  auto rep = fair_umbrella(safe_g.m, safe_g.fixed, prm);
  ASSERT_TRUE(rep);
  std::size_t inside_safe = 0;
  double closest = 1e9;
  for (std::uint32_t v = 0; v < safe_g.fixed.size(); ++v) {
    const double d = sphere_sd(safe_g.m.nodes.position[v]);
    inside_safe += d < 0;
    if (!safe_g.fixed[v]) closest = std::min(closest, d);
  }
  EXPECT_EQ(inside_safe, 0u);
  EXPECT_GE(closest, prm.clearance - 1e-12);
  EXPECT_GT(rep->refused_moves, 0u);
  // The Lipschitz skip: far fewer body queries than nodes x iterations x sub-steps.
  EXPECT_LT(rep->distance_queries, 0.5 * 961 * 600 * prm.substeps);
  // Distance bounds in and out: every bound returned is a true lower bound at
  // the final position, and starting from exact bounds saves queries.
  Grid again = make();
  std::vector<double> bounds(again.m.nodes.slots.capacity());
  for (std::size_t v = 0; v < bounds.size(); ++v) bounds[v] = sphere_sd(again.m.nodes.position[v]);
  prm.distance_bounds = bounds;
  auto rep2 = fair_umbrella(again.m, again.fixed, prm);
  ASSERT_TRUE(rep2);
  for (std::size_t v = 0; v < bounds.size(); ++v)
    EXPECT_LE(bounds[v], sphere_sd(again.m.nodes.position[v]) + 1e-12) << v;
  EXPECT_LT(rep2->distance_queries, rep->distance_queries);
  std::vector<double> too_short(3);
  prm.distance_bounds = too_short;
  EXPECT_FALSE(fair_umbrella(again.m, again.fixed, prm));
}

TEST(Fairing, MismatchedInputIsRefused) {
  Grid g = grid(4, [](double, double) { return 0.0; });
  std::vector<std::uint8_t> fixed(3, 0);
  auto r = fair_umbrella(g.m, fixed, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), ErrorCode::kMismatch);
  // A plan made for another mesh, or with another relaxation, is refused;
  // a matching plan gives the same result as the one-call form.
  Grid big = grid(6, [](double x, double y) { return 0.1 * x * y; });
  const NodeAdjacency small_adj = build_adjacency(g.m), big_adj = build_adjacency(big.m);
  FairParams prm;
  prm.iterations = 5;
  auto plan = make_fair_plan(small_adj, g.fixed, prm);
  ASSERT_TRUE(plan);
  std::vector<Vec3d> p = big.m.nodes.position;
  auto wrong = fair_umbrella(p, big_adj, *plan, prm);
  ASSERT_FALSE(wrong);
  EXPECT_EQ(wrong.status().code(), ErrorCode::kMismatch);
  auto big_plan = make_fair_plan(big_adj, big.fixed, prm).value();
  FairParams other = prm;
  other.relaxation = 0.9;
  EXPECT_FALSE(fair_umbrella(p, big_adj, big_plan, other));
  std::vector<Vec3d> q = p;
  ASSERT_TRUE(fair_umbrella(p, big_adj, big_plan, prm));
  ASSERT_TRUE(fair_umbrella(q, big_adj, big.fixed, prm));
  EXPECT_EQ(std::memcmp(p.data(), q.data(), p.size() * sizeof(Vec3d)), 0);
}

TEST(Fairing, DampingKeepsQuadMeshesStable) {
  // On a quad grid (valence 4) the highest-frequency mode of U2 / nu is
  // 4 / 1.25 = 3.2: undamped Jacobi multiplies it by |1 - 3.2| = 2.2 per
  // iteration, the default damping (0.5) by 0.6. A checkerboard bump is
  // exactly that mode.
  const int n = 20;
  shapes::Soup s;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) s.p.emplace_back(i, j, 0.0);
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) s.face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  Model base;
  ASSERT_TRUE(add_polygon_surface(base, "quads", s.arrays()));
  std::vector<std::uint8_t> fixed(base.nodes.slots.capacity(), 0);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      if (i < 2 || j < 2 || i > n - 2 || j > n - 2) fixed[id(i, j)] = 1;
      else base.nodes.position[id(i, j)].z() = ((i + j) % 2 ? 1e-3 : -1e-3);
    }
  auto max_z = [&](const Model& m) {
    double z = 0;
    for (const auto& p : m.nodes.position) z = std::max(z, std::abs(p.z()));
    return z;
  };
  FairParams prm;
  prm.iterations = 30;
  Model damped = base, undamped = base;
  ASSERT_TRUE(fair_umbrella(damped, fixed, prm));
  prm.relaxation = 1.0;
  ASSERT_TRUE(fair_umbrella(undamped, fixed, prm));
  EXPECT_LT(max_z(damped), 1e-5);   // decays
  EXPECT_GT(max_z(undamped), 1.0);  // 1e-3 * 2.2^30 would be ~2e7: it blows up
  prm.relaxation = 0.0;
  EXPECT_FALSE(fair_umbrella(damped, fixed, prm));
}
