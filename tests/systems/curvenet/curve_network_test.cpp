// Curve treatment (seed 003 section 4): splits at intersections with the
// reported tolerance, the three merge thresholds, pruning of dangling ends
// with a warning, and the errors that name the curve.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "curvenet_fixtures.h"
#include <atelier/systems/curvenet/curve_network.h>

using namespace atelier;
using namespace atelier::curvenet_test;

namespace {

std::size_t count_node(const CurveGraph& g, std::uint32_t v) {
  std::size_t n = 0;
  for (const auto& sn : g.segment_nodes) n += (sn[0] == v) + (sn[1] == v);
  return n;
}

/// Every segment starts and ends exactly (bit for bit) on its nodes.
void expect_ends_on_nodes(const CurveGraph& g) {
  for (std::size_t s = 0; s < g.segment_count(); ++s) {
    const auto p = g.polyline(s);
    ASSERT_GE(p.size(), 2u);
    EXPECT_EQ(p.front(), g.nodes[g.segment_nodes[s][0]]) << "segment " << s;
    EXPECT_EQ(p.back(), g.nodes[g.segment_nodes[s][1]]) << "segment " << s;
  }
}

}  // namespace

TEST(CurveTreatment, TwoCrossingCurvesSplitIntoFourPiecesAtOneNode) {
  PolylineSet s;
  s.add(0, line({-1, 0, 0}, {1, 0, 0}, 7));  // the crossing is inside a polyline segment of both
  s.add(1, line({0, -1, 0}, {0, 1, 0}, 5));
  CurveTreatmentOptions o;
  o.prune_dangling = false;
  auto t = treat_curves(s, o);
  ASSERT_TRUE(t) << t.status().to_string();
  const CurveGraph& g = t->graph;
  EXPECT_EQ(t->report.intersections, 1u);
  EXPECT_EQ(t->report.splits, 2u);
  EXPECT_EQ(g.segment_count(), 4u);
  EXPECT_EQ(g.node_count(), 5u);  // the crossing and four free ends
  expect_ends_on_nodes(g);
  std::uint32_t centre = kNoCurveNode;
  for (std::uint32_t v = 0; v < g.node_count(); ++v)
    if (count_node(g, v) == 4) centre = v;
  ASSERT_NE(centre, kNoCurveNode);
  EXPECT_LT(g.nodes[centre].norm(), 1e-15);
  EXPECT_DOUBLE_EQ(t->report.diagonal, std::sqrt(8.0));
  EXPECT_DOUBLE_EQ(t->report.tolerance, 1e-6 * std::sqrt(8.0));
  // Pruning removes all four arms: nothing bounds a face.
  auto pruned = treat_curves(s);
  ASSERT_FALSE(pruned);
  EXPECT_EQ(pruned.status().code(), ErrorCode::kTopology);
  EXPECT_NE(pruned.status().message().find("no cycle"), std::string::npos);
}

TEST(CurveTreatment, ToleranceDecidesWhetherNearMissesIntersect) {
  PolylineSet s;
  s.add(0, line({-1, 0, 0}, {1, 0, 0}));
  s.add(1, line({0, -1, 3e-6}, {0, 1, 3e-6}));  // passes 3e-6 above: 1.06e-6 of the diagonal
  CurveTreatmentOptions o;
  o.prune_dangling = false;
  auto apart = treat_curves(s, o);
  ASSERT_TRUE(apart);
  EXPECT_EQ(apart->report.intersections, 0u);
  EXPECT_EQ(apart->graph.segment_count(), 2u);
  o.intersection_tolerance = 2e-6;
  auto met = treat_curves(s, o);
  ASSERT_TRUE(met);
  EXPECT_EQ(met->report.intersections, 1u);
  EXPECT_NEAR(met->report.max_intersection_gap, 3e-6, 1e-12);
  EXPECT_EQ(met->graph.segment_count(), 4u);
  expect_ends_on_nodes(met->graph);
}

