// optimise_region's own split and collapse (issue 21, remesh8) against the
// edit operators of systems/mesh/edit.h as the oracle: optimise_region takes
// the generic operators when the model holds an attribute node, and its own
// where it holds none; both must leave the same tables, slot for slot.
// remesh9: a closed region (no border anywhere: the optimiser's border
// walks are skipped there), its faces and nodes outside the region checked
// bit for bit against the model on entry. (Not against the edit operators:
// next to fixed nodes the own collapse may keep the other end, as
// docs/glossary.md says, so the two differ on a fixed outline.)
// sweep11: the chamfer rule of the free border, on a stepped flat sheet.
#include <atelier/storage/model.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/sketch/optimise_region.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "systems/sketch/sketch_fixtures.h"

namespace atelier {
namespace {

using sketch_test::grid;
using sketch_test::icosphere;

TEST(OptimiseRegion, OwnOperatorsLeaveTheTablesOfTheEditOperators) {
  // A quarter cylinder of long thin triangles (cells 0.13 x 0.05 against
  // L = 0.09): many splits and collapses, relaxation projected on a curve.
  Model m;
  auto g = grid(
      12, 24, [](double u, double v) { return Vec3d(std::cos(0.5 * M_PI * u), 1.2 * v, std::sin(0.5 * M_PI * u)); },
      true);
  (void)add_polygon_surface(m, "quarter", g.view()).value();
  std::vector<FaceIdx> region;
  for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i)
    if (m.alive(FaceIdx{i})) region.push_back(FaceIdx{i});
  // The oracle's model: the same, with a vertex attribute node on node 0
  // (a corner of the border: it keeps its place), removed afterwards.
  Model generic = m;
  const NodeIdx corner{0};
  const AttribNodeIdx a = generic.new_attrib_node(generic.nodes.surface[corner.value], AttribNodeKind::kVertex,
                                                  corner.value, Vec3d::Zero(), generic.position(corner));
  RegionOptimiseOptions o;
  o.target = 0.09;
  auto own = optimise_region(m, region, {}, {}, o);
  ASSERT_TRUE(own) << own.status().to_string();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  auto ref = optimise_region(generic, region, {}, {}, o);
  ASSERT_TRUE(ref) << ref.status().to_string();
  ASSERT_TRUE(validate(generic)) << validate(generic).to_string();
  EXPECT_GT(own->splits, 50u);
  EXPECT_GT(own->collapses, 50u);
  EXPECT_EQ(own->splits, ref->splits);
  EXPECT_EQ(own->collapses, ref->collapses);
  EXPECT_EQ(own->swaps, ref->swaps);
  ASSERT_TRUE(generic.alive(a));
  generic.delete_attrib_node(a);
  EXPECT_EQ(diff_tables(m, generic), "");
  EXPECT_EQ(own->after.outside, ref->after.outside);
}

TEST(OptimiseRegion, ClosedCapMeetsTheBoundsAndKeepsTheRestBitForBit) {
  // The cap z > 0.2 of a level-4 icosphere (edges ~0.08) remeshed to
  // L = 0.05: splits everywhere, then collapses and swaps; the rest of the
  // sphere is fixed, so the region has no border.
  Model m = icosphere(4);
  std::vector<FaceIdx> region;
  std::vector<NodeIdx> f, g;
  for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i) {
    if (!m.alive(FaceIdx{i})) continue;
    m.face_nodes(FaceIdx{i}, f);
    bool up = true;
    for (NodeIdx v : f) up = up && m.position(v).z() > 0.2;
    if (up) region.push_back(FaceIdx{i});
  }
  ASSERT_GT(region.size(), 300u);
  const Model before = m;
  RegionOptimiseOptions o;
  o.target = 0.05;
  auto r = optimise_region(m, region, {}, {}, o);
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_GT(r->splits, 300u);
  EXPECT_GT(r->collapses, 10u);
  EXPECT_GT(r->swaps, 10u);
  // Bounds met by every region edge, the surface kept (0.1 L of the cap
  // on entry), still a closed sphere (V - E + F = 2).
  EXPECT_EQ(r->after.outside, 0u);
  EXPECT_GT(r->after.edges, 0u);
  EXPECT_LT(r->max_deviation, 0.1 * o.target);
  EXPECT_EQ(static_cast<long>(m.num_nodes()) - static_cast<long>(m.num_edges()) + static_cast<long>(m.num_faces()), 2);
  // The rest of the sphere: every face and its nodes as on entry, bit for bit.
  std::vector<char> in(before.faces.slots.capacity(), 0);
  for (FaceIdx q : region) in[q.value] = 1;
  std::size_t kept = 0;
  for (std::uint32_t i = 0; i < before.faces.slots.capacity(); ++i) {
    if (!before.alive(FaceIdx{i}) || in[i]) continue;
    ASSERT_TRUE(m.alive(FaceIdx{i})) << "face " << i;
    before.face_nodes(FaceIdx{i}, f);
    m.face_nodes(FaceIdx{i}, g);
    ASSERT_EQ(f, g) << "face " << i;
    for (NodeIdx v : f) ASSERT_EQ(before.position(v), m.position(v)) << "node " << v.value;
    ++kept;
  }
  EXPECT_GT(kept, 1000u);
}

