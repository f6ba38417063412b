// Extended Euler operators: Euler-Poincare deltas against an independent
// recount (count_topology), exact inverses (diff_tables), error codes, and a
// random build/undo property test.
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/mesh/euler.h>
#include <gtest/gtest.h>

#include <array>
#include <functional>
#include <random>

#include "support/fixtures.h"
#include "tests/support/expect.h"

using namespace atelier;

namespace {

struct Delta {
  std::int64_t v = 0, e = 0, f = 0, r = 0, c = 0, s = 0, h = 0;
};

struct Snap {
  TopologyCounts t;
  std::int64_t h;
};
Snap snap(const Model& m) {
  return {count_topology(m), m.complex_holes};
}

void expect_delta(const Snap& a, const Model& m, const Delta& d, const char* what) {
  const Snap b = snap(m);
  EXPECT_EQ(b.t.nodes - a.t.nodes, d.v) << what << ": V";
  EXPECT_EQ(b.t.edges - a.t.edges, d.e) << what << ": E";
  EXPECT_EQ(b.t.faces - a.t.faces, d.f) << what << ": F";
  EXPECT_EQ(b.t.rings - a.t.rings, d.r) << what << ": R";
  EXPECT_EQ(b.t.components - a.t.components, d.c) << what << ": C";
  EXPECT_EQ(b.t.shells - a.t.shells, d.s) << what << ": S";
  EXPECT_EQ(b.h - a.h, d.h) << what << ": H";
  const Status v = validate(m);
  EXPECT_TRUE(v) << what << ": " << v.to_string();
}

#define ASSERT_OK(expr)                                          \
  do {                                                           \
    const auto& r_ = (expr);                                     \
    ASSERT_TRUE(r_) << #expr << ": " << r_.status().to_string(); \
  } while (0)

using atelier::testing::ok;

}  // namespace

TEST(Euler, FixturesAreValid) {
  EXPECT_TRUE(validate(fixtures::single_triangle()));
  EXPECT_TRUE(validate(fixtures::quad_strip(3)));
  EXPECT_TRUE(validate(fixtures::tetrahedron()));
  EXPECT_TRUE(validate(fixtures::octahedron()));
  EXPECT_TRUE(validate(fixtures::grid_patch(4, 3).model));
  for (int k : {3, 5})
    EXPECT_TRUE(validate(fixtures::fan(k, 4).model)) << validate(fixtures::fan(k, 4).model).to_string();
  EXPECT_TRUE(validate(fixtures::inner_edge_joint(4).model))
      << validate(fixtures::inner_edge_joint(4).model).to_string();
  auto inc = fixtures::incomplete();
  EXPECT_TRUE(validate(inc.model)) << validate(inc.model).to_string();
  const auto t = count_topology(inc.model);
  EXPECT_EQ(t.rings, 1);
  EXPECT_EQ(t.faces, 2);
  EXPECT_EQ(t.components, 5);  // triangle (+ring, + dangling edge), quad, polyline, two isolated nodes
}

TEST(Euler, VertexComplexRoundTrip) {
  Model m = fixtures::single_triangle();
  const Model orig = m;
  Snap a = snap(m);
  const Node v = ok(make_vertex_complex(m, m.handle(SurfaceIdx{0}), Vec3d(5, 5, 5)));
  expect_delta(a, m, {.v = 1, .c = 1}, "make_vertex_complex");
  const Model made = m;
  a = snap(m);
  const NodeRecord r = ok(kill_vertex_complex(m, v));
  expect_delta(a, m, {.v = -1, .c = -1}, "kill_vertex_complex");
  EXPECT_EQ(diff_tables(orig, m), "");
  ASSERT_OK(make_vertex_complex(m, r));
  EXPECT_EQ(diff_tables(made, m), "");
}

