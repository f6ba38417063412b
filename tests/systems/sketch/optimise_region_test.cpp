// optimise_region's own split and collapse (issue 21, remesh8) against the
// edit operators of systems/mesh/edit.h as the oracle: optimise_region takes
// the generic operators when the model holds an attribute node, and its own
// where it holds none; both must leave the same tables, slot for slot.
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

}  // namespace
}  // namespace atelier