/// A flat 10 x 10 triangle grid over the unit square (L = 0.1), whose top
/// border steps up at x = 0.4 by a short edge (0.64 L) with a turn of
/// `turn_deg` at each of its ends; the bottom row fixed (a B).
struct SteppedSheet {
  Model m;
  std::vector<FaceIdx> region;
  std::vector<NodeIdx> bottom;
  Vec3d p4, p5;  // the short border edge's ends
};
SteppedSheet stepped_sheet(double turn_deg) {
  SteppedSheet s;
  const double len = 0.064, a = turn_deg * M_PI / 180;
  s.p4 = Vec3d(0.4, 1, 0);
  s.p5 = s.p4 + len * Vec3d(std::cos(a), std::sin(a), 0);
  auto g = grid(
      10, 10,
      [&](double u, double v) {
        if (v < 1) return Vec3d(u, v, 0);
        if (u < 0.45) return Vec3d(u, 1, 0);
        if (u < 0.55) return s.p5;  // node 5 of the top row
        return Vec3d(u, s.p5.y(), 0);
      },
      true);
  (void)add_polygon_surface(s.m, "sheet", g.view()).value();
  for (std::uint32_t i = 0; i < s.m.faces.slots.capacity(); ++i)
    if (s.m.alive(FaceIdx{i})) s.region.push_back(FaceIdx{i});
  for (std::uint32_t v = 0; v < s.m.nodes.slots.capacity(); ++v)
    if (s.m.alive(NodeIdx{v}) && s.m.position(NodeIdx{v}).y() == 0) s.bottom.push_back(NodeIdx{v});
  return s;
}

bool has_node_at(const Model& m, const Vec3d& p) {
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}) && m.position(NodeIdx{v}) == p) return true;
  return false;
}

TEST(OptimiseRegion, AShortBorderEdgeBetweenTwoGentleCornersIsCollapsedSharpCornersStay) {
  // sweep11's chamfer rule: the free border's corners (turns over 30
  // degrees) keep their places, except the two ends of one short border
  // edge when each turns by less than 60 degrees: they meet at the edge's
  // midpoint (the sleeve's open end). Without the rule the 0.64 L edge
  // stays (a border edge cannot be swapped, a split shortens it).
  RegionOptimiseOptions o;
  o.target = 0.1;
  {
    SteppedSheet s = stepped_sheet(40);
    const Model before = s.m;
    auto r = optimise_region(s.m, s.region, s.bottom, {}, o);
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_TRUE(validate(s.m)) << validate(s.m).to_string();
    EXPECT_GE(r->before.outside, 1u);
    EXPECT_EQ(r->after.outside, 0u);
    EXPECT_FALSE(has_node_at(s.m, s.p4));
    EXPECT_FALSE(has_node_at(s.m, s.p5));
    EXPECT_TRUE(has_node_at(s.m, 0.5 * (s.p4 + s.p5)));  // the corners met at the midpoint
    // The square's corners and B (the bottom row), bit for bit.
    EXPECT_TRUE(has_node_at(s.m, Vec3d(0, 1, 0)));
    EXPECT_TRUE(has_node_at(s.m, Vec3d(1, s.p5.y(), 0)));
    for (NodeIdx v : s.bottom) ASSERT_EQ(s.m.position(v), before.position(v));
  }
  {
    SteppedSheet s = stepped_sheet(70);  // sharp: both corners stay, the edge stays short
    auto r = optimise_region(s.m, s.region, s.bottom, {}, o);
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_TRUE(validate(s.m)) << validate(s.m).to_string();
    EXPECT_TRUE(has_node_at(s.m, s.p4));
    EXPECT_TRUE(has_node_at(s.m, s.p5));
    EXPECT_GE(r->after.outside, 1u);
  }
}

}  // namespace
}  // namespace atelier