TEST(CurveTreatment, GridKeepsItsCellsAndPrunesOvershootsWithAWarning) {
  const PolylineSet s = grid_network(3, 2, 1.0, 0.4);
  auto t = treat_curves(s);
  ASSERT_TRUE(t) << t.status().to_string();
  const CurveGraph& g = t->graph;
  // 4 x 3 crossings; 2 x 4 + 3 x 3 = 17 cell sides; the 2 * 7 overshoots pruned.
  EXPECT_EQ(t->report.intersections, 12u);
  EXPECT_EQ(t->report.pruned_segments, 14u);
  ASSERT_EQ(t->report.warnings.size(), 1u);
  EXPECT_NE(t->report.warnings[0].find("pruned 14 dangling curve ends"), std::string::npos);
  EXPECT_EQ(t->report.pruned_curve_ids.size(), 7u);
  EXPECT_NEAR(t->report.pruned_length, 14 * 0.4, 1e-9);
  EXPECT_EQ(g.node_count(), 12u);
  // The four corner nodes are kinks (two curves at right angles): kept, not
  // merged; the other outer nodes keep three pieces.
  EXPECT_EQ(t->report.kinks, 4u);
  EXPECT_EQ(t->report.merges, 0u);
  EXPECT_EQ(g.segment_count(), 17u);
  expect_ends_on_nodes(g);
}

TEST(CurveTreatment, MergeNeedsAllThreeThresholds) {
  // A circle drawn as two arcs meeting end to end: distance, tangent and
  // curvature all agree: merged into one closed curve at one node.
  auto arc = [](double a0, double a1, double r, int n) {
    std::vector<Vec3d> p;
    for (int i = 0; i <= n; ++i) {
      const double a = a0 + (a1 - a0) * i / n;
      p.emplace_back(r * std::cos(a), r * std::sin(a), 0);
    }
    return p;
  };
  {
    PolylineSet s;
    s.add(0, arc(0, kPi, 1.0, 40));
    s.add(1, arc(kPi, 2 * kPi, 1.0, 40));
    s.points.back() = s.points.front();  // close exactly
    auto t = treat_curves(s);
    ASSERT_TRUE(t) << t.status().to_string();
    EXPECT_EQ(t->report.merges, 1u);
    EXPECT_EQ(t->graph.segment_count(), 1u);
    EXPECT_EQ(t->graph.node_count(), 1u);
  }
  // Threshold 2: a corner (tangents 90 degrees apart) is kept as a kink.
  {
    PolylineSet s;
    s.add(0, line({0, 0, 0}, {1, 0, 0}));
    s.add(1, line({1, 0, 0}, {1, 1, 0}));
    s.add(2, line({1, 1, 0}, {0, 0, 0}));
    auto t = treat_curves(s);
    ASSERT_TRUE(t);
    EXPECT_EQ(t->report.merges, 0u);
    EXPECT_EQ(t->report.kinks, 3u);
    EXPECT_EQ(t->graph.segment_count(), 3u);
  }
  // Threshold 3: a straight line continuing tangentially into a tight arc
  // (same tangent, curvature 0 against 4) is kept apart; a looser
  // curvature threshold merges it.
  {
    PolylineSet s;
    s.add(0, line({-1, -0.25, 0}, {0, -0.25, 0}, 20));
    auto a = arc(-kPi / 2, kPi / 2, 0.25, 40);  // from (0, -0.25) round to (0, 0.25)
    s.add(1, a);
    s.add(2, line({0, 0.25, 0}, {-1, -0.25, 0}, 20));
    CurveTreatmentOptions o;
    auto t = treat_curves(s, o);
    ASSERT_TRUE(t);
    EXPECT_EQ(t->report.merges, 0u);
    o.merge_curvature = 1.5;
    auto loose = treat_curves(s, o);
    ASSERT_TRUE(loose);
    EXPECT_EQ(loose->report.merges, 1u);
  }
  // Threshold 1: two pieces of one line with a gap of 7e-4 x the diagonal
  // are joined (then merged); with merge_distance 1e-4 they stay apart and
  // are pruned as dangling ends of the square they cross.
  {
    PolylineSet s;
    s.add(0, line({0, 0.5, 0}, {0.4995, 0.5, 0}));
    s.add(1, line({0.5005, 0.5, 0}, {1, 0.5, 0}));
    s.add(2, line({0, 0, 0}, {1, 0, 0}));
    s.add(3, line({1, 0, 0}, {1, 1, 0}));
    s.add(4, line({1, 1, 0}, {0, 1, 0}));
    s.add(5, line({0, 1, 0}, {0, 0, 0}));
    auto t = treat_curves(s);
    ASSERT_TRUE(t) << t.status().to_string();
    EXPECT_EQ(t->report.joined_ends, 1u);
    EXPECT_EQ(t->report.pruned_segments, 0u);
    CurveTreatmentOptions o;
    o.merge_distance = 1e-4;
    auto apart = treat_curves(s, o);
    ASSERT_TRUE(apart);
    EXPECT_EQ(apart->report.joined_ends, 0u);
    EXPECT_EQ(apart->report.pruned_segments, 2u);
  }
}

