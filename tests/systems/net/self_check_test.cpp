// The self-intersection check (first_self_crossing: certified rules for the
// pairs of overlapping boxes, the exact test for the rest) against brute
// force: every pair of triangles of the net decided by the exact test
// (triangles_cross), the smallest crossing pair or none. On small closed
// nets made to hit the certified rules' edge cases: icospheres with
// vertices moved along their radius and across (snapped to a grid, so
// exactly coplanar neighbours and corners on other triangles' planes are
// common), and grid slabs whose top vertices are moved within the top plane
// (coplanar overlaps of an umbrella, folds over a shared edge) or down onto
// and through the bottom (touching at a point, piercing). Each net is
// checked on one thread and on two threads through the parallel frontier;
// the verdict must be brute force's, faces and all.
#include <atelier/systems/net/boolean.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "../../../systems/net/boolean_detail.h"
#include "net_shapes.h"

namespace atelier {
namespace {

using net_detail::kNil;

/// The smallest pair i < j of triangles that cross, by the exact test on
/// every pair.
std::array<std::uint32_t, 2> self_check_brute_force(const net_detail::TriMesh& m) {
  const auto n = static_cast<std::uint32_t>(m.tri.size());
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = i + 1; j < n; ++j)
      if (net_detail::triangles_cross(m, i, j)) return {i, j};
  return {kNil, kNil};
}

/// A closed slab [0, n] x [0, n] x [0, 1]: top and bottom grids of n x n
/// cells (each cell two triangles, the diagonal chosen at random), walls of
/// quads. Returns the index of top vertex (i, j) through `top`.
PolygonSoup self_check_slab(int n, std::mt19937& rng, std::vector<std::uint32_t>& top) {
  PolygonSoup s;
  auto id = [&](int layer, int i, int j) {
    return static_cast<std::uint32_t>(layer * (n + 1) * (n + 1) + i * (n + 1) + j);
  };
  for (int layer = 0; layer < 2; ++layer)
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) s.positions.emplace_back(i, j, layer == 1 ? 1.0 : 0.0);
  std::bernoulli_distribution coin(0.5);
  for (int layer = 0; layer < 2; ++layer)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const std::uint32_t a = id(layer, i, j), b = id(layer, i + 1, j), c = id(layer, i + 1, j + 1),
                            d = id(layer, i, j + 1);
        // Counter-clockwise seen from outside: from above on the top (a b c
        // d runs counter-clockwise in x, y), from below on the bottom.
        std::array<std::array<std::uint32_t, 3>, 2> t =
            coin(rng) ? std::array<std::array<std::uint32_t, 3>, 2>{{{a, b, c}, {a, c, d}}}
                      : std::array<std::array<std::uint32_t, 3>, 2>{{{a, b, d}, {b, c, d}}};
        for (auto& f : t) {
          if (layer == 0) std::swap(f[1], f[2]);
          s.add_face(f);
        }
      }
  // Walls along the boundary loop of the grid, counter-clockwise from above.
  std::vector<std::array<int, 2>> loop;
  for (int i = 0; i < n; ++i) loop.push_back({i, 0});
  for (int j = 0; j < n; ++j) loop.push_back({n, j});
  for (int i = n; i > 0; --i) loop.push_back({i, n});
  for (int j = n; j > 0; --j) loop.push_back({0, j});
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const auto& u = loop[k];
    const auto& w = loop[(k + 1) % loop.size()];
    s.add_face(
        std::array<std::uint32_t, 4>{id(0, u[0], u[1]), id(0, w[0], w[1]), id(1, w[0], w[1]), id(1, u[0], u[1])});
  }
  top.clear();
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) top.push_back(id(1, i, j));
  return s;
}

struct SelfCheckTally {
  int refused = 0, accepted = 0;
};

/// Builds the net (skipping one the builder refuses: a move that put two
/// vertices together or flattened a triangle) and compares the check with
/// brute force on one and on two threads.
void self_check_against_brute_force(const PolygonSoup& s, const std::string& what, SelfCheckTally& tally) {
  net_detail::TriMesh m;
  if (!net_detail::build_tri_mesh(s, "A", m, ExecContext::sequential())) return;
  net_detail::Bvh bvh;
  net_detail::build_bvh(m, bvh, ExecContext::sequential());
  const auto want = self_check_brute_force(m);
  const auto one = net_detail::first_self_crossing(m, bvh, ExecContext::sequential());
  EXPECT_EQ(one, want) << what << " (one thread): brute force names " << want[0] << ", " << want[1];
  ExecContext two;
  two.threads = 2;
  two.sequential_threshold = 2;  // the parallel frontier even on a small net
  two.grain = 1;
  const auto par = net_detail::first_self_crossing(m, bvh, two);
  EXPECT_EQ(par, want) << what << " (two threads)";
  (want[0] == kNil ? tally.accepted : tally.refused) += 1;
}

