// The net Booleans' exact predicates (orient3d: Shewchuk's first-stage
// filter, then CGAL's filtered predicate; collinear) against CGAL's exact
// ones, on exactly coplanar and collinear points (grid coordinates, with
// and without a large offset), full mantissas, and tiny and huge scales
// (where the filter's permanent leaves its trusted range); and the output
// coordinates of new intersection points against CGAL's lazy exact
// construction rounded to nearest (ties to even) here.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>

#include "../../../systems/net/boolean_detail.h"
#include "net_shapes.h"

namespace atelier {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

int cgal_orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  auto p = [](const Vec3d& v) { return K::Point_3(v.x(), v.y(), v.z()); };
  const auto o = CGAL::orientation(p(a), p(b), p(c), p(d));
  return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}

bool cgal_collinear(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  auto p = [](const Vec3d& v) { return K::Point_3(v.x(), v.y(), v.z()); };
  return CGAL::collinear(p(a), p(b), p(c));
}

TEST(NetPredicates, Orient3dAndCollinearAgreeWithCgal) {
  std::mt19937_64 rng(24);
  std::uniform_int_distribution<int> grid(-40, 40);
  std::uniform_real_distribution<double> real(-1.0, 1.0);
  std::uniform_int_distribution<int> small(-4, 4);
  int zeros = 0, nonzero = 0, collinear_seen = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const int kind = trial % 5;
    // Grid coordinates (every step exact), a large offset (differences
    // exact, products exact), full mantissas, and tiny and huge scales
    // (products below the trusted range or rounded: the fallback).
    const double scale = kind == 3 ? 1e-130 : (kind == 4 ? 1e100 : 1.0);
    auto point = [&] {
      if (kind == 2) return Vec3d(real(rng), real(rng), real(rng)) * scale;
      const double off = kind == 1 ? 4096.0 : 0.0;
      return Vec3d(off + grid(rng) * 0.125, off + grid(rng) * 0.25, off + grid(rng) * 0.5) * scale;
    };
    const Vec3d a = point(), b = point(), c = point();
    // Every other d exactly coplanar: a + s (b - a) + t (c - a), small
    // integers s, t, exact on the grid.
    Vec3d d = point();
    if (trial % 2 == 0 && kind != 2) d = a + small(rng) * (b - a) + small(rng) * (c - a);
    const int ours = net_detail::orient3d(a, b, c, d), theirs = cgal_orient3d(a, b, c, d);
    ASSERT_EQ(ours, theirs) << "trial " << trial;
    (theirs == 0 ? zeros : nonzero) += 1;
    // Collinear triples: c on the line through a and b half the time.
    const Vec3d e = trial % 2 == 0 && kind != 2 ? a + small(rng) * (b - a) : c;
    const bool col = net_detail::collinear(a, b, e);
    ASSERT_EQ(col, cgal_collinear(a, b, e)) << "trial " << trial;
    collinear_seen += col;
  }
  // Both outcomes were exercised, zeros included.
  EXPECT_GT(zeros, 3000);
  EXPECT_GT(nonzero, 3000);
  EXPECT_GT(collinear_seen, 3000);
}

// The stages after the first filter (an axis plane's comparison, the
// exactly summed cofactor) against CGAL on what reaches them: points of a Cray-like slab
// (coordinates at FLT_MAX = 3.4e38) with small points of full mantissas
// (1e4) on, near and off its planes and diagonals, in every order of the
// four arguments; and near-degenerate small ones one ulp off a plane.
TEST(NetPredicates, Orient3dAgreesWithCgalOnFltMaxSlabsAndNearDegenerateInputs) {
  const double F = 340282346999999984391321947108527833088.0;
  std::mt19937_64 rng(38);
  std::uniform_real_distribution<double> real(-2.5e4, 2.5e4);
  std::uniform_int_distribution<int> pick(0, 7), ulps(-3, 3);
  const std::array<Vec3d, 8> corner = {Vec3d(-F, F, -F),     Vec3d(F, F, -F),     Vec3d(-F, -F, -F),
                                       Vec3d(F, -F, -F),     Vec3d(F, F, -100.0), Vec3d(-F, -F, -100.0),
                                       Vec3d(-F, F, -100.0), Vec3d(F, -F, -100.0)};
  auto nudge = [&](double x) {
    for (int k = ulps(rng); k != 0; k += k > 0 ? -1 : 1) x = std::nextafter(x, k > 0 ? HUGE_VAL : -HUGE_VAL);
    return x;
  };
  int zeros = 0, pos = 0, neg = 0;
  for (int trial = 0; trial < 40000; ++trial) {
    // A small point: generic, on the top plane z = -100, on its diagonal
    // y = -x (exactly, or a few ulps off), or on the plane x = F.
    auto small = [&] {
      const double x = real(rng), y = real(rng), z = real(rng);
      switch (pick(rng) % 5) {
        case 0:
          return Vec3d(x, y, z);
        case 1:
          return Vec3d(x, y, -100.0);
        case 2:
          return Vec3d(x, -x, -100.0);
        case 3:
          return Vec3d(x, nudge(-x), nudge(-100.0));
        default:
          return Vec3d(F, y, z);
      }
    };
    std::array<Vec3d, 4> p;
    const int kind = trial % 4;
    if (kind == 0) {  // three corners of one slab face (a triangle of it), one small point
      p = {corner[4], corner[5], corner[6], small()};
    } else if (kind == 1) {  // a small edge against a slab edge (locate_line)
      p = {small(), small(), corner[static_cast<std::size_t>(pick(rng))], corner[static_cast<std::size_t>(pick(rng))]};
    } else if (kind == 2) {  // a small triangle against a corner
      p = {small(), small(), small(), corner[static_cast<std::size_t>(pick(rng))]};
    } else {  // small points a few ulps off a common plane
      const Vec3d a = small(), b = small(), c = small();
      const double s = real(rng) / 2.5e4, t = real(rng) / 2.5e4;
      const Vec3d d = a + s * (b - a) + t * (c - a);
      p = {a, b, c, Vec3d(nudge(d.x()), nudge(d.y()), nudge(d.z()))};
    }
    std::shuffle(p.begin(), p.end(), rng);
    const int ours = net_detail::orient3d(p[0], p[1], p[2], p[3]), theirs = cgal_orient3d(p[0], p[1], p[2], p[3]);
    ASSERT_EQ(ours, theirs) << "trial " << trial << ": " << p[0].transpose() << " | " << p[1].transpose() << " | "
                            << p[2].transpose() << " | " << p[3].transpose();
    (theirs == 0 ? zeros : (theirs > 0 ? pos : neg)) += 1;
  }
  EXPECT_GT(zeros, 1000);
  EXPECT_GT(pos, 5000);
  EXPECT_GT(neg, 5000);
}