TEST(Euler, VertexEdgeRoundTrip) {
  auto inc = fixtures::incomplete();
  Model& m = inc.model;
  const Model orig = m;
  Snap a = snap(m);
  // kill(make(x)) on a new edge from a triangle corner.
  const VertexEdge ve = ok(make_vertex_edge(m, m.handle(NodeIdx{2}), Vec3d(-1, 2, 0)));
  expect_delta(a, m, {.v = 1, .e = 1}, "make_vertex_edge");
  EXPECT_EQ(m.tail(halfedge_of(ve.edge.idx, 0)), NodeIdx{2});
  ASSERT_OK(kill_vertex_edge(m, ve.node));
  EXPECT_EQ(diff_tables(orig, m), "");
  // make(kill(x)) on the fixture's free polyline end, whose edge runs towards it.
  const NodeIdx end = m.head(halfedge_of(inc.wires[2].idx, 0));
  a = snap(m);
  const VertexEdgeRecord r = ok(kill_vertex_edge(m, m.handle(end)));
  expect_delta(a, m, {.v = -1, .e = -1}, "kill_vertex_edge");
  ASSERT_OK(make_vertex_edge(m, r));
  EXPECT_EQ(diff_tables(orig, m), "");
}

TEST(Euler, EdgeCholeAndFaceOnWireCycle) {
  auto inc = fixtures::incomplete();
  Model& m = inc.model;
  const Model orig = m;
  // Polyline p0 - p1 - p2: close it into a triangle of wire edges.
  const NodeIdx p0 = m.tail(halfedge_of(inc.wires[1].idx, 0)), p1 = m.head(halfedge_of(inc.wires[1].idx, 0));
  const NodeIdx p2 = m.head(halfedge_of(inc.wires[2].idx, 0));
  Snap a = snap(m);
  const Edge e = ok(make_edge_Chole(m, m.handle(p2), m.handle(p0)));
  expect_delta(a, m, {.e = 1, .h = 1}, "make_edge_Chole");
  const Model with_edge = m;
  const HalfedgeIdx cyc[3] = {m.find_halfedge(p0, p1), m.find_halfedge(p1, p2), m.find_halfedge(p2, p0)};
  a = snap(m);
  const Face f = ok(make_face_kill_Chole(m, cyc));
  expect_delta(a, m, {.f = 1, .h = -1}, "make_face_kill_Chole");
  EXPECT_EQ(m.faces.halfedge[f.idx.value], cyc[0]);
  a = snap(m);
  const FaceRecord fr = ok(kill_face_make_Chole(m, f));
  expect_delta(a, m, {.f = -1, .h = 1}, "kill_face_make_Chole");
  EXPECT_FALSE(fr.closed_shell);
  EXPECT_EQ(diff_tables(with_edge, m), "");
  a = snap(m);
  const EdgeRecord er = ok(kill_edge_Chole(m, e));
  expect_delta(a, m, {.e = -1, .h = -1}, "kill_edge_Chole");
  EXPECT_EQ(diff_tables(orig, m), "");
  ASSERT_OK(make_edge_Chole(m, er));
  EXPECT_EQ(diff_tables(with_edge, m), "");
}

TEST(Euler, EdgeKillComplexRoundTrip) {
  auto inc = fixtures::incomplete();
  Model& m = inc.model;
  const Model orig = m;
  Snap a = snap(m);
  const Edge e = ok(make_edge_kill_complex(m, inc.isolated[0], m.handle(NodeIdx{4})));
  expect_delta(a, m, {.e = 1, .c = -1}, "make_edge_kill_complex");
  const Model made = m;
  a = snap(m);
  const EdgeRecord r = ok(kill_edge_make_complex(m, e));
  expect_delta(a, m, {.e = -1, .c = 1}, "kill_edge_make_complex");
  EXPECT_EQ(diff_tables(orig, m), "");
  ASSERT_OK(make_edge_kill_complex(m, r));
  EXPECT_EQ(diff_tables(made, m), "");
}

