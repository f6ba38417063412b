// The cut's cheap exact rules (issue 24, round 15) against CGAL's exact
// predicates: orient3d's level-edge rule (an edge level in one coordinate
// against a segment across that level, decided by two filtered orient2d of
// the segment's ends) and locate_line's box rejection (a segment through a
// triangle's plane apart from the triangle's box misses it), on Cray's
// FLT_MAX slab, small full-mantissa points, points a few ulps off the edge
// in the projection, ends on the level, shared and touching corners.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

#include "../../../systems/net/boolean_detail.h"
#include "net_shapes.h"

namespace atelier {
namespace {

using CutFiltersK = CGAL::Exact_predicates_inexact_constructions_kernel;

CutFiltersK::Point_3 cut_filters_point(const Vec3d& v) {
  return {v.x(), v.y(), v.z()};
}

int cut_filters_cgal_orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  const auto o =
      CGAL::orientation(cut_filters_point(a), cut_filters_point(b), cut_filters_point(c), cut_filters_point(d));
  return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}

// Every argument order of orient3d (even orders give the sign, odd ones
// its opposite) against CGAL's exact orientation.
void expect_orient3d_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d, int& nonzero) {
  const std::array<const Vec3d*, 4> v{&a, &b, &c, &d};
  static constexpr std::array<std::array<int, 4>, 6> kOrders{
      {{0, 1, 2, 3}, {2, 3, 0, 1}, {1, 0, 3, 2}, {3, 2, 1, 0}, {0, 1, 3, 2}, {2, 3, 1, 0}}};
  for (const auto& o : kOrders) {
    const Vec3d &p = *v[static_cast<std::size_t>(o[0])], &q = *v[static_cast<std::size_t>(o[1])],
                &r = *v[static_cast<std::size_t>(o[2])], &s = *v[static_cast<std::size_t>(o[3])];
    const int want = cut_filters_cgal_orient3d(p, q, r, s);
    ASSERT_EQ(net_detail::orient3d(p, q, r, s), want)
        << p.transpose() << " | " << q.transpose() << " | " << r.transpose() << " | " << s.transpose();
    nonzero += want != 0;
  }
}

TEST(NetCutFilters, LevelEdgeRuleAgreesWithCgal) {
  const double F = 340282346999999984391321947108527833088.0;
  std::mt19937_64 rng(1515);
  std::uniform_real_distribution<double> real(-2.5e4, 2.5e4), unit(-1.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 5), axis(0, 2), ulps(-3, 3);
  auto nudge = [&](double x) {
    for (int k = ulps(rng); k != 0; k += k > 0 ? -1 : 1) x = std::nextafter(x, k > 0 ? HUGE_VAL : -HUGE_VAL);
    return x;
  };
  int nonzero = 0;
  for (int trial = 0; trial < 30000; ++trial) {
    const int k = axis(rng), u = (k + 1) % 3, w = (k + 2) % 3;
    // The level edge cd: Cray's slab (FLT_MAX corners, its diagonal and its
    // perimeter), or a small full-mantissa one.
    Vec3d c, d;
    const double level = pick(rng) < 2 ? -100.0 : real(rng);
    c[k] = d[k] = level;
    switch (pick(rng)) {
      case 0:  // the slab's perimeter
        c[u] = F, c[w] = -F, d[u] = F, d[w] = F;
        break;
      case 1:  // its diagonal
        c[u] = -F, c[w] = -F, d[u] = F, d[w] = F;
        break;
      case 2:  // a corner at FLT_MAX, one small
        c[u] = F, c[w] = real(rng), d[u] = real(rng), d[w] = real(rng);
        break;
      default:
        c[u] = real(rng), c[w] = real(rng), d[u] = real(rng), d[w] = real(rng);
    }
    // The segment ab across the level (or with an end on it); its ends in
    // the projection generic, on the line cd (a few ulps off), or equal to c.
    auto end = [&](bool above) {
      Vec3d p;
      const double t = unit(rng);
      switch (pick(rng)) {
        case 0:
        case 1:  // near the line cd in the projection (the filter's hard case)
          p[u] = nudge(c[u] + t * (d[u] - c[u]));
          p[w] = nudge(c[w] + t * (d[w] - c[w]));
          break;
        case 2:  // exactly c's projection
          p[u] = c[u], p[w] = c[w];
          break;
        default:
          p[u] = real(rng), p[w] = real(rng);
      }
      const double off = std::abs(real(rng));
      p[k] = pick(rng) == 0 ? level : (above ? nudge(level + off) : nudge(level - off));
      return p;
    };
    const Vec3d a = end(true), b = end(false);
    expect_orient3d_exact(a, b, c, d, nonzero);
    if (::testing::Test::HasFatalFailure()) return;
  }
  EXPECT_GT(nonzero, 100000);  // of 180,000: most are not degenerate
}

