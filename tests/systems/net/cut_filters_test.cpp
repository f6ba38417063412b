// The cut's far orient3d questions (issue 24, round 15) against CGAL's
// exact predicates: orient3d keeps a per-thread memo of the questions that
// reach its cofactor stage (an edge against a 3.4e38 edge of Cray's slab),
// keyed up to the argument orders that keep or flip the sign, so every
// order of every question, asked again and again, must still get CGAL's
// exact sign; and intersect_pair names exactly the edges that cross the
// other triangle (CGAL's exact do_intersect), on the slab, boxes with
// shared, touching and coplanar faces, and spheres.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>

#include <algorithm>
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

// All 24 argument orders of orient3d (the sign of the permutation times
// the sign) against CGAL's exact orientation of the first order.
void expect_orient3d_exact(const std::array<Vec3d, 4>& v, int& nonzero) {
  const int want = cut_filters_cgal_orient3d(v[0], v[1], v[2], v[3]);
  std::array<int, 4> o{0, 1, 2, 3};
  do {
    int parity = 1;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (o[static_cast<std::size_t>(i)] > o[static_cast<std::size_t>(j)]) parity = -parity;
    const Vec3d &p = v[static_cast<std::size_t>(o[0])], &q = v[static_cast<std::size_t>(o[1])],
                &r = v[static_cast<std::size_t>(o[2])], &s = v[static_cast<std::size_t>(o[3])];
    ASSERT_EQ(net_detail::orient3d(p, q, r, s), parity * want)
        << p.transpose() << " | " << q.transpose() << " | " << r.transpose() << " | " << s.transpose();
  } while (std::next_permutation(o.begin(), o.end()));
  nonzero += want != 0;
}

TEST(NetCutFilters, FarOrientationsAgreeWithCgalInEveryOrderAndRepeated) {
  const double F = 340282346999999984391321947108527833088.0;
  std::mt19937_64 rng(1515);
  std::uniform_real_distribution<double> real(-2.5e4, 2.5e4), unit(-1.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 5), ulps(-3, 3);
  auto nudge = [&](double x) {
    for (int k = ulps(rng); k != 0; k += k > 0 ? -1 : 1) x = std::nextafter(x, k > 0 ? HUGE_VAL : -HUGE_VAL);
    return x;
  };
  // The slab's edges (its top's diagonal and perimeter, its sides) and
  // short edges near them: generic, ends on the top, a few ulps off the
  // diagonal in the projection, sharing a corner.
  const std::array<std::array<Vec3d, 2>, 4> slab_edges{{{Vec3d(-F, -F, -100.0), Vec3d(F, F, -100.0)},
                                                        {Vec3d(F, -F, -100.0), Vec3d(F, F, -100.0)},
                                                        {Vec3d(-F, F, -100.0), Vec3d(-F, -F, -F)},
                                                        {Vec3d(F, F, -F), Vec3d(-F, F, -100.0)}}};
  std::vector<std::array<Vec3d, 4>> questions;
  for (int trial = 0; trial < 3000; ++trial) {
    const auto& e = slab_edges[static_cast<std::size_t>(trial) % slab_edges.size()];
    auto end = [&] {
      const double t = unit(rng), z = pick(rng) == 0 ? -100.0 : real(rng);
      switch (pick(rng)) {
        case 0:
        case 1:  // a few ulps off the diagonal's projection
          return Vec3d(nudge(1e4 * t), nudge(1e4 * t), z);
        case 2:  // a corner of the slab edge
          return e[0];
        default:
          return Vec3d(real(rng), real(rng), z);
      }
    };
    Vec3d a = end(), b = end();
    if (a == b) b.z() += 1.0;
    questions.push_back({a, b, e[0], e[1]});
  }
  int nonzero = 0;
  // Twice over, the second time in reverse: each question meets the memo
  // filled by itself in every order and by its neighbours.
  for (int round = 0; round < 2; ++round)
    for (std::size_t i = 0; i < questions.size(); ++i) {
      expect_orient3d_exact(questions[round == 0 ? i : questions.size() - 1 - i], nonzero);
      if (::testing::Test::HasFatalFailure()) return;
    }
  EXPECT_GT(nonzero, 4000);  // of 6,000: most are not degenerate
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
// names it.
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

TEST(NetCutFilters, IntersectPairNamesExactlyTheCrossingEdges) {
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
  // Both outcomes occur often (the slab's far edges mostly miss).
  EXPECT_GT(crossings, 500) << misses;
  EXPECT_GT(misses, 1000) << crossings;
}

}  // namespace
}  // namespace atelier