/// The point of key k from CGAL's exact construction, each coordinate
/// rounded to nearest with ties to the even neighbour.
Vec3d oracle_point(const net_detail::TriMesh& a, const net_detail::TriMesh& b, const net_detail::PointKey& k) {
  using Ke = CGAL::Exact_predicates_exact_constructions_kernel;
  using namespace net_detail;
  auto pe = [](const Vec3d& v) { return Ke::Point_3(v.x(), v.y(), v.z()); };
  auto line = [&](const TriMesh& m, std::uint64_t e) {
    return Ke::Line_3(pe(m.p[m.edge[idx_of(e)][0]]), pe(m.p[m.edge[idx_of(e)][1]]));
  };
  auto plane = [&](const TriMesh& m, std::uint64_t f) {
    const auto& t = m.tri[idx_of(f)];
    return Ke::Plane_3(pe(m.p[t[0]]), pe(m.p[t[1]]), pe(m.p[t[2]]));
  };
  const auto r = dim_of(k.a) == kDimEdge && dim_of(k.b) == kDimEdge ? CGAL::intersection(line(a, k.a), line(b, k.b))
                 : dim_of(k.a) == kDimEdge                          ? CGAL::intersection(line(a, k.a), plane(b, k.b))
                                                                    : CGAL::intersection(line(b, k.b), plane(a, k.a));
  const Ke::Point_3* x = r ? boost::get<Ke::Point_3>(&*r) : nullptr;
  if (x == nullptr) return Vec3d::Constant(std::nan(""));
  auto round = [](const Ke::FT& f) {
    const auto& e = CGAL::exact(f);
    const auto iv = CGAL::to_interval(e);
    if (iv.first == iv.second) return iv.first;
    using Q = std::decay_t<decltype(e)>;
    const Q mid = (Q(iv.first) + Q(iv.second)) / 2;
    if (e < mid) return iv.first;
    if (mid < e) return iv.second;
    std::uint64_t bits;
    std::memcpy(&bits, &iv.first, sizeof bits);
    return (bits & 1) == 0 ? iv.first : iv.second;
  };
  return {round(x->x()), round(x->y()), round(x->z())};
}

bool within_four_ulps(double lo, double hi) {
  for (int i = 0; i < 4 && lo < hi; ++i) lo = std::nextafter(lo, hi);
  return lo >= hi;
}

