// Prepared operands of the net Booleans (PreparedNet): the prepared Boolean
// gives the one-call's bits on the unit-test shapes and the shared pairs,
// prepare refuses bad nets with the one-call's messages, a chain of
// prepared results gives the bits of one-call steps and each prepared result
// is what prepare() builds from the result's soup, and threads may share a
// prepared net.
#include <atelier/io/obj.h>
#include <atelier/systems/net/boolean.h>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <thread>

#include "../../../systems/net/boolean_detail.h"
#include "net_shapes.h"

namespace atelier {
namespace {

using net_test::box;
using net_test::box_triangles;
using net_test::icosphere;

PreparedNet prepared(const PolygonSoup& s, const std::string& name, bool check = true, const ExecContext& ctx = {}) {
  PrepareOptions o;
  o.name = name;
  o.check_self_intersection = check;
  auto p = PreparedNet::prepare(s, o, ctx);
  EXPECT_TRUE(p.has_value()) << p.status().to_string();
  return p.has_value() ? std::move(*p) : PreparedNet{};
}

template <class T>
bool same_bytes(const std::vector<T>& x, const std::vector<T>& y) {
  return x.size() == y.size() && (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(T)) == 0);
}

bool same_double(double x, double y) {
  return std::memcmp(&x, &y, sizeof x) == 0;
}

/// Results, measures and counters equal bit for bit.
::testing::AssertionResult same_report(const BooleanReport& x, const BooleanReport& y) {
  if (!same_bytes(x.result.positions, y.result.positions)) return ::testing::AssertionFailure() << "positions differ";
  if (x.result.face_offsets != y.result.face_offsets || x.result.face_nodes != y.result.face_nodes)
    return ::testing::AssertionFailure() << "faces differ";
  if (x.seam != y.seam) return ::testing::AssertionFailure() << "seams differ";
  for (auto [u, v] : {std::pair{x.volume, y.volume},
                      {x.area, y.area},
                      {x.volume_a, y.volume_a},
                      {x.volume_b, y.volume_b},
                      {x.area_a, y.area_a},
                      {x.area_b, y.area_b}})
    if (!same_double(u, v)) return ::testing::AssertionFailure() << "measures differ: " << u << " " << v;
  if (x.intersection_polygons != y.intersection_polygons || x.candidate_pairs != y.candidate_pairs ||
      x.intersection_points != y.intersection_points || x.cut_triangles != y.cut_triangles)
    return ::testing::AssertionFailure() << "counters differ";
  return ::testing::AssertionSuccess();
}

/// The same tables as prepare() builds: triangles, edges, boxes, hierarchy,
/// measures.
::testing::AssertionResult same_tables(const PreparedNet& x, const PreparedNet& y) {
  using net_detail::PreparedAccess;
  const net_detail::PreparedData *a = PreparedAccess::get(x), *b = PreparedAccess::get(y);
  if (!a || !b) return ::testing::AssertionFailure() << "empty";
  const net_detail::TriMesh &m = a->mesh, &n = b->mesh;
  if (!same_bytes(m.p, n.p) || m.tri != n.tri || m.tri_edge != n.tri_edge || m.edge != n.edge ||
      m.edge_tri != n.edge_tri || m.face_of != n.face_of || m.face_tri_begin != n.face_tri_begin ||
      !same_bytes(m.box, n.box) || m.net_vertices != n.net_vertices || m.name != n.name)
    return ::testing::AssertionFailure() << "triangulated nets differ";
  if (a->bvh.order != b->bvh.order || !same_bytes(a->bvh.box, b->bvh.box) || a->bvh.nodes.size() != b->bvh.nodes.size())
    return ::testing::AssertionFailure() << "hierarchies differ";
  for (std::size_t i = 0; i < a->bvh.nodes.size(); ++i) {
    const auto &u = a->bvh.nodes[i], &v = b->bvh.nodes[i];
    if (u.box != v.box || u.left != v.left || u.first != v.first || u.count != v.count)
      return ::testing::AssertionFailure() << "hierarchy node " << i << " differs";
  }
  if (!same_double(a->volume, b->volume) || !same_double(a->area, b->area))
    return ::testing::AssertionFailure() << "measures differ";
  if (!same_bytes(a->owned.positions, b->owned.positions) || a->owned.face_nodes != b->owned.face_nodes ||
      a->owned.face_offsets != b->owned.face_offsets)
    return ::testing::AssertionFailure() << "soups differ";
  return ::testing::AssertionSuccess();
}

/// The pairs of boolean_test.cpp: overlapping and coplanar cubes, a lens of
/// an icosphere and a UV sphere (quads and fans), touching, nested and
/// pocket boxes, shared vertices, grid boxes.
std::vector<std::pair<PolygonSoup, PolygonSoup>> unit_pairs() {
  std::vector<std::pair<PolygonSoup, PolygonSoup>> p;
  const PolygonSoup cube = box({0, 0, 0}, {1, 1, 1});
  p.emplace_back(cube, box({.5, .25, -.5}, {1.5, 1.25, .5}));
  p.emplace_back(cube, box({.5, 0, 0}, {1.5, 1, 1}));
  p.emplace_back(icosphere(3, 1.0, {0, 0, 0}),
                 net_test::from_shapes(shapes::uv_sphere(40, 20, 1.0, {0.8, 0.0123, -0.0071})));
  p.emplace_back(cube, box({1, 0, 0}, {2, 1, 1}));
  p.emplace_back(cube, box_triangles({0.25, 0.25, 0}, {0.75, 0.75, 0.5}));
  p.emplace_back(cube, box({0.25, 0.25, 0.25}, {0.75, 0.75, 0.75}));
  p.emplace_back(cube, box_triangles({1, 1, 0}, {2, 2, 1}));
  const PolygonSoup ico = icosphere(2, 1.0, {0, 0, 0});
  PolygonSoup moved = ico;
  for (auto& x : moved.positions) x += ico.positions[5] - ico.positions[0];
  p.emplace_back(ico, moved);
  std::uint64_t seed = 12345;
  for (int trial = 0; trial < 6; ++trial) {
    Vec3d lo[2], hi[2];
    net_test::grid_box_pair(seed, lo, hi);
    p.emplace_back(trial % 2 ? box(lo[0], hi[0]) : box_triangles(lo[0], hi[0]),
                   trial % 3 ? box_triangles(lo[1], hi[1]) : box(lo[1], hi[1]));
  }
  return p;
}

void expect_prepared_is_one_call(const PolygonSoup& a, const PolygonSoup& b, const std::string& what) {
  const PreparedNet pa = prepared(a, "A"), pb = prepared(b, "B");
  EXPECT_TRUE(same_double(pa.volume(), soup_volume(a)));
  EXPECT_TRUE(same_double(pb.area(), soup_area(b)));
  for (BooleanOp op : net_test::kAllOps) {
    BooleanOptions o;
    o.op = op;
    auto one = net_boolean(a, b, o);
    auto two = net_boolean(pa, pb, o);
    ASSERT_EQ(one.has_value(), two.has_value()) << what;
    if (!one) {
      EXPECT_EQ(one.status().message(), two.status().message()) << what;
      continue;
    }
    EXPECT_TRUE(same_report(*one, *two)) << what << " op " << static_cast<int>(op);
  }
}

TEST(NetPrepared, PreparedBooleanIsTheOneCallOnTheUnitShapes) {
  int i = 0;
  for (const auto& [a, b] : unit_pairs()) expect_prepared_is_one_call(a, b, "pair " + std::to_string(i++));
}

TEST(NetPrepared, PreparedBooleanIsTheOneCallOnTheSharedPairs) {
  const auto dir = std::filesystem::path(ATELIER_SHARED_DATA) / "meshes" / "boolean-pairs";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "shared data absent: " << dir;
  for (auto [x, y] : {std::pair{"Havocglass8_left.obj", "Havocglass8_right.obj"},
                      {"Offset3.obj", "Offset4.obj"},
                      {"Cray_left.obj", "Cray_right.obj"}})
    expect_prepared_is_one_call(net_polygons(read_obj(dir / x)), net_polygons(read_obj(dir / y)), x);
}

TEST(NetPrepared, PrepareRefusesBadNetsWithTheOneCallsMessages) {
  const PolygonSoup good = box({0, 0, 0}, {1, 1, 1});
  std::vector<PolygonSoup> bad;
  PolygonSoup open = box({.5, .5, .5}, {2, 2, 2});  // a face missing
  open.face_offsets.pop_back();
  open.face_nodes.resize(open.face_offsets.back());
  bad.push_back(open);
  const PolygonSoup two = net_test::two_boxes_in_one_net();
  bad.push_back(two);
  PolygonSoup inward = box({.5, .5, .5}, {2, 2, 2});
  for (std::size_t f = 0; f < inward.face_count(); ++f)
    std::reverse(inward.face_nodes.begin() + inward.face_offsets[f],
                 inward.face_nodes.begin() + inward.face_offsets[f + 1]);
  bad.push_back(inward);
  PolygonSoup dup = box({.5, .5, .5}, {2, 2, 2});
  dup.positions.push_back(dup.positions[0]);
  dup.face_nodes[0] = 8;
  bad.push_back(dup);
  bad.push_back(PolygonSoup{});
  for (std::size_t i = 0; i < bad.size(); ++i) {
    auto one = net_boolean(good, bad[i], {});
    ASSERT_FALSE(one.has_value()) << i;
    PrepareOptions o;
    o.name = "B";
    auto p = PreparedNet::prepare(bad[i], o);
    ASSERT_FALSE(p.has_value()) << i;
    EXPECT_EQ(p.status().code(), one.status().code()) << i;
    EXPECT_EQ(p.status().message(), one.status().message()) << i;
    EXPECT_NE(p.status().message().find("net B"), std::string::npos) << p.status().message();
  }
  // Without the self-intersection test the crossing net is prepared, and
  // a Boolean that asks for the test refuses it (naming it) rather than
  // skipping it silently.
  const PreparedNet unchecked = prepared(two, "B", false);
  EXPECT_FALSE(unchecked.self_checked());
  auto r = net_boolean(prepared(good, "A"), unchecked, {});
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("net B was prepared without"), std::string::npos) << r.status().message();
  EXPECT_FALSE(net_boolean(PreparedNet{}, unchecked, {}).has_value());
}

