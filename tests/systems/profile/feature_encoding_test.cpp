#include <gtest/gtest.h>

#include <atelier/systems/profile/feature_encoding.h>
#include <atelier/systems/body/mannequin.h>

using namespace atelier;

namespace {

const ReferenceBody& mannequin() {
  static const ReferenceBody b = make_mannequin(MannequinParams{}, MannequinResolution::from_level(3)).value();
  return b;
}

// A few template nodes around the body, each encoded in every body-based mode.
struct Case {
  NodeEncodings enc;
  std::vector<Vec3d> p;
};

Case build_case(const ReferenceBody& b) {
  Case c;
  const auto pos = skin_positions(b);
  const Model& m = b.model;
  // Nodes 5 cm outside a few skin vertices, edges and faces, and off feature points.
  for (std::uint32_t k = 0; k < 6; ++k) {
    const NodeIdx v{static_cast<std::uint32_t>((k * 997) % m.nodes.slots.capacity())};
    const Vec3d p = pos[v.value] * 1.05 + Vec3d(0.01, 0.02, -0.01);
    c.enc.nodes.push_back(*encode_on_vertex(b, v, p));
    c.p.push_back(p);
    const EdgeIdx e{static_cast<std::uint32_t>((k * 1319 + 7) % m.edges.slots.capacity())};
    const Vec3d q = 0.5 * (pos[m.tail(halfedge_of(e, 0)).value] + pos[m.head(halfedge_of(e, 0)).value]) * 1.04;
    c.enc.nodes.push_back(*encode_on_edge(b, e, q));
    c.p.push_back(q);
    const FaceIdx f{static_cast<std::uint32_t>((k * 733 + 3) % m.faces.slots.capacity())};
    const Vec3d r = pos[m.tail(m.faces.halfedge[f.value]).value] * 1.03;
    c.enc.nodes.push_back(*encode_on_face(b, f, r));
    c.p.push_back(r);
  }
  for (const auto& fp : b.points) {
    auto fr = feature_frame(b, fp.id);
    const Vec3d p = fr->origin + 0.04 * fr->n + 0.02 * fr->t1 - 0.01 * fr->t2;
    c.enc.nodes.push_back(*encode_on_feature_point(b, fp.id, p));
    c.p.push_back(p);
  }
  // Nodes on other nodes: one-to-one on node 0, n-to-one on nodes 1..4.
  const Vec3d mid = 0.25 * (c.p[1] + c.p[2] + c.p[3] + c.p[4]) + Vec3d(0, 0.05, 0);
  c.enc.nodes.push_back(encode_one_to_one(0, c.p[0], c.p[0] + Vec3d(0.1, 0, 0)));
  c.p.push_back(c.p[0] + Vec3d(0.1, 0, 0));
  const std::uint32_t others[] = {1, 2, 3, 4};
  const Vec3d other_pos[] = {c.p[1], c.p[2], c.p[3], c.p[4]};
  c.enc.nodes.push_back(encode_n_to_one(c.enc, others, other_pos, mid));
  c.p.push_back(mid);
  return c;
}

}  // namespace

TEST(FeatureEncoding, DecodingOnTheSameBodyReturnsTheNodes) {
  const auto& b = mannequin();
  Case c = build_case(b);
  std::vector<Vec3d> out(c.p.size());
  ASSERT_TRUE(decode_nodes(c.enc, b, skin_positions(b), out));
  for (std::size_t i = 0; i < out.size(); ++i)
    EXPECT_LT((out[i] - c.p[i]).norm(), 1e-12) << "node " << i << " " << to_string(c.enc.nodes[i].mode);
}