TEST(NetPredicates, NewPointsAreTheExactPointsRoundedToNearest) {
  using namespace net_detail;
  using namespace net_test;
  // Boxes on a grid of 0.15 (not dyadic: the points are not doubles),
  // with coplanar faces, so two edges cross on them; and two icospheres
  // (edges through triangles, generic).
  std::uint64_t seed = 11;
  std::vector<std::pair<PolygonSoup, PolygonSoup>> pairs;
  for (int i = 0; i < 40; ++i) {
    Vec3d lo[2], hi[2];
    grid_box_pair(seed, lo, hi);
    pairs.emplace_back(box_triangles(0.3 * lo[0], 0.3 * hi[0]), box_triangles(0.3 * lo[1], 0.3 * hi[1]));
  }
  pairs.emplace_back(icosphere(2, 1.0, {0, 0, 0}), icosphere(2, 0.9, {0.7, 0.3, 0.1}));
  int edge_edge = 0, edge_face = 0;
  for (const auto& [sa, sb] : pairs) {
    TriMesh a, b;
    ASSERT_TRUE(build_tri_mesh(sa, "A", a, {}));
    ASSERT_TRUE(build_tri_mesh(sb, "B", b, {}));
    const ExactPointsPtr none = make_exact_points(a, b, {}, {}, {});
    PairHit hit;
    for (std::uint32_t ta = 0; ta < a.tri.size(); ++ta)
      for (std::uint32_t tb = 0; tb < b.tri.size(); ++tb) {
        intersect_pair(a, ta, b, tb, hit);
        for (const PointKey& k : hit.points) {
          if (dim_of(k.a) == kDimVertex || dim_of(k.b) == kDimVertex) continue;
          const PointBox box = point_box(a, b, k);
          const bool ee = dim_of(k.a) == kDimEdge && dim_of(k.b) == kDimEdge;
          // A pinned edge-face box gives its centre by design (glossary).
          if (!ee && box.ok && within_four_ulps(box.b[0], box.b[3]) && within_four_ulps(box.b[1], box.b[4]) &&
              within_four_ulps(box.b[2], box.b[5]))
            continue;
          const Vec3d got = point_coordinates(a, b, k, box, *none, 0);
          const Vec3d want = oracle_point(a, b, k);
          ASSERT_EQ(std::memcmp(&got, &want, sizeof got), 0)
              << got.transpose() << " vs " << want.transpose() << (ee ? " (two edges)" : " (edge, face)");
          (ee ? edge_edge : edge_face) += 1;
        }
      }
  }
  EXPECT_GT(edge_edge, 100) << edge_face;
  EXPECT_GT(edge_face, 50);
}

// The root cause of issue 24's refused slab placements (round 13): the
// certified winding number of a centroid whose interval box is wide (a
// corner on Cray's slab diagonal, corners at FLT_MAX: a box ~1e23 wide)
// culled the other net's hierarchy by the segment from the box's centre
// (~1e22 away from a sphere of radius 2.5e4), so no predicate was
// uncertain and it returned 0 for a centroid inside: the pieces of the
// disc the sphere cuts from the slab were all dropped (an intersection)
// and the result had unmatched edges. Expectation by convexity: a point
// on the sphere (the diagonal's crossing) and two of its vertices off
// that point's face have their centroid strictly inside.
TEST(NetPredicates, CentroidWindingWithAWideBoxIsTheExactOne) {
  using namespace net_detail;
  using namespace net_test;
  const double big = 340282346999999984391321947108527833088.0;  // FLT_MAX, as Cray_right's OBJ writes it
  TriMesh a, b;
  ASSERT_TRUE(build_tri_mesh(icosphere(1, 2.5e4, {3.0, -7.0, -100.0}), "A", a, {}));
  ASSERT_TRUE(build_tri_mesh(box_triangles({-big, -big, -big}, {big, big, -100.0}), "B", b, {}));
  Bvh bvh;
  build_bvh(a, bvh, {});
  const ExactPointsPtr none = make_exact_points(a, b, {}, {}, {});
  PairHit hit;
  int wide = 0;
  for (std::uint32_t ta = 0; ta < a.tri.size(); ++ta)
    for (std::uint32_t tb = 0; tb < b.tri.size(); ++tb) {
      intersect_pair(a, ta, b, tb, hit);
      for (const PointKey& k : hit.points) {
        if (dim_of(k.a) != kDimFace || dim_of(k.b) != kDimEdge) continue;  // A's face by the slab's diagonal
        const PointBox box = point_box(a, b, k);
        ASSERT_TRUE(box.ok);
        if (!(box.b[3] - box.b[0] > 1e20)) continue;
        ++wide;
        const Vec3d x = point_coordinates(a, b, k, box, *none, 0);
        const auto& t = a.tri[idx_of(k.a)];
        // The two vertices farthest from x, neither a corner of its face.
        std::vector<std::pair<double, std::uint32_t>> far;
        for (std::uint32_t v = 0; v < a.net_vertices; ++v)
          if (v != t[0] && v != t[1] && v != t[2]) far.emplace_back(-(a.p[v] - x).squaredNorm(), v);
        std::sort(far.begin(), far.end());
        const std::array<PointKey, 3> corners{k, PointKey{simplex(kDimVertex, far[0].second), kNoSimplex},
                                              PointKey{simplex(kDimVertex, far[1].second), kNoSimplex}};
        EXPECT_EQ(winding_number(a, bvh, (x + a.p[far[0].second] + a.p[far[1].second]) / 3.0), 1);
        EXPECT_EQ(winding_number_centroid(a, bvh, a, b, corners, {nullptr, nullptr, nullptr}), 1);
        EXPECT_EQ(winding_number_centroid(a, bvh, a, b, corners, {&box, nullptr, nullptr}), 1)
            << "box x [" << box.b[0] << ", " << box.b[3] << "]";
      }
    }
  EXPECT_GE(wide, 2);  // the diagonal enters and leaves the sphere
}

}  // namespace
}  // namespace atelier