TEST(NetPrepared, UncheckedOperandsGiveTheOneCallsUncheckedBits) {
  const PolygonSoup a = icosphere(3, 1.0, {0, 0, 0}), b = icosphere(3, 0.7, {0.6, 0.2, 0.1});
  BooleanOptions o;
  o.op = BooleanOp::kAMinusB;
  o.check_self_intersection = false;
  auto one = net_boolean(a, b, o);
  auto two = net_boolean(prepared(a, "A", false), prepared(b, "B", false), o);
  ASSERT_TRUE(one.has_value() && two.has_value());
  EXPECT_TRUE(same_report(*one, *two));
}

/// A - B1 - B2 - B3 (tools of different kinds: a box through the sphere,
/// a sphere biting a side, a box sharing no vertex), then a union: each
/// prepared result gives the one-call step's bits, and is what prepare()
/// builds from the result's soup.
TEST(NetPrepared, AChainOfPreparedResultsIsTheChainOfOneCallSteps) {
  const PolygonSoup a = icosphere(3, 1.0, {0, 0, 0});
  const std::vector<std::pair<PolygonSoup, BooleanOp>> tools = {
      {box_triangles({-0.3, -0.25, -2}, {0.31, 0.27, 2}), BooleanOp::kAMinusB},
      {icosphere(2, 0.5, {0.9, 0.1, 0.2}), BooleanOp::kAMinusB},
      {box({-2, -2, 0.55}, {2, 2, 3}), BooleanOp::kAMinusB},
      {icosphere(2, 0.4, {-0.8, 0.3, 0.1}), BooleanOp::kUnion}};
  PolygonSoup step = a;  // the one-call chain
  PreparedNet net = prepared(a, "A");
  for (std::size_t i = 0; i < tools.size(); ++i) {
    BooleanOptions o;
    o.op = tools[i].second;
    auto one = net_boolean(step, tools[i].first, o);
    ASSERT_TRUE(one.has_value()) << one.status().to_string();
    o.prepare_result = true;
    auto two = net_boolean(net, prepared(tools[i].first, "B"), o);
    ASSERT_TRUE(two.has_value()) << two.status().to_string();
    EXPECT_TRUE(same_report(*one, *two)) << "step " << i;
    EXPECT_TRUE(net_test::closed_model(two->result));
    ASSERT_TRUE(two->prepared_status) << two->prepared_status.to_string();
    ASSERT_FALSE(two->prepared.empty());
    EXPECT_TRUE(two->prepared.self_checked());
    // prepare() with the full checks accepts the result and builds the
    // same tables (so the skipped test would have passed).
    const PreparedNet again = prepared(one->result, "A");
    EXPECT_TRUE(same_tables(two->prepared, again)) << "step " << i;
    EXPECT_TRUE(same_double(two->prepared.volume(), two->volume));
    step = std::move(one->result);
    net = std::move(two->prepared);
  }
  EXPECT_LT(net.volume(), soup_volume(a));
  EXPECT_GT(net.volume(), 0.0);
}