TEST(Euler, FaceOnClosedShell) {
  for (Model m : {fixtures::tetrahedron(), fixtures::octahedron()}) {
    const Model orig = m;
    Snap a = snap(m);
    ASSERT_EQ(a.t.shells, 1);
    const FaceRecord r = ok(kill_face_make_Chole(m, m.handle(FaceIdx{1})));
    EXPECT_TRUE(r.closed_shell);
    expect_delta(a, m, {.f = -1, .s = -1}, "kill_face on a closed shell");
    const Model open = m;
    a = snap(m);
    ASSERT_OK(make_face_kill_Chole(m, r));
    expect_delta(a, m, {.f = 1, .s = 1}, "make_face closing the shell");
    EXPECT_EQ(diff_tables(orig, m), "");
    // A second face removed: now an ordinary hole.
    ASSERT_OK(kill_face_make_Chole(m, m.handle(FaceIdx{1})));
    a = snap(m);
    const FaceRecord r2 = ok(kill_face_make_Chole(m, m.handle(FaceIdx{0})));
    EXPECT_FALSE(r2.closed_shell);
    expect_delta(a, m, {.f = -1, .h = 1}, "kill_face on an open group");
    ASSERT_OK(make_face_kill_Chole(m, r2));
    EXPECT_EQ(diff_tables(open, m), "");
  }
}

TEST(Euler, Rings) {
  Model m = fixtures::single_triangle();
  const Model orig = m;
  const Face f = m.handle(FaceIdx{0});
  Snap a = snap(m);
  const Node r1 = ok(make_vertex_ring(m, f, Vec3d(0.2, 0.2, 0)));
  expect_delta(a, m, {.v = 1, .r = 1}, "make_vertex_ring");
  a = snap(m);
  const VertexEdge r1b = ok(make_vertex_edge(m, r1, Vec3d(0.3, 0.2, 0)));
  expect_delta(a, m, {.v = 1, .e = 1}, "make_vertex_edge in a ring");
  EXPECT_EQ(m.nodes.in_face[r1b.node.idx.value], f.idx);
  const Node r2 = ok(make_vertex_ring(m, f, Vec3d(0.25, 0.3, 0)));
  const Model two_rings = m;
  a = snap(m);
  const Edge e = ok(make_edge_kill_ring(m, r2, r1b.node));
  expect_delta(a, m, {.e = 1, .r = -1}, "make_edge_kill_ring");
  const Model one_ring = m;
  a = snap(m);
  const Edge c = ok(make_edge_Chole(m, r2, r1));
  expect_delta(a, m, {.e = 1, .h = 1}, "make_edge_Chole in a ring");
  ASSERT_OK(kill_edge_Chole(m, c));
  EXPECT_EQ(diff_tables(one_ring, m), "");
  a = snap(m);
  const EdgeRecord er = ok(kill_edge_make_ring(m, e));
  expect_delta(a, m, {.e = -1, .r = 1}, "kill_edge_make_ring");
  EXPECT_EQ(diff_tables(two_rings, m), "");
  ASSERT_OK(make_edge_kill_ring(m, er));
  EXPECT_EQ(diff_tables(one_ring, m), "");
  ASSERT_OK(kill_edge_make_ring(m, m.handle(e.idx)));
  // Face with rings cannot be killed; a ring node is not a complex vertex.
  EXPECT_EQ(kill_face_make_Chole(m, f).status().code(), ErrorCode::kTopology);
  EXPECT_EQ(kill_vertex_complex(m, r2).status().code(), ErrorCode::kTopology);
  a = snap(m);
  const NodeRecord nr = ok(kill_vertex_ring(m, r2));
  expect_delta(a, m, {.v = -1, .r = -1}, "kill_vertex_ring");
  ASSERT_OK(make_vertex_ring(m, nr));
  ASSERT_OK(kill_vertex_ring(m, m.handle(r2.idx)));
  ASSERT_OK(kill_vertex_edge(m, m.handle(r1b.node.idx)));
  ASSERT_OK(kill_vertex_ring(m, m.handle(r1.idx)));
  EXPECT_EQ(diff_tables(orig, m), "");
}

