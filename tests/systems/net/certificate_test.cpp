// The rounded result's certificate, its shortcut within a net triangle
// (issue 24, cert17): rounded_pieces_embedded says that the pieces of a cut
// triangle (or of two net triangles sharing an edge) still form an
// embedded triangulation once their new points are rounded, and the
// certificate then skips their pairs. Tested against brute force: on
// triangulations whose points are moved at random (from a few ulps to
// more than the spacing, so that pieces flip and boundaries fold), every
// triangulation it certifies has no two pieces meeting beyond the corners
// they share, by the exact triangles_cross over all pairs; and on the
// Booleans, the certificate's verdict and the result's bytes are the same
// with the shortcut and without it (each pair tested), on 1 and 2 threads.
#include <atelier/io/obj.h>
#include <gtest/gtest.h>

#include <array>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <vector>

#include "../../../systems/net/boolean_detail.h"
#include "../../../systems/net/fold_level_patch.h"
#include "net_shapes.h"

// Its own namespace: the net tests build as unity batches, and other
// files define kPairs, Tally and the like in atelier's anonymous namespace.
namespace atelier::certificate_test {
namespace {

using net_detail::Cut;
using net_detail::TriMesh;

/// One or two net triangles of side 0, each cut into the regular
/// subdivision of `level` (corners: the net's vertices, ids 0..3; the
/// other grid points new points, shared along the common edge), with the
/// new points at the given positions. u = (0, 1, 2); w = (1, 0, 3).
struct GridPatch {
  TriMesh a, b;
  Cut cut;
  std::vector<Vec3d> exact;  // the new points before the move
};

GridPatch grid_patch(const std::array<Vec3d, 4>& c, int level, bool two) {
  GridPatch g;
  g.a.p.assign(c.begin(), c.begin() + (two ? 4 : 3));
  g.a.net_vertices = g.a.p.size();
  g.a.tri.push_back({0, 1, 2});
  if (two) g.a.tri.push_back({1, 0, 3});
  const auto n_net = static_cast<std::uint32_t>(g.a.p.size());
  // Point (i, j) of a triangle (p0, p1, p2): p0 + i/L (p1 - p0) + j/L (p2 - p0).
  std::map<std::array<int, 3>, std::uint32_t> id_of;  // (triangle, i, j) -> id
  auto corner_id = [&](const std::array<std::uint32_t, 3>& t, int i, int j) -> std::uint32_t {
    if (i == 0 && j == 0) return t[0];
    if (i == level && j == 0) return t[1];
    if (i == 0 && j == level) return t[2];
    return net_detail::kNil;
  };
  auto id = [&](int tri, int i, int j) -> std::uint32_t {
    const auto& t = g.a.tri[static_cast<std::size_t>(tri)];
    if (const std::uint32_t v = corner_id(t, i, j); v != net_detail::kNil) return v;
    if (tri == 1 && j == 0) return id_of.at({0, level - i, 0});  // w's edge 1 -> 0 is u's 0 -> 1
    const auto key = std::array<int, 3>{tri, i, j};
    if (const auto it = id_of.find(key); it != id_of.end()) return it->second;
    const Vec3d& p0 = g.a.p[t[0]];
    const Vec3d& p1 = g.a.p[t[1]];
    const Vec3d& p2 = g.a.p[t[2]];
    g.exact.push_back(p0 + (p1 - p0) * (double(i) / level) + (p2 - p0) * (double(j) / level));
    return id_of[key] = n_net + static_cast<std::uint32_t>(g.exact.size() - 1);
  };
  auto& s = g.cut.sides[0];
  s.m = &g.a;
  s.side = 0;
  s.offset = 0;
  s.piece_begin.push_back(0);
  for (int tri = 0; tri < (two ? 2 : 1); ++tri) {
    for (int j = 0; j < level; ++j)
      for (int i = 0; i + j < level; ++i) {
        s.piece.push_back({id(tri, i, j), id(tri, i + 1, j), id(tri, i, j + 1)});
        if (i + j + 1 < level) s.piece.push_back({id(tri, i + 1, j), id(tri, i + 1, j + 1), id(tri, i, j + 1)});
      }
    s.piece_begin.push_back(static_cast<std::uint32_t>(s.piece.size()));
  }
  s.keep.assign(s.piece.size(), 1);
  g.cut.nA = n_net;
  g.cut.nB = 0;
  g.cut.new_points = g.exact;
  g.cut.canon.resize(n_net + g.exact.size());
  for (std::uint32_t k = 0; k < g.cut.canon.size(); ++k) g.cut.canon[k] = k;
  return g;
}

/// Brute force: some two pieces meet beyond the corners they share (exact).
bool some_pieces_cross(const GridPatch& g) {
  TriMesh m;
  for (std::uint32_t k = 0; k < g.cut.canon.size(); ++k) m.p.push_back(g.cut.position(g.a, g.b, k));
  m.tri = g.cut.sides[0].piece;
  for (std::uint32_t x = 0; x < m.tri.size(); ++x)
    for (std::uint32_t y = x + 1; y < m.tri.size(); ++y)
      if (net_detail::triangles_cross(m, x, y)) return true;
  return false;
}

/// Random patches, their new points moved by up to `scale` times the grid's
/// spacing (in u's plane, or also across it); tallies.
struct Tally {
  int certified = 0, crossing = 0, refused_not_crossing = 0;
};

void run_random_patches(bool two, Tally& t) {
  std::mt19937_64 rng(two ? 1717 : 17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double scales[] = {0x1p-50, 1e-9, 0.05, 0.2, 0.45, 0.7, 1.2};
  for (int trial = 0; trial < 700; ++trial) {
    const int level = 2 + trial % 4;
    std::array<Vec3d, 4> c;
    const bool flat = trial % 2 == 0;  // u in a plane z = const: overlap in projection is overlap
    const double size = std::ldexp(1.0, static_cast<int>(rng() % 40) - 20);
    for (auto& p : c) p = Vec3d(unit(rng), unit(rng), flat ? 0.375 : 0.3 * unit(rng)) * size;
    if (two) {
      // w's apex across the edge (0, 1) from u's corner 2.
      const Vec3d mid = (c[0] + c[1]) * 0.5;
      c[3] = mid - (c[2] - mid) * (0.5 + 0.5 * std::abs(unit(rng)));
      if (flat) c[3].z() = c[0].z();
    }
    GridPatch g = grid_patch(c, level, two);
    const double h = (c[1] - c[0]).norm() / level;
    const double scale = scales[static_cast<std::size_t>(trial) % std::size(scales)];
    // Move some new points (every one, or one of them).
    const bool all = trial % 3 != 0;
    const std::size_t one = rng() % std::max<std::size_t>(1, g.exact.size());
    for (std::size_t k = 0; k < g.cut.new_points.size(); ++k) {
      if (!all && k != one) continue;
      Vec3d d(unit(rng), unit(rng), flat ? 0.0 : unit(rng));
      g.cut.new_points[k] += d * (scale * h);
    }
    const std::uint32_t u0[1] = {0}, uw[2] = {0, 1};
    const bool embedded = two ? net_detail::rounded_pieces_embedded(g.cut, g.a, g.b, 0, uw)
                              : net_detail::rounded_pieces_embedded(g.cut, g.a, g.b, 0, u0);
    const bool crosses = some_pieces_cross(g);
    if (embedded) {
      ++t.certified;
      EXPECT_FALSE(crosses) << "trial " << trial << " (level " << level << ", scale " << scale
                            << "): certified embedded, but two pieces cross";
    } else {
      crosses ? ++t.crossing : ++t.refused_not_crossing;
    }
  }
}

// Soundness against the exact pair test, one cut triangle: what the rule
// certifies has no crossing pair; crossing triangulations occur (so the
// rule is what decides them: without the orientation test it certifies
// folded ones, checked when written) and are all refused.
TEST(NetCertificateEmbedding, CertifiedTriangulationsHaveNoCrossingPieces) {
  Tally t;
  run_random_patches(false, t);
  std::cout << "certified " << t.certified << ", crossing (refused) " << t.crossing << ", refused but not crossing "
            << t.refused_not_crossing << "\n";
  EXPECT_GE(t.certified, 250);
  EXPECT_GE(t.crossing, 100);
}

// The same for two net triangles sharing an edge (the quadrilateral's
// boundary: four chains).
TEST(NetCertificateEmbedding, CertifiedNeighbourPairsHaveNoCrossingPieces) {
  Tally t;
  run_random_patches(true, t);
  std::cout << "certified " << t.certified << ", crossing (refused) " << t.crossing << ", refused but not crossing "
            << t.refused_not_crossing << "\n";
  EXPECT_GE(t.certified, 250);
  EXPECT_GE(t.crossing, 100);
}

// Hand-made folds: an interior point moved out of u (pieces flip), and a
// boundary point moved along its edge past the next corner; the grid as it
// is certified.
TEST(NetCertificateEmbedding, FoldsAreRefused) {
  const std::array<Vec3d, 4> c = {Vec3d(0, 0, 1), Vec3d(4, 0, 1), Vec3d(0, 4, 1), Vec3d(2, -3, 1)};
  {
    GridPatch g = grid_patch(c, 4, false);
    const std::uint32_t u0[1] = {0};
    EXPECT_TRUE(net_detail::rounded_pieces_embedded(g.cut, g.a, g.b, 0, u0));
    EXPECT_FALSE(some_pieces_cross(g));
    // The interior point (1, 1) of the grid moved out of u, far across
    // its star: its pieces flip.
    for (std::size_t k = 0; k < g.exact.size(); ++k)
      if ((g.exact[k] - Vec3d(1, 1, 1)).norm() < 1e-12) g.cut.new_points[k] = Vec3d(2.6, 2.6, 1);
    EXPECT_FALSE(net_detail::rounded_pieces_embedded(g.cut, g.a, g.b, 0, u0));
    EXPECT_TRUE(some_pieces_cross(g));
  }
  {
    GridPatch g = grid_patch(c, 4, false);
    const std::uint32_t u0[1] = {0};
    // Boundary point (3, 0) on edge 0 -> 1 moved along it past corner 1.
    for (std::size_t k = 0; k < g.exact.size(); ++k)
      if ((g.exact[k] - Vec3d(3, 0, 1)).norm() < 1e-12) g.cut.new_points[k] = Vec3d(4.5, 0, 1);
    EXPECT_FALSE(net_detail::rounded_pieces_embedded(g.cut, g.a, g.b, 0, u0));
    EXPECT_TRUE(some_pieces_cross(g));
  }
}

// The level-plane rule against the exact pair test: y in a plane z = l, x
// with corners on the plane (shared with y by id, or not: inside y, on its
// edges, outside) and off it on one side or both; whatever the rule calls
// apart, triangles_cross (corners merged by id) finds apart, and touching
// or crossing pairs occur and are refused.
// A fold only the boundary tests see: u cut at level 2 (corners (0, 0),
// (1, 0), (0, 1) in the plane z = 3/8; new points the edges' midpoints),
// the midpoint of edge 0 -> 1 moved to (-0.17, -0.08) and that of edge
// 0 -> 2 to (-1.99, -1.00) (found by a random search over level-2 moves):
// every piece keeps u's orientation, but the boundary crosses itself and
// the piece at corner 0 overlaps the piece at corner 1. Without the chain
// and corner tests the rule certifies it (the orientation test alone
// passes all four pieces).
TEST(NetCertificateEmbedding, AFoldedBoundaryWithEveryPieceKeepingItsOrientationIsRefused) {
  const std::array<Vec3d, 4> c = {Vec3d(0, 0, 0.375), Vec3d(1, 0, 0.375), Vec3d(0, 1, 0.375), Vec3d(0, 0, 0)};
  GridPatch g = grid_patch(c, 2, false);
  const std::uint32_t u0[1] = {0};
  ASSERT_TRUE(net_detail::rounded_pieces_embedded(g.cut, g.a, g.b, 0, u0));
  int moved = 0;
  for (std::size_t k = 0; k < g.exact.size(); ++k) {
    if ((g.exact[k] - Vec3d(0.5, 0, 0.375)).norm() < 1e-12) {
      g.cut.new_points[k] = Vec3d(-0.1672374460150512, -0.07913906662479198, 0.375);
      ++moved;
    }
    if ((g.exact[k] - Vec3d(0, 0.5, 0.375)).norm() < 1e-12) {
      g.cut.new_points[k] = Vec3d(-1.988498063963907, -1.0048435595000953, 0.375);
      ++moved;
    }
  }
  ASSERT_EQ(moved, 2);
  // Every piece still has u's orientation (so only the boundary tests can
  // refuse), and two pieces cross (so they must).
  for (const auto& t : g.cut.sides[0].piece) {
    const Vec3d p0 = g.cut.position(g.a, g.b, t[0]), p1 = g.cut.position(g.a, g.b, t[1]),
                p2 = g.cut.position(g.a, g.b, t[2]);
    EXPECT_GT((p1 - p0).cross(p2 - p0).z(), 1e-3);
  }
  EXPECT_TRUE(some_pieces_cross(g));
  EXPECT_FALSE(net_detail::rounded_pieces_embedded(g.cut, g.a, g.b, 0, u0));
}

TEST(NetCertificateEmbedding, LevelPlaneRuleAgreesWithTheExactTest) {
  std::mt19937_64 rng(1717);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int apart = 0, meeting = 0, refused_apart = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double l = trial % 3 == 0 ? -100.0 : 0.375 * unit(rng);
    const double big = trial % 5 == 0 ? 3.4028234699999998e+38 : 1.0;
    std::array<Vec3d, 3> y;
    for (auto& p : y) p = Vec3d(unit(rng), unit(rng), l);
    if (trial % 5 == 0) y[0] = Vec3d(-big, -big, l);  // Cray's fan from a far corner
    const std::array<std::uint32_t, 3> y_ids = {0, 1, 2};
    std::array<Vec3d, 3> x;
    std::array<std::uint32_t, 3> x_ids = {10, 11, 12};
    const int n_on = 1 + static_cast<int>(rng() % 2);
    const bool both_sides = rng() % 8 == 0;
    for (int c = 0; c < 3; ++c) {
      if (c < n_on) {
        const int kind = static_cast<int>(rng() % 4);
        if (kind == 0) {  // a corner of y, by id
          std::uint32_t k = static_cast<std::uint32_t>(rng() % 3);
          if (c == 1 && x_ids[0] == k) k = (k + 1) % 3;
          x[static_cast<std::size_t>(c)] = y[k];
          x_ids[static_cast<std::size_t>(c)] = k;
        } else if (kind == 1) {  // on an edge of y (rounded: on or near it)
          const double t = 0.5 + 0.4 * unit(rng);
          x[static_cast<std::size_t>(c)] = y[1] + (y[2] - y[1]) * t;
          x[static_cast<std::size_t>(c)].z() = l;
        } else {
          x[static_cast<std::size_t>(c)] = Vec3d(1.5 * unit(rng), 1.5 * unit(rng), l);
        }
      } else {
        const double up = both_sides && c == 2 ? -1.0 : 1.0;
        x[static_cast<std::size_t>(c)] = Vec3d(unit(rng), unit(rng), l + up * (0.01 + std::abs(unit(rng))));
      }
    }
    if (n_on == 2 && x_ids[1] == 11 && x_ids[0] != 10 && rng() % 2 == 0) {
      // the edge from a shared corner into or out of y
      x[1] = y[x_ids[0]] + (y[(x_ids[0] + 1) % 3] - y[x_ids[0]]) * 0.3 + Vec3d(0.2 * unit(rng), 0.2 * unit(rng), 0);
      x[1].z() = l;
    }
    TriMesh m;
    std::array<std::uint32_t, 3> tx{}, ty = {0, 1, 2};
    m.p.assign(y.begin(), y.end());
    for (std::size_t c = 0; c < 3; ++c) {
      if (x_ids[c] < 3) {
        tx[c] = x_ids[c];
      } else {
        m.p.push_back(x[c]);
        tx[c] = static_cast<std::uint32_t>(m.p.size() - 1);
      }
    }
    if (tx[0] == tx[1] || tx[1] == tx[2] || tx[0] == tx[2]) continue;
    if (net_detail::collinear(m.p[tx[0]], m.p[tx[1]], m.p[tx[2]]) || net_detail::collinear(y[0], y[1], y[2])) continue;
    m.tri = {ty, tx};
    const bool says = net_detail::level_plane_pieces_apart(y, y_ids, x, x_ids);
    const bool crosses = net_detail::triangles_cross(m, 0, 1);
    if (says) {
      ++apart;
      EXPECT_FALSE(crosses) << "trial " << trial << ": called apart, but the triangles meet";
    } else {
      crosses ? ++meeting : ++refused_apart;
    }
  }
  std::cout << "apart " << apart << ", meeting (refused) " << meeting << ", refused but apart " << refused_apart
            << "\n";
  EXPECT_GE(apart, 5000);
  EXPECT_GE(meeting, 1000);
}

const std::filesystem::path kPairs = std::filesystem::path(ATELIER_SHARED_DATA) / "meshes" / "boolean-pairs";

/// The certificate with a rule switched off and on: the same verdict and
/// the same result bytes, on 1 and 2 threads; returns the pairs tested
/// (on, off), the results certified and how far the rule's own counter
/// moved (cert17: triangles certified embedded; cert18: level-patch skips).
struct Compared {
  std::size_t pairs_on = 0, pairs_off = 0, counted = 0, certified = 0;
};

void compare_rule(const PolygonSoup& a, const PolygonSoup& b, const std::string& what, void (*set_rule)(bool) noexcept,
                  const std::atomic<std::size_t>& counter, Compared& out) {
  auto& counts = net_detail::result_check_counts();
  for (BooleanOp op : net_test::kAllOps) {
    BooleanOptions o;
    o.op = op;
    for (const int threads : {1, 2}) {
      ExecContext ctx;
      ctx.threads = threads;
      ctx.sequential_threshold = 2;
      set_rule(false);
      const std::size_t c0 = counts.certified, p0 = counts.pairs;
      const auto off = net_boolean(a, b, o, ctx);
      const std::size_t c1 = counts.certified, p1 = counts.pairs, e1 = counter;
      set_rule(true);
      const auto on = net_boolean(a, b, o, ctx);
      const std::size_t c2 = counts.certified, p2 = counts.pairs, e2 = counter;
      ASSERT_EQ(on.has_value(), off.has_value()) << what;
      EXPECT_EQ(c2 - c1, c1 - c0) << what << " op " << static_cast<int>(op) << ": the verdict changed";
      out.certified += c2 - c1;
      out.pairs_off += p1 - p0;
      out.pairs_on += p2 - p1;
      out.counted += e2 - e1;
      if (!on) {
        EXPECT_EQ(on.status().to_string(), off.status().to_string()) << what;
        continue;
      }
      EXPECT_EQ(on->result.positions, off->result.positions) << what;
      EXPECT_EQ(on->result.face_nodes, off->result.face_nodes) << what;
      EXPECT_EQ(on->result.face_offsets, off->result.face_offsets) << what;
    }
  }
}

void compare_shortcut(const PolygonSoup& a, const PolygonSoup& b, const std::string& what, Compared& out) {
  compare_rule(a, b, what, net_detail::set_embedding_shortcut, net_detail::result_check_counts().embedded, out);
}

// The Booleans: the shortcut changes no verdict and no byte, and on Cray
// (the slab's two top triangles, ~90 pieces each) it removes most pairs.
TEST(NetCertificateEmbedding, ShortcutKeepsVerdictsAndBytes) {
  Compared shapes;
  compare_shortcut(net_test::icosphere(3, 1.0, {0, 0, 0}), net_test::icosphere(3, 0.9, {0.31, 0.17, 0.05}),
                   "icospheres", shapes);
  compare_shortcut(net_test::box({0, 0, 0}, {1, 1, 1}), net_test::box({0.5, 0.25, -0.5}, {1.5, 1.25, 0.5}), "boxes",
                   shapes);
  compare_shortcut(net_test::box_triangles({-1e30, -1e30, -1e30}, {1e30, 1e30, -100.0}),
                   net_test::icosphere(3, 2.5e4, {3.0, -7.0, -100.0}), "slab and sphere", shapes);
  EXPECT_GE(shapes.certified, 16u);
  EXPECT_GE(shapes.counted, 1u);
  EXPECT_LE(shapes.pairs_on, shapes.pairs_off);
  if (!std::filesystem::exists(kPairs)) GTEST_SKIP() << "shared data absent: " << kPairs;
  Compared cray;
  compare_shortcut(net_polygons(read_obj(kPairs / "Cray_left.obj")), net_polygons(read_obj(kPairs / "Cray_right.obj")),
                   "Cray", cray);
  std::cout << "Cray: certified " << cray.certified << " of 8, pairs " << cray.pairs_off << " -> " << cray.pairs_on
            << ", triangles certified embedded " << cray.counted << "\n";
  EXPECT_EQ(cray.certified, 8u);
  EXPECT_GE(cray.counted, 16u) << "the slab's top triangles are no longer certified embedded";
  EXPECT_LT(cray.pairs_on, cray.pairs_off);
}

// ---- cert18: a whole level patch at once (LevelPatch in fold_certificate.cpp)

/// Brute force: x (corners given by canonical id: a patch vertex's id keeps
/// its rounded position, other ids are new points) crosses some piece of
/// the patch (exact triangles_cross, corners merged by id).
bool crosses_some_piece(const GridPatch& g, const std::array<Vec3d, 3>& x, const std::array<std::uint32_t, 3>& x_ids) {
  TriMesh m;
  const auto n = static_cast<std::uint32_t>(g.cut.canon.size());
  for (std::uint32_t k = 0; k < n; ++k) m.p.push_back(g.cut.position(g.a, g.b, k));
  std::array<std::uint32_t, 3> tx{};
  for (std::size_t c = 0; c < 3; ++c) {
    if (x_ids[c] < n) {
      tx[c] = x_ids[c];
    } else {
      m.p.push_back(x[c]);
      tx[c] = static_cast<std::uint32_t>(m.p.size() - 1);
    }
  }
  m.tri = g.cut.sides[0].piece;
  const auto ix = static_cast<std::uint32_t>(m.tri.size());
  m.tri.push_back(tx);
  for (std::uint32_t y = 0; y < ix; ++y)
    if (net_detail::triangles_cross(m, ix, y)) return true;
  return false;
}

// The level-patch rule against brute force: a patch (one cut triangle or
// two sharing an edge) in a plane z = l, cut into a grid of levels 2-5, its
// new points moved in the plane (by a few ulps to more than the spacing, so
// some patches fold and must not count as embedded), sometimes with a
// corner at 3.4e38 (Cray's fan); x touches the plane in nothing, a patch
// vertex (by id, or a new id at the same place), a patch edge, two patch
// vertices that are not an edge, a point inside or on an edge of a piece,
// with its other corners above, or on both sides. Whatever the rule calls
// apart from the whole patch crosses none of its pieces by the exact test.
TEST(NetCertificateLevelPatch, RuleAgreesWithTheExactTestOnEveryPiece) {
  std::mt19937_64 rng(1818);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int trials = std::getenv("ATELIER_SKIP_LONG_TESTS") != nullptr ? 200 : 800;
  const double scales[] = {0x1p-50, 1e-9, 0.05, 0.3, 0.7, 1.2};
  int apart = 0, meeting = 0, refused_apart = 0, folded_patches = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const bool two = trial % 2 == 1;
    const int level = 2 + (trial / 2) % 4;
    const double l = trial % 3 == 0 ? -100.0 : 0.375 * unit(rng);
    std::array<Vec3d, 4> c;
    for (auto& p : c) p = Vec3d(unit(rng), unit(rng), l);
    const bool far = trial % 7 == 0;
    if (far) c[2] = Vec3d(-3.4028234699999998e+38, 3.4028234699999998e+38, l);
    const Vec3d mid = (c[0] + c[1]) * 0.5;
    c[3] = mid - (c[2] - mid) * (0.5 + 0.5 * std::abs(unit(rng)));
    c[3].z() = l;
    if (far) c[3] = Vec3d(3.4028234699999998e+38, -3.4028234699999998e+38, l);
    if (net_detail::collinear(c[0], c[1], c[2])) continue;
    GridPatch g = grid_patch(c, level, two);
    const double h = (c[1] - c[0]).norm() / level;
    const double scale = scales[static_cast<std::size_t>(trial / 2) % std::size(scales)];
    for (auto& p : g.cut.new_points) {
      if (far && std::abs(p.x()) > 1e30) continue;  // a fan point: keep it where the grid put it
      p += Vec3d(unit(rng), unit(rng), 0.0) * (scale * h);
    }
    const std::uint32_t u0[1] = {0}, uw[2] = {0, 1};
    const std::span<const std::uint32_t> tris =
        two ? std::span<const std::uint32_t>(uw) : std::span<const std::uint32_t>(u0);
    if (!net_detail::rounded_pieces_embedded(g.cut, g.a, g.b, 0, tris)) ++folded_patches;
    const auto n = static_cast<std::uint32_t>(g.cut.canon.size());
    const auto& pieces = g.cut.sides[0].piece;
    for (int q = 0; q < 12; ++q) {
      std::array<Vec3d, 3> x;
      std::array<std::uint32_t, 3> x_ids = {n, n + 1, n + 2};
      const int kind = static_cast<int>(rng() % 7);
      int n_on = 0;
      auto vertex = [&](std::size_t c2, std::uint32_t id) {
        x[c2] = g.cut.position(g.a, g.b, id);
        x_ids[c2] = id;
      };
      const auto& piece = pieces[rng() % pieces.size()];
      const std::size_t e = rng() % 3;
      if (kind == 1) {  // a patch vertex by id
        vertex(0, piece[e]);
        n_on = 1;
      } else if (kind == 2) {  // a patch edge by ids
        vertex(0, piece[e]);
        vertex(1, piece[(e + 1) % 3]);
        n_on = 2;
      } else if (kind == 3) {  // two patch vertices, most often not an edge
        vertex(0, piece[e]);
        vertex(1, static_cast<std::uint32_t>(rng() % n));
        if (x_ids[1] == x_ids[0]) continue;
        n_on = 2;
      } else if (kind == 4) {  // a patch vertex's place under a new id
        x[0] = g.cut.position(g.a, g.b, piece[e]);
        n_on = 1;
      } else if (kind == 5) {  // a point inside a piece, or on its edge
        const Vec3d p0 = g.cut.position(g.a, g.b, piece[0]), p1 = g.cut.position(g.a, g.b, piece[1]),
                    p2 = g.cut.position(g.a, g.b, piece[2]);
        const double s = std::abs(unit(rng)), t = std::abs(unit(rng)) * (1 - s);
        x[0] = rng() % 2 == 0 ? Vec3d(p0 + (p1 - p0) * s + (p2 - p0) * t) : Vec3d(p0 + (p1 - p0) * 0.5);
        x[0].z() = l;
        n_on = 1;
        if (rng() % 2 == 0) {  // and an edge from a patch vertex to it
          vertex(1, piece[e]);
          n_on = 2;
        }
      } else if (kind == 6) {  // a corner of the net triangle (Cray's side faces)
        vertex(0, static_cast<std::uint32_t>(rng() % (two ? 4 : 3)));
        n_on = 1;
      }
      const bool both_sides = rng() % 6 == 0;
      for (int c2 = n_on; c2 < 3; ++c2) {
        const double up = both_sides && c2 == 2 ? -1.0 : 1.0;
        x[static_cast<std::size_t>(c2)] =
            Vec3d(1.2 * unit(rng), 1.2 * unit(rng), l + up * (rng() % 4 == 0 ? 1e-12 : 0.01 + std::abs(unit(rng))));
      }
      if (net_detail::collinear(x[0], x[1], x[2])) continue;
      const bool says = net_detail::level_patch_pieces_apart(g.cut, g.a, g.b, 0, tris, x, x_ids);
      const bool crosses = crosses_some_piece(g, x, x_ids);
      if (says) {
        ++apart;
        EXPECT_FALSE(crosses) << "trial " << trial << " query " << q << " (kind " << kind << ", level " << level
                              << ", scale " << scale << "): called apart, but x crosses a piece";
      } else {
        crosses ? ++meeting : ++refused_apart;
      }
    }
  }
  std::cout << "apart " << apart << ", meeting (refused) " << meeting << ", refused but apart " << refused_apart
            << ", folded patches " << folded_patches << "\n";
  EXPECT_GE(apart, trials * 2);
  EXPECT_GE(meeting, trials / 2);
  EXPECT_GE(folded_patches, trials / 20);
}

/// cert18's rule on and off (cert17's certificate).
void compare_level_rule(const PolygonSoup& a, const PolygonSoup& b, const std::string& what, Compared& out) {
  compare_rule(a, b, what, net_detail::set_level_patch_rule, net_detail::level_patch_counts().skips, out);
}

// The Booleans: the level-patch rule changes no verdict and no byte; on a
// 1e30 slab with a sphere and on Cray (the slab top's fan against
// Cray_left's cut triangles and the slab's side faces) it removes most of
// the pairs cert17's certificate tests.
TEST(NetCertificateLevelPatch, RuleKeepsVerdictsAndBytes) {
  Compared slab;
  compare_level_rule(net_test::box_triangles({-1e30, -1e30, -1e30}, {1e30, 1e30, -100.0}),
                     net_test::icosphere(3, 2.5e4, {3.0, -7.0, -100.0}), "slab and sphere", slab);
  std::cout << "slab and sphere: certified " << slab.certified << " of 8, pairs " << slab.pairs_off << " -> "
            << slab.pairs_on << ", skips " << slab.counted << "\n";
  EXPECT_GE(slab.certified, 1u);
  EXPECT_LE(slab.pairs_on, slab.pairs_off);
  if (!std::filesystem::exists(kPairs)) GTEST_SKIP() << "shared data absent: " << kPairs;
  Compared cray;
  compare_level_rule(net_polygons(read_obj(kPairs / "Cray_left.obj")),
                     net_polygons(read_obj(kPairs / "Cray_right.obj")), "Cray", cray);
  std::cout << "Cray: certified " << cray.certified << " of 8, pairs " << cray.pairs_off << " -> " << cray.pairs_on
            << ", skips " << cray.counted << "\n";
  EXPECT_EQ(cray.certified, 8u);
  EXPECT_GT(cray.counted, 0u);
  EXPECT_LT(cray.pairs_on * 5, cray.pairs_off * 3) << "the rule no longer decides the pairs against the slab top";
}

// ---- cert19: the hierarchy walks shared by neighbouring cut triangles

// The Booleans: walking the hierarchies once per group of neighbouring cut
// triangles tests exactly the pairs the walks per triangle test (a member's
// query keeps the group's finds whose boxes meet its own), so the same
// verdict, the same pair count and the same bytes, on 1 and 2 threads, with
// fewer walks.
TEST(NetCertificateWalk, GroupedWalksKeepPairsVerdictsAndBytes) {
  auto walks = [](const PolygonSoup& a, const PolygonSoup& b, bool grouped) {
    net_detail::set_grouped_walk(grouped);
    const std::size_t w0 = net_detail::cert_walk_counts().walks;
    BooleanOptions o;
    o.op = BooleanOp::kUnion;
    ExecContext ctx;
    ctx.threads = 1;
    EXPECT_TRUE(net_boolean(a, b, o, ctx).has_value());
    net_detail::set_grouped_walk(true);
    return net_detail::cert_walk_counts().walks - w0;
  };
  Compared shapes;
  const PolygonSoup s0 = net_test::icosphere(3, 1.0, {0, 0, 0}), s1 = net_test::icosphere(3, 0.9, {0.31, 0.17, 0.05});
  compare_rule(s0, s1, "icospheres", net_detail::set_grouped_walk, net_detail::cert_walk_counts().walks, shapes);
  compare_rule(net_test::box_triangles({-1e30, -1e30, -1e30}, {1e30, 1e30, -100.0}),
               net_test::icosphere(3, 2.5e4, {3.0, -7.0, -100.0}), "slab and sphere", net_detail::set_grouped_walk,
               net_detail::cert_walk_counts().walks, shapes);
  std::cout << "icospheres and slab: certified " << shapes.certified << " of 16, pairs " << shapes.pairs_off
            << " -> " << shapes.pairs_on << "\n";
  EXPECT_GE(shapes.certified, 9u);
  EXPECT_EQ(shapes.pairs_on, shapes.pairs_off) << "a member's query lost or gained pairs";
  const std::size_t alone = walks(s0, s1, false), grouped = walks(s0, s1, true);
  std::cout << "icospheres' union: walks " << alone << " -> " << grouped << "\n";
  EXPECT_LT(grouped * 2, alone);
  if (!std::filesystem::exists(kPairs)) GTEST_SKIP() << "shared data absent: " << kPairs;
  const PolygonSoup left = net_polygons(read_obj(kPairs / "Cray_left.obj"));
  const PolygonSoup right = net_polygons(read_obj(kPairs / "Cray_right.obj"));
  Compared cray;
  compare_rule(left, right, "Cray", net_detail::set_grouped_walk, net_detail::cert_walk_counts().walks, cray);
  const std::size_t cray_alone = walks(left, right, false), cray_grouped = walks(left, right, true);
  std::cout << "Cray: certified " << cray.certified << " of 8, pairs " << cray.pairs_off << " -> " << cray.pairs_on
            << ", union's walks " << cray_alone << " -> " << cray_grouped << "\n";
  EXPECT_EQ(cray.certified, 8u);
  EXPECT_EQ(cray.pairs_on, cray.pairs_off);
  EXPECT_LT(cray_grouped * 2, cray_alone);
}

}  // namespace
}  // namespace atelier::certificate_test