TEST(NetPrepared, AResultThatCannotBeAnOperandSaysWhy) {
  // Disjoint nets: the intersection is empty, the Boolean succeeds.
  BooleanOptions o;
  o.op = BooleanOp::kIntersection;
  o.prepare_result = true;
  auto r = net_boolean(prepared(box({0, 0, 0}, {1, 1, 1}), "A"), prepared(box({3, 3, 3}, {4, 4, 4}), "B"), o);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->result.face_count(), 0u);
  EXPECT_TRUE(r->prepared.empty());
  EXPECT_FALSE(r->prepared_status);
  EXPECT_NE(r->prepared_status.message().find("no faces"), std::string::npos) << r->prepared_status.to_string();
  // Solids touching along an edge: the union has coincident copies of the
  // pinched vertices, which prepare() refuses as duplicates.
  o.op = BooleanOp::kUnion;
  auto t = net_boolean(prepared(box({0, 0, 0}, {1, 1, 1}), "A"), prepared(box_triangles({1, 1, 0}, {2, 2, 1}), "B"), o);
  ASSERT_TRUE(t.has_value());
  auto direct = PreparedNet::prepare(t->result);
  ASSERT_FALSE(direct.has_value());
  EXPECT_TRUE(t->prepared.empty());
  EXPECT_EQ(t->prepared_status.message(), direct.status().message());
  EXPECT_NE(direct.status().message().find("duplicate"), std::string::npos) << direct.status().to_string();
  // Paper mode moves points: its result is prepared with the full checks.
  o.op = BooleanOp::kUnion;
  o.mode = BooleanMode::kPaper;
  const PolygonSoup a = icosphere(3, 1.0, {0, 0, 0}), b = icosphere(3, 0.8, {0.9, 0.05, 0.03});
  auto p = net_boolean(prepared(a, "A"), prepared(b, "B"), o);
  ASSERT_TRUE(p.has_value());
  auto full = PreparedNet::prepare(p->result);
  ASSERT_EQ(p->prepared.empty(), !full.has_value());
  if (full) {
    EXPECT_TRUE(same_tables(p->prepared, *full));
  }
}

