// The net Booleans' exact predicates (orient3d: Shewchuk's first-stage
// filter, then CGAL's filtered predicate; collinear) against CGAL's exact
// ones, on exactly coplanar and collinear points (grid coordinates, with
// and without a large offset), full mantissas, and tiny and huge scales
// (where the filter's permanent leaves its trusted range).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gtest/gtest.h>

#include <random>

#include "../../../systems/net/boolean_detail.h"

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

}  // namespace
}  // namespace atelier