TEST(Euler, SplitMergeInteriorEdge) {
  auto g = fixtures::grid_patch(3, 3);
  Model& m = g.model;
  const Model orig = m;
  const HalfedgeIdx h = m.find_halfedge(g.node(1, 1), g.node(2, 2));  // interior diagonal
  ASSERT_TRUE(h.valid());
  const FaceIdx f0 = m.face(h), f1 = m.face(twin(h));
  Snap a = snap(m);
  const Vec3d p(1.5, 1.5, 0);
  const SplitEdgeResult s = ok(split_edge(m, m.handle(edge_of(h)), p));
  expect_delta(a, m, {.v = 1, .e = 1}, "split_edge");
  EXPECT_EQ(m.face_degree(f0), 4u);
  EXPECT_EQ(m.face_degree(f1), 4u);
  EXPECT_EQ(m.head(halfedge_of(edge_of(h), 0)), s.node.idx);
  EXPECT_EQ(m.position(s.node.idx), p);
  const Model split = m;
  a = snap(m);
  const MergeEdgeRecord r = ok(merge_edge(m, s.node, m.handle(edge_of(h)), s.attribs));
  expect_delta(a, m, {.v = -1, .e = -1}, "merge_edge");
  EXPECT_EQ(diff_tables(orig, m), "");
  ASSERT_OK(split_edge(m, r));
  EXPECT_EQ(diff_tables(split, m), "");
}

TEST(Euler, SplitMergeMeshEdgeKeepsChainOrder) {
  auto g = fixtures::grid_patch(3, 2);
  Model& m = g.model;
  const Model orig = m;
  // Top side runs right to left: split its second edge, against and along.
  const MeshEdgeIdx top = g.sides[2].idx;
  const HalfedgeIdx c1 = m.mesh_edges.halfedges.row(top.value)[1];
  for (HalfedgeIdx h : {c1, twin(c1)}) {
    const Vec3d p = 0.5 * (m.position(m.tail(h)) + m.position(m.head(h)));
    const SplitEdgeResult s = ok(split_edge(m, m.handle(h), p));
    ASSERT_TRUE(validate(m)) << validate(m).to_string();
    auto row = m.mesh_edges.halfedges.row(top.value);
    ASSERT_EQ(row.size(), 4u);
    EXPECT_EQ(m.head(row[1]), s.node.idx);
    EXPECT_EQ(m.tail(row[2]), s.node.idx);
    EXPECT_EQ(m.edges.mesh_edge[s.new_edge.idx.value], top);
    ASSERT_OK(merge_edge(m, s.node, m.handle(edge_of(h)), s.attribs));
    EXPECT_EQ(diff_tables(orig, m), "");
  }
}

TEST(Euler, MergeThenSplitCornerOfQuad) {
  Model m = fixtures::quad_strip(2);
  const Model orig = m;
  // Node 0 has degree 2; merging turns quad 0 into a triangle.
  std::vector<HalfedgeIdx> out;
  m.outgoing(NodeIdx{0}, out);
  ASSERT_EQ(out.size(), 2u);
  for (HalfedgeIdx keep : out) {
    const Snap a = snap(m);
    const MergeEdgeRecord r = ok(merge_edge(m, m.handle(NodeIdx{0}), m.handle(edge_of(keep))));
    expect_delta(a, m, {.v = -1, .e = -1}, "merge_edge");
    EXPECT_EQ(m.face_degree(FaceIdx{0}), 3u);
    ASSERT_OK(split_edge(m, r));
    EXPECT_EQ(diff_tables(orig, m), "");
  }
}