/// Two threads doing Booleans with the same prepared A (and the same
/// prepared tools), each with a two-thread context, give the one-thread
/// bits.
TEST(NetPrepared, ThreadsShareAPreparedNet) {
  const PolygonSoup a = icosphere(4, 1.0, {0, 0, 0});
  const PreparedNet pa = prepared(a, "A");
  const std::vector<PreparedNet> tools = {prepared(icosphere(4, 1.0, {0.61, 0.23, 0.17}), "B"),
                                          prepared(icosphere(3, 0.5, {-0.7, 0.1, 0.3}), "B")};
  std::vector<BooleanReport> want;
  for (const PreparedNet& b : tools) {
    BooleanOptions o;
    o.op = BooleanOp::kAMinusB;
    auto r = net_boolean(pa, b, o, ExecContext::sequential());
    ASSERT_TRUE(r.has_value());
    want.push_back(std::move(*r));
  }
  std::vector<BooleanReport> got[2];
  auto work = [&](int t) {
    ExecContext two;
    two.threads = 2;
    for (int round = 0; round < 2; ++round)
      for (std::size_t k = 0; k < tools.size(); ++k) {
        BooleanOptions o;
        o.op = BooleanOp::kAMinusB;
        auto r = net_boolean(pa, tools[(k + static_cast<std::size_t>(t)) % tools.size()], o, two);
        if (r) got[t].push_back(std::move(*r));
      }
  };
  std::thread t0(work, 0), t1(work, 1);
  t0.join();
  t1.join();
  for (int t = 0; t < 2; ++t) {
    ASSERT_EQ(got[t].size(), 2 * tools.size());
    for (std::size_t i = 0; i < got[t].size(); ++i)
      EXPECT_TRUE(same_report(got[t][i], want[(i + static_cast<std::size_t>(t)) % tools.size()]))
          << "thread " << t << " call " << i;
  }
}

TEST(NetPrepared, PreparedBooleanReportsItsThreeStages) {
  std::vector<std::string> seen;
  ExecContext ctx;
  ctx.progress = [&](std::string_view stage, std::size_t done, std::size_t total) {
    seen.emplace_back(stage);
    EXPECT_EQ(done, seen.size());
    EXPECT_EQ(total, 3u);
  };
  auto r = net_boolean(prepared(icosphere(2, 1.0, {0, 0, 0}), "A"), prepared(icosphere(2, 1.0, {0.5, 0.13, 0.07}), "B"),
                       {}, ctx);
  ASSERT_TRUE(r.has_value()) << r.status().to_string();
  EXPECT_EQ(seen, (std::vector<std::string>{"boolean: cut", "boolean: classify", "boolean: result"}));
}

}  // namespace
}  // namespace atelier
