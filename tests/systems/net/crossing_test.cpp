// The net Booleans' whole self-test of a result the certificate could not
// pass (issue 24, cross18): boolean.cpp runs prepare_result on it after the
// fold check; a result not moved by snap17's repair that this test finds
// crossing itself is refused ("intersects itself"), and a result with
// coincident vertex copies (which prepare_result refuses as duplicate
// vertices before its crossing test) is tested by pinched_self_crossing.
#include <atelier/systems/net/boolean.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <string>

#include "../../../systems/net/boolean_detail.h"
#include "net_shapes.h"

namespace atelier::crossing_test {

/// A unit box (as triangles) and, far from it (x in [10, 13]), two boxes overlapping each
/// other in the same net: closed, manifold and oriented, but crossing
/// itself away from the box.
PolygonSoup box_and_far_crossing() {
  PolygonSoup a = net_test::box_triangles({0, 0, 0}, {1, 1, 1});
  const PolygonSoup two = net_test::two_boxes_in_one_net();
  const auto base = static_cast<std::uint32_t>(a.positions.size());
  for (const Vec3d& p : two.positions) a.positions.push_back(p + Vec3d(10, 0, 0));
  for (std::size_t f = 0; f < two.face_count(); ++f) {
    std::vector<std::uint32_t> c(two.face(f).begin(), two.face(f).end());
    for (auto& x : c) x += base;
    a.add_face(c);
  }
  return a;
}

/// The unit box (as triangles) turned a quarter turn about its centre's z
/// axis by Eigen's AngleAxis, then shifted by (1/8, 0, 1/8): an inexact
/// near-copy (seed 1 case 9's pair), whose cut the certificate cannot pass.
PolygonSoup near_copy_of_the_box() {
  PolygonSoup b = net_test::box_triangles({0, 0, 0}, {1, 1, 1});
  const Vec3d centre(0.5, 0.5, 0.5), shift(0.125, 0, 0.125);
  const Eigen::AngleAxisd q(M_PI / 2, Vec3d::UnitZ());
  for (Vec3d& p : b.positions) p = centre + q * (p - centre) + shift;
  return b;
}

// The branch of the whole self-test that refuses a result not moved by the
// repair: only a crossing the fold check does not look at can reach it
// (the fold check tests every triangle with a new point against all kept
// triangles near it, so with checked operands and no coincident copies the
// two agree). An operand the caller promised to be free of crossings
// (check_self_intersection = false) that crosses itself away from the cut
// is one: the result keeps the crossing boxes whole, the certificate fails
// on the near-copy, the fold check passes, and the whole test finds the
// crossing, which is named in A. Without the branch the Boolean returns a
// result that crosses itself (op 0 and op 2 fail the ASSERT below).
TEST(NetCrossing, AResultTheFoldCheckPassesButThatCrossesItselfIsRefused) {
  const PolygonSoup a = box_and_far_crossing(), b = near_copy_of_the_box();
  auto& counts = net_detail::result_check_counts();
  for (BooleanOp op : {BooleanOp::kUnion, BooleanOp::kAMinusB}) {
    BooleanOptions o;
    o.op = op;
    o.check_self_intersection = false;
    const std::size_t full_before = counts.full.load();
    const auto r = net_boolean(a, b, o);
    EXPECT_EQ(counts.full.load(), full_before + 1) << "the certificate passed: pick another pair";
    ASSERT_FALSE(r.has_value()) << "op " << static_cast<int>(op) << ": a crossing result returned";
    EXPECT_EQ(r.status().code(), ErrorCode::kTopology);
    // Named in the operand that crosses itself (faces 12-23 are the far boxes').
    EXPECT_NE(r.status().message().find("net A intersects itself: faces 1"), std::string::npos)
        << r.status().to_string();
    // The same pair without the far boxes: answered (the crossing is theirs).
    const auto clean = net_boolean(net_test::box_triangles({0, 0, 0}, {1, 1, 1}), b, o);
    ASSERT_TRUE(clean.has_value()) << clean.status().to_string();
    EXPECT_TRUE(net_test::closed_model(clean->result));
  }
}

}  // namespace atelier::crossing_test