// The keys of one pair that name edge e of `self`'s triangle (side 0: A's
// edges, k.a; side 1: B's, k.b).
bool names_edge(const net_detail::PairHit& hit, int side, std::uint32_t e) {
  for (const net_detail::PointKey& k : hit.points)
    if ((side == 0 ? k.a : k.b) == net_detail::simplex(net_detail::kDimEdge, e)) return true;
  return false;
}

// An edge whose ends lie strictly on either side of the other triangle's
// plane meets it (CGAL's exact do_intersect) exactly when intersect_pair
// names it: the rejection by boxes must never drop a crossing.
void expect_edges_named(const net_detail::TriMesh& self, std::uint32_t ts, const net_detail::TriMesh& other,
                        std::uint32_t to, int side, const net_detail::PairHit& hit, int& crossings, int& misses) {
  using EK = CGAL::Exact_predicates_exact_constructions_kernel;
  auto pe = [](const Vec3d& v) { return EK::Point_3(v.x(), v.y(), v.z()); };
  const auto& ov = other.tri[to];
  const EK::Triangle_3 tri(pe(other.p[ov[0]]), pe(other.p[ov[1]]), pe(other.p[ov[2]]));
  for (std::size_t k = 0; k < 3; ++k) {
    const std::uint32_t e = self.tri_edge[ts][k];
    const Vec3d &p = self.p[self.tri[ts][k]], &q = self.p[self.tri[ts][(k + 1) % 3]];
    const int sp = cut_filters_cgal_orient3d(other.p[ov[0]], other.p[ov[1]], other.p[ov[2]], p);
    const int sq = cut_filters_cgal_orient3d(other.p[ov[0]], other.p[ov[1]], other.p[ov[2]], q);
    if (sp * sq >= 0) continue;
    const bool meets = CGAL::do_intersect(EK::Segment_3(pe(p), pe(q)), tri);
    ASSERT_EQ(names_edge(hit, side, e), meets)
        << "side " << side << " triangle " << ts << " edge " << k << " against triangle " << to;
    (meets ? crossings : misses) += 1;
  }
}

TEST(NetCutFilters, BoxRejectionNeverDropsACrossing) {
  using namespace net_detail;
  using namespace net_test;
  // The slab against spheres across its top (Cray's case: slab edges at
  // FLT_MAX through the spheres' planes, far from their triangles), and
  // small pairs with shared, touching and crossing corners: boxes on a
  // grid with coplanar faces, and two icospheres.
  std::vector<std::pair<PolygonSoup, PolygonSoup>> pairs;
  for (PolygonSoup& s : spheres_across_the_slab(3)) pairs.emplace_back(flt_max_slab(), std::move(s));
  std::uint64_t seed = 15;
  for (int i = 0; i < 20; ++i) {
    Vec3d lo[2], hi[2];
    grid_box_pair(seed, lo, hi);
    pairs.emplace_back(box_triangles(lo[0], hi[0]), box_triangles(lo[1], hi[1]));
  }
  pairs.emplace_back(icosphere(2, 1.0, {0, 0, 0}), icosphere(2, 0.9, {0.7, 0.3, 0.1}));
  int crossings = 0, misses = 0;
  for (const auto& [sa, sb] : pairs) {
    TriMesh a, b;
    ASSERT_TRUE(build_tri_mesh(sa, "A", a, {}));
    ASSERT_TRUE(build_tri_mesh(sb, "B", b, {}));
    PairHit hit;
    for (std::uint32_t ta = 0; ta < a.tri.size(); ++ta)
      for (std::uint32_t tb = 0; tb < b.tri.size(); ++tb) {
        intersect_pair(a, ta, b, tb, hit);
        expect_edges_named(a, ta, b, tb, 0, hit, crossings, misses);
        expect_edges_named(b, tb, a, ta, 1, hit, crossings, misses);
        if (::testing::Test::HasFatalFailure()) return;
      }
  }
  // Both outcomes occur often (the slab's far edges are the misses the
  // boxes reject).
  EXPECT_GT(crossings, 500) << misses;
  EXPECT_GT(misses, 1000) << crossings;
}

}  // namespace
}  // namespace atelier