TEST(Euler, SplitMovesEdgeAndFaceAttributes) {
  auto g = fixtures::grid_patch(2, 2);
  Model& m = g.model;
  const HalfedgeIdx h = m.find_halfedge(g.node(1, 0), g.node(1, 1));  // interior vertical edge
  const SurfaceIdx s = g.surface.idx;
  auto pos_of = [&](HalfedgeIdx x, double u) { return (1 - u) * m.position(m.tail(x)) + u * m.position(m.head(x)); };
  const AttribNodeIdx e1 = m.new_attrib_node(s, AttribNodeKind::kEdge, h.value, Vec3d(0.25, 0, 0), pos_of(h, 0.25));
  const AttribNodeIdx e2 =
      m.new_attrib_node(s, AttribNodeKind::kEdge, twin(h).value, Vec3d(0.1, 0, 0), pos_of(twin(h), 0.1));
  const AttribNodeIdx fa =
      m.new_attrib_node(s, AttribNodeKind::kFace, m.face(h).value, Vec3d(0.2, 0.3, 0.5), Vec3d::Zero());
  const AttribNodeIdx list[3] = {e1, e2, fa};
  (void)m.new_attrib_edge(s, 7, list);
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  const Model orig = m;
  std::vector<Vec3d> before;
  for (AttribNodeIdx a : list) before.push_back(m.attrib_position_on_surface(a));
  // Split at 0.4 (from (1,0)): e1 (0.25) stays on the first half, e2 (0.9 from (1,0)) moves.
  const SplitEdgeResult r = ok(split_edge(m, m.handle(h), pos_of(h, 0.4)));
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  for (int i = 0; i < 3; ++i) EXPECT_LT((m.attrib_position_on_surface(list[i]) - before[i]).norm(), 1e-12) << i;
  EXPECT_EQ(edge_of(HalfedgeIdx{m.attrib_nodes.element[e1.value]}), edge_of(h));
  EXPECT_NEAR(m.attrib_nodes.param[e1.value].x(), 0.25 / 0.4, 1e-12);
  EXPECT_EQ(edge_of(HalfedgeIdx{m.attrib_nodes.element[e2.value]}), r.new_edge.idx);
  EXPECT_EQ(r.attribs.size(), 3u);
  // Plain merge re-expresses them (positions kept); with the split's record it is bit-exact.
  Model plain = m;
  ASSERT_OK(merge_edge(plain, plain.handle(r.node.idx), plain.handle(edge_of(h))));
  ASSERT_TRUE(validate(plain)) << validate(plain).to_string();
  for (int i = 0; i < 3; ++i) EXPECT_LT((plain.attrib_position_on_surface(list[i]) - before[i]).norm(), 1e-12) << i;
  ASSERT_OK(merge_edge(m, r.node, m.handle(edge_of(h)), r.attribs));
  EXPECT_EQ(diff_tables(orig, m), "");
}

TEST(Euler, ErrorCodes) {
  auto inc = fixtures::incomplete();
  Model& m = inc.model;
  const Model orig = m;
  // Stale handle.
  const Node iso = inc.isolated[1];
  const NodeRecord r = ok(kill_vertex_complex(m, iso));
  EXPECT_EQ(kill_vertex_complex(m, iso).status().code(), ErrorCode::kStaleHandle);
  EXPECT_EQ(make_vertex_edge(m, iso, Vec3d::Zero()).status().code(), ErrorCode::kStaleHandle);
  ASSERT_OK(make_vertex_complex(m, r));
  EXPECT_EQ(kill_vertex_complex(m, iso).status().code(), ErrorCode::kStaleHandle);  // slot reused, generation differs
  // Non-isolated node.
  const auto nonisolated = kill_vertex_complex(m, m.handle(NodeIdx{0}));
  EXPECT_EQ(nonisolated.status().code(), ErrorCode::kTopology);
  EXPECT_NE(nonisolated.status().message().find("node 0"), std::string::npos) << nonisolated.status().message();
  // Face over a non-closed chain (the polyline p0 -> p1 -> p2 and back is not a cycle of 3).
  const HalfedgeIdx w1 = halfedge_of(inc.wires[1].idx, 0), w2 = halfedge_of(inc.wires[2].idx, 0);
  const HalfedgeIdx open_chain[3] = {w1, w2, twin(w2)};
  EXPECT_EQ(make_face_kill_Chole(m, open_chain).status().code(), ErrorCode::kTopology);
  // Chain already having a face.
  std::vector<HalfedgeIdx> tri;
  m.face_halfedges(inc.triangle.idx, tri);
  EXPECT_EQ(make_face_kill_Chole(m, tri).status().code(), ErrorCode::kTopology);
  // Parallel edge, wrong Chole/complex classification.
  EXPECT_EQ(make_edge_Chole(m, m.handle(NodeIdx{0}), m.handle(NodeIdx{1})).status().code(), ErrorCode::kTopology);
  EXPECT_EQ(make_edge_Chole(m, m.handle(NodeIdx{0}), m.handle(NodeIdx{3})).status().code(), ErrorCode::kTopology);
  EXPECT_EQ(make_edge_kill_complex(m, m.handle(NodeIdx{0}), m.handle(NodeIdx{2})).status().code(),
            ErrorCode::kTopology);
  EXPECT_EQ(kill_edge_Chole(m, inc.wires[1]).status().code(), ErrorCode::kTopology);          // a bridge
  EXPECT_EQ(kill_edge_Chole(m, m.handle(EdgeIdx{0})).status().code(), ErrorCode::kTopology);  // bounds a face
  // Ring node joined to a face corner.
  EXPECT_EQ(make_edge_Chole(m, inc.ring, m.handle(NodeIdx{0})).status().code(), ErrorCode::kTopology);
  EXPECT_EQ(diff_tables(orig, m), "");  // failed calls changed nothing
  // Nodes in different surfaces; split of a joint edge.
  auto fan = fixtures::fan(3, 2);
  const NodeIdx a = fan.model.tail(fan.model.mesh_edges.halfedges.row(fan.members[0].idx.value)[0]);
  const NodeIdx b = fan.model.tail(fan.model.mesh_edges.halfedges.row(fan.members[1].idx.value)[0]);
  EXPECT_EQ(make_edge_kill_complex(fan.model, fan.model.handle(a), fan.model.handle(b)).status().code(),
            ErrorCode::kInvalidArgument);
  const EdgeIdx je = edge_of(fan.model.mesh_edges.halfedges.row(fan.members[0].idx.value)[0]);
  EXPECT_EQ(split_edge(fan.model, fan.model.handle(je), Vec3d(0.5, 0, 0)).status().code(), ErrorCode::kJointRefused);
}

