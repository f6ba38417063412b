// Net Booleans (seed 004 sections 2-3): volumes against analytic values,
// closed and oriented results, touching and coplanar cases, bad input.
#include <atelier/systems/net/boolean.h>

#include <gtest/gtest.h>

#include <cmath>

#include "net_shapes.h"

namespace atelier {
namespace {

using net_test::box;
using net_test::box_triangles;
using net_test::closed_model;

BooleanReport run(const PolygonSoup& a, const PolygonSoup& b, BooleanOp op, const ExecContext& ctx = {}) {
  BooleanOptions o;
  o.op = op;
  auto r = net_boolean(a, b, o, ctx);
  EXPECT_TRUE(r.has_value()) << r.status().to_string();
  return r.has_value() ? std::move(*r) : BooleanReport{};
}

TEST(NetBoolean, OverlappingCubes) {
  const auto a = box({0, 0, 0}, {1, 1, 1});
  const auto b = box({.5, .25, -.5}, {1.5, 1.25, .5});
  const struct {
    BooleanOp op;
    double volume;
  } cases[] = {{BooleanOp::kIntersection, 0.1875},
               {BooleanOp::kUnion, 1.8125},
               {BooleanOp::kAMinusB, 0.8125},
               {BooleanOp::kBMinusA, 0.8125}};
  for (const auto& c : cases) {
    const BooleanReport r = run(a, b, c.op);
    EXPECT_NEAR(r.volume, c.volume, 1e-12) << static_cast<int>(c.op);
    EXPECT_TRUE(closed_model(r.result)) << static_cast<int>(c.op);
    EXPECT_EQ(r.intersection_polygons, 1u);
  }
}

TEST(NetBoolean, CoplanarCubes) {
  const auto a = box({0, 0, 0}, {1, 1, 1});
  const auto b = box({.5, 0, 0}, {1.5, 1, 1});
  const struct {
    BooleanOp op;
    double volume;
  } cases[] = {{BooleanOp::kIntersection, 0.5}, {BooleanOp::kUnion, 1.5}, {BooleanOp::kAMinusB, 0.5}, {BooleanOp::kBMinusA, 0.5}};
  for (const auto& c : cases) {
    const BooleanReport r = run(a, b, c.op);
    EXPECT_NEAR(r.volume, c.volume, 1e-12) << static_cast<int>(c.op);
    EXPECT_TRUE(closed_model(r.result)) << static_cast<int>(c.op);
  }
}

}  // namespace
}  // namespace atelier