TEST(FeatureEncoding, TranslatedAndScaledBodiesMoveNodesAsTheAnalyticAnswerSays) {
  const auto& b = mannequin();
  Case c = build_case(b);
  const auto pos = skin_positions(b);
  // Translation: every node moves by t.
  const Vec3d t(0.3, -0.2, 1.5);
  std::vector<Vec3d> moved(pos.size()), out(c.p.size());
  for (std::size_t v = 0; v < pos.size(); ++v) moved[v] = pos[v] + t;
  ASSERT_TRUE(decode_nodes(c.enc, b, moved, out));
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_LT((out[i] - (c.p[i] + t)).norm(), 1e-10) << i;
  // Uniform scale s about the origin: frames keep their directions, origins
  // scale, so a body-encoded node lands at s * origin + (p - origin).
  const double s = 1.17;
  for (std::size_t v = 0; v < pos.size(); ++v) moved[v] = s * pos[v];
  ASSERT_TRUE(decode_nodes(c.enc, b, moved, out));
  for (std::size_t i = 0; i < c.enc.nodes.size(); ++i) {
    const NodeEncoding& e = c.enc.nodes[i];
    Vec3d origin;
    if (e.mode == NodeEncodingMode::kFeaturePoint) {
      origin = feature_frame(b, e.feature_point)->origin;
    } else if (e.mode == NodeEncodingMode::kVertex || e.mode == NodeEncodingMode::kEdge ||
               e.mode == NodeEncodingMode::kFace) {
      origin = element_frame(b, e.mode, e.element, e.t, pos)->origin;
    } else {
      continue;
    }
    EXPECT_LT((out[i] - (s * origin + (c.p[i] - origin))).norm(), 1e-9) << i << " " << to_string(e.mode);
  }
}

TEST(FeatureEncoding, EquationOneKeepsOrientationWhereEquationTwoDoesNot) {
  // Seed 000 Fig. 11: on a rotated body, eq. (1) turns the node with the
  // body; eq. (2) keeps the world offset and leaves it on the wrong side.
  const auto& b = mannequin();
  const auto pos = skin_positions(b);
  const auto* fp = b.find_point("waist_x_centre_front");
  ASSERT_NE(fp, nullptr);
  auto fr = feature_frame(b, fp->id);
  const Vec3d p = fr->origin + 0.08 * fr->n;  // 8 cm in front of the waist
  NodeEncodings enc;
  enc.nodes.push_back(*encode_on_feature_point(b, fp->id, p, false));
  enc.nodes.push_back(*encode_on_feature_point(b, fp->id, p, true));
  const Mat3d R = Eigen::AngleAxisd(M_PI / 2, Vec3d::UnitY()).toRotationMatrix();
  std::vector<Vec3d> rotated(pos.size()), out(2);
  for (std::size_t v = 0; v < pos.size(); ++v) rotated[v] = R * pos[v];
  ASSERT_TRUE(decode_nodes(enc, b, rotated, out));
  EXPECT_LT((out[0] - R * p).norm(), 1e-9);
  EXPECT_GT((out[1] - R * p).norm(), 0.1);  // eq. (2): 8 cm offset not turned -> over 11 cm off
}

TEST(FeatureEncoding, NToOneFollowsItsReferences) {
  const auto& b = mannequin();
  Case c = build_case(b);
  const std::size_t n = c.p.size();
  // Move the references of the n-to-one node: eq. (5) blends delta_i + new p_i.
  NodeEncodings enc = c.enc;
  const NodeEncoding& last = enc.nodes[n - 1];
  ASSERT_EQ(last.mode, NodeEncodingMode::kNToOne);
  std::vector<Vec3d> out(n);
  const auto pos = skin_positions(b);
  ASSERT_TRUE(decode_nodes(enc, b, pos, out));
  double w = 0;
  Vec3d s = Vec3d::Zero();
  for (std::uint32_t k = 0; k < last.ref_count; ++k) {
    const NodeRef& r = enc.refs[last.first_ref + k];
    s += r.weight * (r.delta + out[r.node]);
    w += r.weight;
  }
  EXPECT_LT((out[n - 1] - s / w).norm(), 1e-12);
  EXPECT_LT((out[n - 2] - (out[0] + Vec3d(0.1, 0, 0))).norm(), 1e-12);
}

TEST(FeatureEncoding, BadEncodingsAreRefusedNamingTheNode) {
  const auto& b = mannequin();
  NodeEncodings enc;
  enc.nodes.push_back(encode_one_to_one(1, Vec3d::Zero(), Vec3d(1, 0, 0)));
  enc.nodes.push_back(encode_one_to_one(0, Vec3d::Zero(), Vec3d(1, 0, 0)));  // 0 <-> 1 cycle
  std::vector<Vec3d> out(2);
  Status s = decode_nodes(enc, b, skin_positions(b), out);
  EXPECT_EQ(s.code(), ErrorCode::kTopology);
  EXPECT_NE(s.message().find("cycle"), std::string::npos);
  EXPECT_FALSE(encode_on_vertex(b, NodeIdx{99999999}, Vec3d::Zero()));
  EXPECT_FALSE(encode_on_feature_point(b, 424242, Vec3d::Zero()));
  EXPECT_FALSE(encode_on_face(b, FaceIdx{0}, Vec3d(std::nan(""), 0, 0)));
}
