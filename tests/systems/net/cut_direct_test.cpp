// The Cray cut's shortcuts (issue 24, cray16) against their references:
// round_edge_through_level_plane (Shewchuk's expansions) must give the
// exact value rounded to nearest, ties to even, as CGAL's exact rational
// says, on edges crossing planes of constant coordinate at every scale
// (FLT_MAX slabs, small CAD boxes, full mantissas, exact midpoints); and
// the two-point split of a cut triangle without CGAL's CDT must give the
// CDT path's results byte for byte (the same triangles in the same order,
// so the same soups and volumes), on random pairs, in every operation.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <random>

#include "../../../systems/net/boolean_detail.h"
#include "net_shapes.h"

namespace atelier {
namespace {

using CutDirectKe = CGAL::Exact_predicates_exact_constructions_kernel;
using CutDirectFT = CutDirectKe::FT;

/// An exact rational rounded to nearest, ties to even, +0 for a zero:
/// point_coordinates' rule for the lazy kernel's values.
double cut_direct_round(const CutDirectFT& x) {
  const auto& e = CGAL::exact(x);
  const std::pair<double, double> iv = CGAL::to_interval(e);
  if (!(iv.first < iv.second)) return iv.first + 0.0;
  using Q = std::decay_t<decltype(e)>;
  const Q mid = (Q(iv.first) + Q(iv.second)) / 2;
  if (e < mid) return iv.first + 0.0;
  if (mid < e) return iv.second + 0.0;
  return iv.first + 0.5 * (iv.second - iv.first) + 0.0;
}

/// The reference: the edge's point on the plane x_k = level, exactly.
Vec3d cut_direct_reference(const Vec3d& p, const Vec3d& q, int k, double level) {
  const CutDirectFT pk(p[k]), qk(q[k]), lv(level);
  const CutDirectFT t = (lv - pk) / (qk - pk);
  Vec3d x;
  for (int j = 0; j < 3; ++j) x[j] = cut_direct_round(CutDirectFT(p[j]) + t * (CutDirectFT(q[j]) - CutDirectFT(p[j])));
  return x;
}

bool cut_direct_same_bits(const Vec3d& a, const Vec3d& b) {
  for (int j = 0; j < 3; ++j)
    if (std::bit_cast<std::uint64_t>(a[j]) != std::bit_cast<std::uint64_t>(b[j])) return false;
  return true;
}

TEST(NetCutDirect, LevelPlaneRoundingIsTheExactValueRoundedToNearest) {
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> axis(0, 2), expo(-60, 120);
  int checked = 0, taken = 0, ties = 0;
  for (int trial = 0; trial < 6000; ++trial) {
    const int k = axis(rng);
    const int kind = trial % 4;
    const double scale = std::ldexp(1.0, expo(rng));
    double level = unit(rng) * scale;
    if (kind == 3) level = -100.0;  // Cray's slab top
    Vec3d p, q;
    for (int j = 0; j < 3; ++j) {
      p[j] = unit(rng) * scale;
      q[j] = unit(rng) * scale;
    }
    // The ends on both sides of the plane.
    const double reach = std::max(scale, std::abs(level));  // the ends off the plane in doubles
    p[k] = level + (std::abs(unit(rng)) + 1e-3) * reach;
    q[k] = level - (std::abs(unit(rng)) + 1e-3) * reach;
    if (kind == 1) {
      // An exact midpoint: symmetric ends, so t = 1/2 and x_j = (p_j + q_j) / 2,
      // with p_j + q_j an odd multiple of the smallest ulp: a tie.
      q[k] = level - (p[k] - level);
      if (p[k] - level != level - q[k]) continue;
      for (int j = 0; j < 3; ++j)
        if (j != k) q[j] = std::nextafter(p[j], HUGE_VAL) + (trial % 8 == 1 ? 0.0 : unit(rng) * 1e-6 * scale);
    }
    if (kind == 2) {
      // Ends a full FLT_MAX-sized edge apart, crossing near a small point.
      for (int j = 0; j < 3; ++j)
        if (j != k) {
          p[j] = unit(rng) * 3.4e38;
          q[j] = -p[j] + unit(rng) * 1e4;
        }
    }
    const Vec3d want = cut_direct_reference(p, q, k, level);
    Vec3d got(NAN, NAN, NAN);
    ++checked;
    if (!net_detail::round_edge_through_level_plane(p, q, k, level, got)) continue;
    ++taken;
    ties += kind == 1;
    EXPECT_TRUE(cut_direct_same_bits(got, want)) << "trial " << trial << " k " << k << ": got (" << got.transpose() << ") want ("
                                      << want.transpose() << ")";
  }
  EXPECT_GT(checked, 5000);
  EXPECT_GT(taken, checked * 9 / 10);  // refused only for zero or tiny coordinates
  EXPECT_GT(ties, 1000);
}

TEST(NetCutDirect, LevelPlaneRoundingRefusesWhatItCannotTell) {
  Vec3d x(7, 7, 7);
  // The edge in the plane.
  EXPECT_FALSE(net_detail::round_edge_through_level_plane({0, 0, 1}, {1, 1, 1}, 2, 1.0, x));
  // Huge coordinates (products would overflow).
  EXPECT_FALSE(net_detail::round_edge_through_level_plane({1e300, 0, 1}, {-1e300, 1, -1}, 2, 0.0, x));
  // A coordinate rounding to zero (the guess is zero).
  EXPECT_FALSE(net_detail::round_edge_through_level_plane({-1, 1, 1}, {1, 1, -1}, 2, 0.0, x));
  EXPECT_EQ(x, Vec3d(7, 7, 7));
  // Cray-like: a small edge across the slab's top.
  ASSERT_TRUE(net_detail::round_edge_through_level_plane({1234.5, -77.25, -99.0}, {1240.0, -70.0, -101.5}, 2, -100.0, x));
  EXPECT_TRUE(cut_direct_same_bits(x, cut_direct_reference({1234.5, -77.25, -99.0}, {1240.0, -70.0, -101.5}, 2, -100.0)));
  EXPECT_EQ(x.z(), -100.0);
}

/// Byte-for-byte equal Boolean results (or the same refusal).
::testing::AssertionResult cut_direct_same(const Expected<BooleanReport>& x, const Expected<BooleanReport>& y) {
  if (x.has_value() != y.has_value()) return ::testing::AssertionFailure() << "one refused, the other not";
  if (!x) {
    if (x.status().message() == y.status().message()) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << x.status().to_string() << " vs " << y.status().to_string();
  }
  const PolygonSoup &a = x->result, &b = y->result;
  if (a.positions.size() != b.positions.size() || a.face_nodes != b.face_nodes || a.face_offsets != b.face_offsets)
    return ::testing::AssertionFailure() << "faces differ (" << a.face_count() << " / " << b.face_count() << ")";
  for (std::size_t i = 0; i < a.positions.size(); ++i)
    if (!cut_direct_same_bits(a.positions[i], b.positions[i])) return ::testing::AssertionFailure() << "position " << i << " differs";
  if (std::bit_cast<std::uint64_t>(x->volume) != std::bit_cast<std::uint64_t>(y->volume) ||
      std::bit_cast<std::uint64_t>(x->area) != std::bit_cast<std::uint64_t>(y->area))
    return ::testing::AssertionFailure() << "volume or area bits differ";
  return ::testing::AssertionSuccess();
}

TEST(NetCutDirect, TwoPointSplitsGiveTheCdtsBytes) {
  std::mt19937 rng(1616);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<std::pair<PolygonSoup, PolygonSoup>> pairs;
  // Icospheres at random rotations and offsets (generic cuts).
  for (int i = 0; i < 12; ++i) {
    PolygonSoup a = net_test::icosphere(1 + i % 2, 1.0, {0, 0, 0});
    PolygonSoup b = net_test::icosphere(1 + (i / 2) % 2, 0.8 + 0.3 * std::abs(unit(rng)),
                                        {0.6 * unit(rng), 0.6 * unit(rng), 0.6 * unit(rng)});
    const Eigen::Quaterniond q(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized());
    for (Vec3d& p : b.positions) p = q.toRotationMatrix() * p;
    pairs.emplace_back(std::move(a), std::move(b));
  }
  // Boxes on a coarse grid, one turned about z (points at exact midpoints,
  // symmetric cuts: cocircular quadrilaterals in the triangles' frames).
  std::uint64_t seed = 16;
  for (int i = 0; i < 24; ++i) {
    Vec3d lo[2], hi[2];
    net_test::grid_box_pair(seed, lo, hi);
    PolygonSoup a = net_test::box_triangles(lo[0], hi[0]), b = net_test::box_triangles(lo[1], hi[1]);
    if (i % 2) {
      const Vec3d c = 0.5 * (lo[1] + hi[1]);
      const Eigen::Matrix3d r = Eigen::AngleAxisd(M_PI / 4 * (i % 4 == 1 ? 1 : 0.5), Vec3d::UnitZ()).toRotationMatrix();
      for (Vec3d& p : b.positions) p = r * (p - c) + c + Vec3d(0.13, 0.07, 0.11);
    }
    pairs.emplace_back(std::move(a), std::move(b));
  }
  // Cray's kind: spheres across the FLT_MAX slab.
  for (PolygonSoup& s : net_test::spheres_across_the_slab(4)) pairs.emplace_back(std::move(s), net_test::flt_max_slab());
  const std::uint64_t taken0 = net_detail::direct_split_count();
  int compared = 0;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    for (BooleanOp op : net_test::kAllOps) {
      BooleanOptions o;
      o.op = op;
      net_detail::set_direct_split(false);
      const auto want = net_boolean(pairs[i].first, pairs[i].second, o);
      net_detail::set_direct_split(true);
      const auto got = net_boolean(pairs[i].first, pairs[i].second, o);
      EXPECT_TRUE(cut_direct_same(got, want)) << "pair " << i << " op " << static_cast<int>(op);
      ++compared;
    }
  net_detail::set_direct_split(true);
  const std::uint64_t taken = net_detail::direct_split_count() - taken0;
  EXPECT_EQ(compared, static_cast<int>(pairs.size()) * 4);
  EXPECT_GT(taken, 1000u) << "the direct split was hardly taken";
  // Two threads on a pair above the sequential threshold (per-thread
  // records): the one-thread CDT path's bytes.
  const PolygonSoup a = net_test::icosphere(4, 1.0, {0, 0, 0}), b = net_test::icosphere(4, 1.0, {0.37, 0.21, 0.13});
  BooleanOptions o;
  o.op = BooleanOp::kUnion;
  ExecContext one, two;
  one.threads = 1;
  two.threads = 2;
  net_detail::set_direct_split(false);
  const auto want = net_boolean(a, b, o, one);
  net_detail::set_direct_split(true);
  EXPECT_TRUE(cut_direct_same(net_boolean(a, b, o, two), want));
  EXPECT_TRUE(cut_direct_same(net_boolean(a, b, o, one), want));
}

}  // namespace
}  // namespace atelier
