// optimise_region's own split and collapse (issue 21, remesh8) against the
// edit operators of systems/mesh/edit.h as the oracle: optimise_region takes
// the generic operators when the model holds an attribute node, and its own
// where it holds none; both must leave the same tables, slot for slot.
// remesh9: a closed region (no border anywhere: the optimiser's border
// walks are skipped there), its faces and nodes outside the region checked
// bit for bit against the model on entry. (Not against the edit operators:
// next to fixed nodes the own collapse may keep the other end, as
// docs/glossary.md says, so the two differ on a fixed outline.)
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

}  // namespace
}  // namespace atelier
