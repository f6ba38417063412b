#include <gtest/gtest.h>
#include "storage/builder.h"
#include "systems/validate.h"
using namespace atelier;
TEST(Model, Smoke) {
  Model m;
  std::vector<Vec3d> p = {{0,0,0},{1,0,0},{0,1,0},{0,0,1}};
  std::vector<std::uint32_t> off = {0,3,6,9,12}, idx = {0,2,1, 0,1,3, 1,2,3, 0,3,2};
  auto s = add_polygon_surface(m, "tet", {p, off, idx});
  ASSERT_TRUE(s) << s.status().to_string();
  EXPECT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_EQ(m.num_edges(), 6u);
}