// ------------------------------------------------------------------ random

namespace {

struct RandomBuilder {
  Model& m;
  std::mt19937 rng;
  std::vector<std::function<Status(Model&)>> undo;
  int done = 0;
  std::array<int, 14> per_op{};

  template <class T>
  T pick(const std::vector<T>& v) {
    return v[std::uniform_int_distribution<std::size_t>(0, v.size() - 1)(rng)];
  }
  double uni() { return std::uniform_real_distribution<double>(-2, 2)(rng); }
  Vec3d rpos() { return {uni(), uni(), uni()}; }
  std::vector<NodeIdx> live_nodes() const {
    std::vector<NodeIdx> v;
    for (std::uint32_t i = 0; i < m.nodes.slots.capacity(); ++i)
      if (m.alive(NodeIdx{i})) v.push_back(NodeIdx{i});
    return v;
  }
  std::vector<EdgeIdx> live_edges() const {
    std::vector<EdgeIdx> v;
    for (std::uint32_t i = 0; i < m.edges.slots.capacity(); ++i)
      if (m.alive(EdgeIdx{i})) v.push_back(EdgeIdx{i});
    return v;
  }
  std::vector<FaceIdx> live_faces() const {
    std::vector<FaceIdx> v;
    for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i)
      if (m.alive(FaceIdx{i})) v.push_back(FaceIdx{i});
    return v;
  }
  static Status st(const Status& s) { return s; }
  template <class T>
  static Status st(const Expected<T>& e) {
    return e.status();
  }

  /// A closed chain of faceless halfedges found by a random walk, or empty.
  std::vector<HalfedgeIdx> find_cycle() {
    std::vector<HalfedgeIdx> free;
    for (EdgeIdx e : live_edges())
      for (unsigned s = 0; s < 2; ++s)
        if (!m.face(halfedge_of(e, s)).valid() && !m.nodes.in_face[m.tail(halfedge_of(e, s)).value].valid())
          free.push_back(halfedge_of(e, s));
    if (free.empty()) return {};
    for (int attempt = 0; attempt < 10; ++attempt) {
      std::vector<HalfedgeIdx> cyc{pick(free)};
      std::vector<NodeIdx> seen{m.tail(cyc[0])};
      while (cyc.size() < 7) {
        const NodeIdx v = m.head(cyc.back());
        if (v == m.tail(cyc[0]) && cyc.size() >= 3) return cyc;
        if (std::find(seen.begin(), seen.end(), v) != seen.end()) break;
        seen.push_back(v);
        std::vector<HalfedgeIdx> nx;
        m.for_each_outgoing(v, [&](HalfedgeIdx x) {
          if (!m.face(x).valid() && x != twin(cyc.back())) nx.push_back(x);
        });
        if (nx.empty()) break;
        cyc.push_back(pick(nx));
      }
    }
    return {};
  }