TEST(CurveTreatment, BadCurvesAreNamed) {
  {
    PolylineSet s;
    s.add(4, line({0, 0, 0}, {1, 0, 0}));
    const Vec3d one[] = {{2, 2, 2}, {2, 2, 2}};
    s.add(9, one);
    auto t = treat_curves(s);
    ASSERT_FALSE(t);
    EXPECT_NE(t.status().message().find("CURVE 9 has fewer than 2 distinct points"), std::string::npos)
        << t.status().message();
  }
  {
    PolylineSet s;
    s.add(4, line({0, 0, 0}, {1, 0, 0}));
    s.add(5, line({0, 0, 0}, {0, 1, 0}));
    s.points[12].y() = std::nan("");
    auto t = treat_curves(s);
    ASSERT_FALSE(t);
    EXPECT_NE(t.status().message().find("CURVE 5 has a non-finite point"), std::string::npos) << t.status().message();
  }
  for (bool reversed : {false, true}) {
    PolylineSet s = cube_wireframe();
    auto dup = line({0, 0, 0}, {1, 0, 0}, 3);
    if (reversed) std::reverse(dup.begin(), dup.end());
    s.add(77, dup);
    auto t = treat_curves(s);
    ASSERT_FALSE(t);
    EXPECT_EQ(t.status().code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(t.status().message().find("CURVE 77"), std::string::npos) << t.status().message();
    EXPECT_NE(t.status().message().find("duplicate"), std::string::npos);
  }
  {
    PolylineSet s;
    const Vec3d same[] = {{1, 1, 1}, {1, 1, 1}};
    s.add(0, same);
    EXPECT_FALSE(treat_curves(s));
    EXPECT_FALSE(treat_curves(PolylineSet{}));
  }
}

TEST(CurveTreatment, ResultDoesNotDependOnThreads) {
  ATELIER_REQUIRE_SHARED_NETWORKS();
  const PolylineSet s = shared_network("roof_75");
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 1;
  auto a = treat_curves(s, {}, one), b = treat_curves(s, {}, two);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->graph.points, b->graph.points);
  EXPECT_EQ(a->graph.segment_nodes, b->graph.segment_nodes);
  EXPECT_EQ(a->graph.nodes, b->graph.nodes);
}

TEST(CurveTreatment, SharedNetworksSplitAtTheirCrossings) {
  ATELIER_REQUIRE_SHARED_NETWORKS();
  struct Case {
    const char* name;
    std::size_t nodes, segments;
  };
  // Nodes and segments after pruning; every crossing is exact in these
  // files (closest approach <= 1e-7 of the diagonal), far below the tolerance.
  for (const Case c :
       {Case{"shell_100", 819, 1578}, Case{"roof_75", 776, 1729}, Case{"kagome_114_regular", 3294, 6474}}) {
    auto t = treat_curves(shared_network(c.name));
    ASSERT_TRUE(t) << c.name << ": " << t.status().to_string();
    EXPECT_EQ(t->graph.node_count(), c.nodes) << c.name;
    EXPECT_EQ(t->graph.segment_count(), c.segments) << c.name;
    EXPECT_LT(t->report.max_intersection_gap, 1e-7 * t->report.diagonal) << c.name;
    EXPECT_FALSE(t->report.warnings.empty()) << c.name << ": the overshooting ends are pruned with a warning";
    expect_ends_on_nodes(t->graph);
  }
}
