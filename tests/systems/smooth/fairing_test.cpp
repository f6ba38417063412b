#include <atelier/systems/smooth/fairing.h>

#include <gtest/gtest.h>

#include <cstring>

#include <atelier/engine/random.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include "support/shapes.h"

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

// Moves every node by `amplitude` times a normal draw per coordinate and
// fixes each with probability `p_fixed` (one uniform, then three normals per
// node, from `seed`). Returns the fixed flags.
std::vector<std::uint8_t> perturb_and_fix(Model& m, std::uint64_t seed, double p_fixed, double amplitude) {
  SplitMix64 r(seed);
  std::vector<std::uint8_t> fixed(m.nodes.slots.capacity(), 0);
  for (std::size_t v = 0; v < fixed.size(); ++v) {
    fixed[v] = r.uniform(0, 1) < p_fixed;
    m.nodes.position[v] += amplitude * Vec3d(r.normal(), r.normal(), r.normal());
  }
  return fixed;
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
      if (g.fixed[g.id(i, j)]) {
        EXPECT_EQ(std::memcmp(p.data(), before.nodes.position[g.id(i, j)].data(), 24), 0);
      }
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

TEST(Fairing, MatchesAReferenceJacobiOnAnIrregularMesh) {
  // Valences 3, 4 and 12 (quads with fan poles), a random fixed set, an
  // isolated node and two surfaces: the planned, renumbered run must follow
  // a plain Jacobi written here on the model's own rings (no NodeAdjacency).
  Model m;
  ASSERT_TRUE(add_polygon_surface(m, "sphere", shapes::uv_sphere(12, 9).arrays()));
  ASSERT_TRUE(add_polygon_surface(m, "small", shapes::uv_sphere(3, 3, 0.5, Vec3d(3, 0, 0)).arrays()));
  const NodeIdx lonely = m.new_node(m.nodes.surface[0], Vec3d(9, 9, 9));
  ASSERT_TRUE(validate(m));
  const std::size_t n = m.nodes.slots.capacity();
  std::vector<std::uint8_t> fixed = perturb_and_fix(m, 5, 0.3, 0.1);
  fixed[0] = 0;  // the north pole (valence 12) stays free
  std::vector<Vec3d> ref = m.nodes.position;
  FairParams prm;
  prm.iterations = 7;
  const int iters = prm.iterations;
  auto umbrella_of = [&](const std::vector<Vec3d>& x, std::size_t v) {
    Vec3d s = Vec3d::Zero();
    int k = 0;
    m.for_each_outgoing(NodeIdx{static_cast<std::uint32_t>(v)}, [&](HalfedgeIdx h) {
      s += x[m.head(h).value];
      ++k;
    });
    return k ? Vec3d(s / k - x[v]) : Vec3d::Zero();
  };
  for (int it = 0; it < iters; ++it) {
    std::vector<Vec3d> u(n), next = ref;
    for (std::size_t v = 0; v < n; ++v) u[v] = umbrella_of(ref, v);
    for (std::size_t v = 0; v < n; ++v) {
      const std::size_t deg = m.degree(NodeIdx{static_cast<std::uint32_t>(v)});
      if (fixed[v] || deg == 0) continue;
      Vec3d s = Vec3d::Zero();
      double inv = 0;
      m.for_each_outgoing(NodeIdx{static_cast<std::uint32_t>(v)}, [&](HalfedgeIdx h) {
        s += u[m.head(h).value];
        inv += 1.0 / m.degree(m.head(h));
      });
      const double nu = 1.0 + inv / deg;
      next[v] = ref[v] - prm.relaxation * (s / deg - u[v]) / nu;
    }
    ref = next;
  }
  ExecContext two;
  two.threads = 2;
  two.sequential_threshold = 16;
  const Model before = m;
  auto rep = fair_umbrella(m, fixed, prm, two);
  ASSERT_TRUE(rep) << rep.status().to_string();
  EXPECT_EQ(rep->iterations, iters);
  EXPECT_TRUE(validate(m));
  double worst = 0, moved = 0;
  for (std::size_t v = 0; v < n; ++v) {
    worst = std::max(worst, (m.nodes.position[v] - ref[v]).norm());
    moved = std::max(moved, (m.nodes.position[v] - before.nodes.position[v]).norm());
    if (fixed[v] || v == lonely.value) {
      EXPECT_EQ(m.nodes.position[v], before.nodes.position[v]) << v;
    }
  }
  EXPECT_LT(worst, 1e-12);
  EXPECT_GT(moved, 1e-3);  // the comparison is not between two unmoved meshes
}

TEST(Fairing, CollisionRunIsBitIdenticalAcrossThreadCounts) {
  // The collision-checked path (per-node distance bounds, sub-steps) is as
  // deterministic as the plain one: same positions, queries and refusals.
  auto sphere_sd = [](const Vec3d& p) { return p.norm() - 1.0; };
  auto make = [] {
    Grid g = grid(30, [](double, double) { return 0.0; });
    for (auto& p : g.m.nodes.position) {
      const double x = (p.x() - 15) / 10.0, y = (p.y() - 15) / 10.0, rr = x * x + y * y;
      p = Vec3d(x, y, std::max(rr < 1.0 ? std::sqrt(1.05 * 1.05 - rr) : 0.5, 0.5));
    }
    return g;
  };
  Grid a = make(), b = make();
  FairParams prm;
  prm.iterations = 600;
  prm.signed_distance = sphere_sd;
  prm.clearance = 0.01;
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 64;
  auto ra = fair_umbrella(a.m, a.fixed, prm, one);
  auto rb = fair_umbrella(b.m, b.fixed, prm, two);
  ASSERT_TRUE(ra && rb);
  EXPECT_GT(ra->refused_moves, 0u);
  EXPECT_EQ(ra->distance_queries, rb->distance_queries);
  EXPECT_EQ(ra->refused_moves, rb->refused_moves);
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
      if (i < 2 || j < 2 || i > n - 2 || j > n - 2)
        fixed[id(i, j)] = 1;
      else
        base.nodes.position[id(i, j)].z() = ((i + j) % 2 ? 1e-3 : -1e-3);
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

TEST(Fairing, Avx2KernelIsBitIdenticalToThePortableKernel) {
  // The AVX2 kernel makes the same operations in the same order without FMA:
  // on a mesh with valences 4, 6 (unrolled rings) and 12 (the general loop),
  // a random fixed set and several blocks (1, 2 and 3 threads), positions
  // and the reported largest move must match the portable kernel bit for bit.
  Model m;
  ASSERT_TRUE(add_polygon_surface(m, "sphere", shapes::uv_sphere(40, 30).arrays()));
  Grid g = grid(90, [](double x, double y) { return std::sin(0.2 * x) * std::cos(0.3 * y); });
  shapes::Soup s;
  for (std::uint32_t v = 0; v < g.m.nodes.slots.capacity(); ++v) s.p.push_back(g.m.nodes.position[v] + Vec3d(5, 0, 0));
  for (int i = 0; i < g.n; ++i)
    for (int j = 0; j < g.n; ++j) {
      s.face({g.id(i, j), g.id(i + 1, j), g.id(i + 1, j + 1)});
      s.face({g.id(i, j), g.id(i + 1, j + 1), g.id(i, j + 1)});
    }
  ASSERT_TRUE(add_polygon_surface(m, "grid", s.arrays()));
  ASSERT_TRUE(validate(m));
  const std::size_t n = m.nodes.slots.capacity();
  std::vector<std::uint8_t> fixed = perturb_and_fix(m, 11, 0.1, 0.05);
  const NodeAdjacency adj = build_adjacency(m);
  FairParams prm;
  prm.iterations = 9;
  auto run = [&](bool avx2, int threads, FairReport& rep) {
    ExecContext ctx;
    ctx.threads = threads;
    ctx.sequential_threshold = 64;
    FairParams q = prm;
    q.allow_avx2 = avx2;
    std::vector<Vec3d> p = m.nodes.position;
    auto res = fair_umbrella(std::span<Vec3d>(p), adj, fixed, q, ctx);
    EXPECT_TRUE(res) << res.status().to_string();
    if (res) rep = *res;
    return p;
  };
  FairReport ref_rep, rep;
  const std::vector<Vec3d> ref = run(false, 1, ref_rep);
  EXPECT_FALSE(ref_rep.avx2);
  double moved = 0;
  for (std::size_t v = 0; v < n; ++v) moved = std::max(moved, (ref[v] - m.nodes.position[v]).norm());
  EXPECT_GT(moved, 1e-3);  // not a comparison of unmoved meshes
  bool ran_avx2 = false;
  for (bool avx2 : {false, true})
    for (int threads : {1, 2, 3}) {
      const std::vector<Vec3d> p = run(avx2, threads, rep);
      EXPECT_EQ(std::memcmp(p.data(), ref.data(), n * sizeof(Vec3d)), 0) << "avx2 " << avx2 << ", threads " << threads;
      EXPECT_EQ(rep.last_max_move, ref_rep.last_max_move);
      EXPECT_EQ(rep.iterations, ref_rep.iterations);
      ran_avx2 |= rep.avx2;
    }
  if (!ran_avx2) GTEST_SKIP() << "this CPU has no AVX2: only the portable kernel was compared across thread counts";
}
