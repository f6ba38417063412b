// The self-intersection check switched off (BooleanOptions and
// PrepareOptions::check_self_intersection = false) is the caller's promise
// that neither net crosses itself. A broken promise that the cut meets (two
// faces of one net crossing inside a face of the other: crossing cut
// segments, or two cut points at one place) is refused with the check's own
// error naming the first crossing pair of faces, never a crash (a zero-length
// edge in the constrained triangulation: SIGSEGV before guard15), an
// internal error or a result. The oracle for the faces is the check itself
// (prepare with the check on). A crossing the cut does not meet is copied
// into the result as the caller gave it, and a prepared result refuses it.
#include <atelier/systems/net/boolean.h>
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "net_shapes.h"

namespace atelier {
namespace {

struct PromiseCase {
  const char* what;
  PolygonSoup crossing;  // closed, outward, manifold, crossing itself
  PolygonSoup other;     // a valid net meeting the crossing
};

std::vector<PromiseCase> promise_cases() {
  using net_test::box_triangles;
  using net_test::icosphere;
  std::vector<PromiseCase> c;
  // Two overlapping spheres in one soup; a slab through their circle of
  // crossing, and a sphere inside their lens poking out of both.
  const PolygonSoup spheres = net_test::joined(icosphere(2, 1.0, {0, 0, 0}), icosphere(2, 1.0, {1, 0, 0}));
  c.push_back({"spheres / slab", spheres, box_triangles({0.3, -2, -0.2}, {0.7, 2, 0.21})});
  c.push_back({"spheres / lens", spheres, icosphere(2, 0.6, {0.45, 0.1, 0.05})});
  // A box with a top corner pushed through its bottom (a face through
  // another), against a box sharing its diagonal and a sphere.
  PolygonSoup poked = box_triangles({0, 0, 0}, {1, 1, 1});
  poked.positions[6] = {0.5, 0.6, -0.5};
  c.push_back({"poked / box", poked, box_triangles({0, 0, 0}, {1, 1, 1})});
  c.push_back({"poked / sphere", poked, icosphere(2, 0.6, {0.45, 0.1, 0.05})});
  // A tall box folded over: its top's y = 0 edge swung under the bottom.
  PolygonSoup folded = box_triangles({0, 0, 0}, {1, 1, 2});
  folded.positions[4] = {0, 0.6, -0.5};
  folded.positions[5] = {1, 0.6, -0.5};
  c.push_back({"folded / box", folded, box_triangles({0.2, -0.5, -0.3}, {0.8, 0.7, 0.4})});
  // Two boxes in one soup crossing along x = y = 0.5, through the diagonal
  // of the unit box's bottom: two cut points at one place on that edge (the
  // crash).
  const PolygonSoup cross =
      net_test::joined(box_triangles({-1, -1, -1}, {0.5, 2, 0.75}), box_triangles({0, 0.5, -1}, {2, 2, 0.75}));
  c.push_back({"crossing line through an edge", cross, box_triangles({0, 0, 0}, {1, 1, 1})});
  // Two overlapping boxes (quads), a sphere about one crossing edge.
  c.push_back({"two boxes / sphere", net_test::two_boxes_in_one_net(), icosphere(2, 0.3, {2, 1, 1.5})});
  return c;
}

/// The self-intersection check's message for `net` named `name`.
std::string promise_check_message(const PolygonSoup& net, const char* name) {
  PrepareOptions o;
  o.name = name;
  auto p = PreparedNet::prepare(net, o);
  EXPECT_FALSE(p.has_value()) << name << " does not cross itself";
  return p.has_value() ? std::string("(no crossing)") : std::string(p.status().message());
}

TEST(NetPromise, CrossingNetsMetByTheCutAreRefusedNamingTheFaces) {
  for (const PromiseCase& pc : promise_cases()) {
    for (int swap = 0; swap < 2; ++swap) {
      const PolygonSoup& a = swap ? pc.other : pc.crossing;
      const PolygonSoup& b = swap ? pc.crossing : pc.other;
      const char* name = swap ? "B" : "A";
      const std::string expected = promise_check_message(pc.crossing, name);
      ASSERT_NE(expected.find("intersects itself: faces"), std::string::npos) << pc.what << ": " << expected;
      // Without the check the nets are prepared (closed, outward, manifold).
      PrepareOptions pa, pb;
      pa.check_self_intersection = pb.check_self_intersection = false;
      pb.name = "B";
      auto xa = PreparedNet::prepare(a, pa);
      auto xb = PreparedNet::prepare(b, pb);
      ASSERT_TRUE(xa.has_value() && xb.has_value()) << pc.what;
      for (BooleanOp op : net_test::kAllOps)
        for (BooleanMode mode : {BooleanMode::kExact, BooleanMode::kPaper})
          for (int prepared = 0; prepared < 2; ++prepared) {
            BooleanOptions o;
            o.op = op;
            o.mode = mode;
            o.check_self_intersection = false;
            const auto r = prepared ? net_boolean(*xa, *xb, o) : net_boolean(a, b, o);
            const std::string where = std::string(pc.what) + (swap ? " swapped" : "") + " op " +
                                      std::to_string(static_cast<int>(op)) + " mode " +
                                      std::to_string(static_cast<int>(mode)) + (prepared ? " prepared" : " soups");
            ASSERT_FALSE(r.has_value()) << where << ": answered, volume " << r->volume;
            EXPECT_EQ(r.status().code(), ErrorCode::kTopology) << where << ": " << r.status().to_string();
            // The check's own words and faces, then why it was found late.
            EXPECT_EQ(r.status().message().substr(0, expected.size()), expected)
                << where << ": " << r.status().message();
            EXPECT_NE(r.status().message().find("check_self_intersection = false skips"), std::string::npos) << where;
          }
      // With the check the one-call refuses the same faces up front.
      const auto checked = net_boolean(a, b, {});
      ASSERT_FALSE(checked.has_value()) << pc.what;
      EXPECT_EQ(checked.status().message(), expected) << pc.what;
    }
  }
}

/// The check off, a crossing the other net does not meet is not seen (that
/// would take the check): the union copies the crossing net unchanged
/// beside the other, and the result is not a valid operand, so a prepared
/// result is refused naming the crossing.
TEST(NetPromise, ACrossingTheCutDoesNotMeetIsCopiedAndRefusedAsAnOperand) {
  const PolygonSoup spheres =
      net_test::joined(net_test::icosphere(2, 1.0, {0, 0, 0}), net_test::icosphere(2, 1.0, {1, 0, 0}));
  const PolygonSoup far = net_test::box({5, 5, 5}, {6, 6, 6});
  BooleanOptions o;
  o.check_self_intersection = false;
  o.prepare_result = true;
  const auto r = net_boolean(spheres, far, o);
  ASSERT_TRUE(r.has_value()) << r.status().to_string();
  EXPECT_EQ(r->result.face_count(), spheres.face_count() + far.face_count());
  EXPECT_NEAR(r->volume, soup_volume(spheres) + soup_volume(far), 1e-12);
  EXPECT_TRUE(net_test::closed_model(r->result));
  EXPECT_TRUE(r->prepared.empty());
  EXPECT_EQ(r->prepared_status.code(), ErrorCode::kTopology);
  EXPECT_NE(r->prepared_status.message().find("intersects itself: faces"), std::string::npos)
      << r->prepared_status.to_string();
}

}  // namespace
}  // namespace atelier