TEST(NetSelfCheck, MatchesBruteForceOnMovedIcospheres) {
  std::mt19937 rng(11);
  const double factor[] = {-1.3, -0.5, 0.0, 0.3, 0.7, 1.2, 1.6};
  std::uniform_int_distribution<int> pick(0, 6);
  SelfCheckTally tally;
  for (int trial = 0; trial < 60; ++trial) {
    PolygonSoup a = net_test::icosphere(trial % 2 == 0 ? 1 : 2, 8.0, {0, 0, 0});  // 80 or 320 triangles
    std::uniform_int_distribution<std::size_t> which(0, a.positions.size() - 1);
    std::uniform_real_distribution<double> shift(-4.0, 4.0);
    for (int k = 0; k < 1 + trial % 4; ++k) {
      Vec3d& p = a.positions[which(rng)];
      if (trial % 3 == 0)
        p += Vec3d(shift(rng), shift(rng), shift(rng));  // sideways: folds over neighbours
      else
        p *= factor[pick(rng)];  // along the radius, through the centre or beyond
    }
    for (Vec3d& p : a.positions) p = p.array().round().matrix();  // exact coplanarities
    self_check_against_brute_force(a, "icosphere trial " + std::to_string(trial), tally);
  }
  EXPECT_GE(tally.refused, 10);
  EXPECT_GE(tally.accepted, 10);
}

TEST(NetSelfCheck, MatchesBruteForceOnFoldedSlabs) {
  std::mt19937 rng(5);
  SelfCheckTally tally;
  // In-plane moves (quarters: exact, often collinear with the grid lines)
  // make coplanar umbrellas that fold over a shared edge or overlap a
  // neighbour's triangle; vertical moves put a top vertex above, onto
  // (touching at a point) or through the bottom.
  std::uniform_int_distribution<int> quarter(-7, 7);
  const double heights[] = {0.5, 0.0, -0.25, 1.0, 0.75};
  std::uniform_int_distribution<int> height(0, 4);
  for (int trial = 0; trial < 80; ++trial) {
    const int n = 3 + trial % 4;
    std::vector<std::uint32_t> top;
    PolygonSoup s = self_check_slab(n, rng, top);
    std::uniform_int_distribution<int> inner(1, n - 1);
    for (int k = 0; k < 1 + trial % 3; ++k) {
      Vec3d& p = s.positions[top[static_cast<std::size_t>(inner(rng) * (n + 1) + inner(rng))]];
      if (trial % 2 == 0) {
        p.x() += 0.25 * quarter(rng);
        p.y() += 0.25 * quarter(rng);
      } else {
        p.z() = heights[height(rng)];
      }
    }
    self_check_against_brute_force(s, "slab trial " + std::to_string(trial), tally);
  }
  EXPECT_GE(tally.refused, 10);
  EXPECT_GE(tally.accepted, 10);
}

/// A double cone whose link winds about its axis: vertex v on top, its
/// link vertices w_k at angle `step` k about v, an apex below closing the
/// net. With 6 link vertices at 125 degrees the link winds twice, every
/// top triangle still faces up: a top umbrella no orientation test alone
/// can tell from a simple one. Alternating heights make top triangles k
/// and k + 3, over the same angles, cross along a line from v; rising
/// heights make a spiral whose triangles meet only in v.
PolygonSoup self_check_wound_cone(int n, double step_degrees, bool alternate) {
  PolygonSoup s;
  s.positions.emplace_back(0.0, 0.0, 0.0);    // v
  s.positions.emplace_back(0.0, 0.0, -20.0);  // apex
  for (int k = 0; k < n; ++k) {
    const double a = step_degrees * k * M_PI / 180.0, r = 4.0 + 0.5 * k;
    const double z = alternate ? (k % 2 == 0 ? -1.0 : 1.0) : -1.0 + 0.25 * k;
    s.positions.emplace_back(r * std::cos(a), r * std::sin(a), z);
  }
  auto w = [&](int k) { return static_cast<std::uint32_t>(2 + (k % n)); };
  for (int k = 0; k < n; ++k) s.add_face(std::array<std::uint32_t, 3>{0, w(k), w(k + 1)});  // v's umbrella first
  for (int k = 0; k < n; ++k) s.add_face(std::array<std::uint32_t, 3>{1, w(k + 1), w(k)});
  return s;
}

TEST(NetSelfCheck, MatchesBruteForceOnWoundUmbrellas) {
  SelfCheckTally tally;
  for (const bool alternate : {true, false})
    for (const auto& [n, step] : {std::pair{6, 125.0}, std::pair{6, 118.0}, std::pair{8, 95.0}, std::pair{5, 72.0}})
      self_check_against_brute_force(
          self_check_wound_cone(n, step, alternate),
          "wound cone " + std::to_string(n) + " x " + std::to_string(step) + (alternate ? " alternating" : " rising"),
          tally);
  EXPECT_GE(tally.refused, 2);
  EXPECT_GE(tally.accepted, 2);
}

}  // namespace
}  // namespace atelier