  /// Applies one random operation; on success records its inverse.
  void step() {
    const int op = std::uniform_int_distribution<int>(0, 13)(rng);
    const auto nodes = live_nodes();
    const auto edges = live_edges();
    const auto faces = live_faces();
    const Model before = (done % 7 == 0) ? m : Model{};
    const bool check_unchanged = done % 7 == 0;
    Status s(ErrorCode::kUnsupported, "no candidate");
    switch (op) {
      case 0: {
        auto r = make_vertex_complex(m, m.handle(SurfaceIdx{0}), rpos());
        if ((s = r.status()))
          undo.push_back([i = r->idx](Model& x) { return st(kill_vertex_complex(x, x.handle(i))); });
        break;
      }
      case 1:
      case 2: {
        if (nodes.empty()) break;
        // The draws in a fixed order (a function's arguments have none: clang and GCC differ).
        const Vec3d at = rpos();
        auto r = make_vertex_edge(m, m.handle(pick(nodes)), at);
        if ((s = r.status()))
          undo.push_back([i = r->node.idx](Model& x) { return st(kill_vertex_edge(x, x.handle(i))); });
        break;
      }
      case 3:
      case 4: {
        if (nodes.size() < 2) break;
        const Node a = m.handle(pick(nodes)), b = m.handle(pick(nodes));
        // Exactly one of the three edge makers may succeed.
        auto r1 = make_edge_Chole(m, a, b);
        if (r1) {
          s = {};
          undo.push_back([i = r1->idx](Model& x) { return st(kill_edge_Chole(x, x.handle(i))); });
          break;
        }
        auto r2 = make_edge_kill_complex(m, a, b);
        if (r2) {
          s = {};
          undo.push_back([i = r2->idx](Model& x) { return st(kill_edge_make_complex(x, x.handle(i))); });
          break;
        }
        auto r3 = make_edge_kill_ring(m, a, b);
        if ((s = r3.status()))
          undo.push_back([i = r3->idx](Model& x) { return st(kill_edge_make_ring(x, x.handle(i))); });
        break;
      }
      case 5:
      case 6: {
        const auto cyc = find_cycle();
        if (cyc.empty()) break;
        auto r = make_face_kill_Chole(m, cyc);
        if ((s = r.status()))
          undo.push_back([i = r->idx](Model& x) { return st(kill_face_make_Chole(x, x.handle(i))); });
        break;
      }
      case 7: {
        if (faces.empty()) break;
        const Vec3d at = rpos();
        auto r = make_vertex_ring(m, m.handle(pick(faces)), at);
        if ((s = r.status())) undo.push_back([i = r->idx](Model& x) { return st(kill_vertex_ring(x, x.handle(i))); });
        break;
      }
      case 8: {
        if (edges.empty()) break;
        const EdgeIdx e = pick(edges);
        const HalfedgeIdx h = halfedge_of(e, std::uniform_int_distribution<unsigned>(0, 1)(rng));
        const double t = std::uniform_real_distribution<double>(0.1, 0.9)(rng);
        auto r = split_edge(m, m.handle(h), (1 - t) * m.position(m.tail(h)) + t * m.position(m.head(h)));
        if ((s = r.status()))
          undo.push_back([v = r->node.idx, e, at = r->attribs](Model& x) {
            return st(merge_edge(x, x.handle(v), x.handle(e), at));
          });
        break;
      }
      case 9: {  // kills, each undone by its make
        if (faces.empty()) break;
        auto r = kill_face_make_Chole(m, m.handle(pick(faces)));
        if ((s = r.status())) undo.push_back([rec = *r](Model& x) { return st(make_face_kill_Chole(x, rec)); });
        break;
      }
      case 10: {
        if (edges.empty()) break;
        const Edge e = m.handle(pick(edges));
        if (auto r = kill_edge_Chole(m, e)) {
          s = {};
          undo.push_back([rec = *r](Model& x) { return st(make_edge_Chole(x, rec)); });
        } else if (auto r2 = kill_edge_make_complex(m, e)) {
          s = {};
          undo.push_back([rec = *r2](Model& x) { return st(make_edge_kill_complex(x, rec)); });
        } else if (auto r3 = kill_edge_make_ring(m, e)) {
          s = {};
          undo.push_back([rec = *r3](Model& x) { return st(make_edge_kill_ring(x, rec)); });
        } else {
          s = r3.status();
        }
        break;
      }
      case 11: {
        if (nodes.empty()) break;
        const Node v = m.handle(pick(nodes));
        if (auto r = kill_vertex_complex(m, v)) {
          s = {};
          undo.push_back([rec = *r](Model& x) { return st(make_vertex_complex(x, rec)); });
        } else if (auto r2 = kill_vertex_ring(m, v)) {
          s = {};
          undo.push_back([rec = *r2](Model& x) { return st(make_vertex_ring(x, rec)); });
        } else if (auto r3 = kill_vertex_edge(m, v)) {
          s = {};
          undo.push_back([rec = *r3](Model& x) { return st(make_vertex_edge(x, rec)); });
        } else {
          s = r3.status();
        }
        break;
      }
      case 12:
      case 13: {
        if (nodes.empty()) break;
        const NodeIdx v = pick(nodes);
        if (m.degree(v) != 2) break;
        auto r = merge_edge(m, m.handle(v), m.handle(edge_of(m.nodes.out[v.value])));
        if ((s = r.status())) undo.push_back([rec = *r](Model& x) { return st(split_edge(x, rec)); });
        break;
      }
    }
    if (s) {
      ++done;
      ++per_op[op];
    } else {
      ASSERT_NE(s.code(), ErrorCode::kInternal) << s.message();
      if (check_unchanged) {
        ASSERT_EQ(diff_tables(before, m), "") << "failed op " << op << " changed the model: " << s.message();
      }
    }
    const Status v = validate(m);
    ASSERT_TRUE(v) << "after op " << op << " (step " << done << "): " << v.to_string();
  }
};

}  // namespace

TEST(Euler, RandomBuildAndUndo) {
  for (unsigned seed : {1u, 2u, 3u, 4u}) {
    auto inc = fixtures::incomplete();
    Model m = inc.model;
    const Model original = m;
    RandomBuilder b{m, std::mt19937(seed), {}};
    int steps = 0;
    while (b.done < 1500 && steps < 20000) {
      b.step();
      ++steps;
      if (HasFatalFailure()) return;
    }
    EXPECT_GE(b.done, 1500) << "seed " << seed;
    // Every kind of operation really happened (0 vertex, 1-2 vertex-edge,
    // 3-4 edges, 5-6 faces, 7 rings, 8 splits, 9-11 kills, 12-13 merges).
    for (int op : {0, 1, 3, 5, 7, 8, 9, 10, 11, 12}) EXPECT_GT(b.per_op[op], 5) << "seed " << seed << " op " << op;
    RecordProperty("ops_seed" + std::to_string(seed), [&] {
      std::string o;
      for (int c : b.per_op) o += std::to_string(c) + " ";
      return o;
    }());
    const auto t = count_topology(m);
    EXPECT_GT(t.faces, 2);  // the walk really built faces
    for (auto it = b.undo.rbegin(); it != b.undo.rend(); ++it) {
      const Status s = (*it)(m);
      ASSERT_TRUE(s) << "seed " << seed << " undo " << (it - b.undo.rbegin()) << ": " << s.to_string();
      const Status v = validate(m);
      ASSERT_TRUE(v) << v.to_string();
    }
    EXPECT_EQ(diff_tables(original, m), "") << "seed " << seed;
    Model c1 = original, c2 = m;
    (void)c1.compact();
    (void)c2.compact();
    EXPECT_EQ(diff_tables(c1, c2), "") << "seed " << seed;
    EXPECT_EQ(c1.num_nodes(), c2.nodes.slots.capacity());
  }
}
