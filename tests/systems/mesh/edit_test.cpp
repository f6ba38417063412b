// High-level edit operators on the shared fixtures: validate() after every
// call, Euler-Poincare terms preserved, split/collapse round trips compared
// as geometric face sets, joint members kept equal and coincident.
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/mesh/edit.h>
#include <atelier/systems/mesh/euler.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "support/fixtures.h"
#include "tests/support/expect.h"

using namespace atelier;

namespace {

using atelier::testing::ok;

using Key = std::array<double, 3>;
Key key(const Vec3d& p) {
  return {p.x(), p.y(), p.z()};
}

/// Faces as sets of corner positions, per surface: independent of slots.
std::multiset<std::pair<std::uint32_t, std::vector<Key>>> face_set(const Model& m) {
  std::multiset<std::pair<std::uint32_t, std::vector<Key>>> out;
  std::vector<NodeIdx> c;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    m.face_nodes(FaceIdx{f}, c);
    std::vector<Key> k;
    for (NodeIdx v : c) k.push_back(key(m.position(v)));
    // Rotate to the smallest corner: same cycle, canonical start.
    std::rotate(k.begin(), std::min_element(k.begin(), k.end()), k.end());
    out.emplace(m.faces.surface[f].value, std::move(k));
  }
  return out;
}

/// Euler-Poincare terms other than V, E, F must not move; V - E + F neither.
void expect_euler_preserved(const TopologyCounts& a, const Model& m, std::int64_t h_before, const char* what) {
  const TopologyCounts b = count_topology(m);
  EXPECT_EQ(b.euler(), a.euler()) << what;
  EXPECT_EQ(b.components, a.components) << what;
  EXPECT_EQ(b.shells, a.shells) << what;
  EXPECT_EQ(b.rings, a.rings) << what;
  EXPECT_EQ(m.complex_holes, h_before) << what;
  const Status v = validate(m);
  EXPECT_TRUE(v) << what << ": " << v.to_string();
}

Vec3d midpoint(const Model& m, EdgeIdx e) {
  return 0.5 * (m.position(m.tail(halfedge_of(e, 0))) + m.position(m.head(halfedge_of(e, 0))));
}

std::vector<EdgeIdx> live_edges(const Model& m) {
  std::vector<EdgeIdx> v;
  for (std::uint32_t i = 0; i < m.edges.slots.capacity(); ++i)
    if (m.alive(EdgeIdx{i})) v.push_back(EdgeIdx{i});
  return v;
}

double area(const Model& m, FaceIdx f) {
  std::vector<NodeIdx> c;
  m.face_nodes(f, c);
  Vec3d n = Vec3d::Zero();
  for (std::size_t i = 1; i + 1 < c.size(); ++i)
    n += (m.position(c[i]) - m.position(c[0])).cross(m.position(c[i + 1]) - m.position(c[0]));
  return 0.5 * n.norm();
}

std::vector<std::pair<std::string, Model>> all_fixtures() {
  std::vector<std::pair<std::string, Model>> v;
  v.emplace_back("triangle", fixtures::single_triangle());
  v.emplace_back("tetrahedron", fixtures::tetrahedron());
  v.emplace_back("octahedron", fixtures::octahedron());
  v.emplace_back("grid", fixtures::grid_patch(4, 3).model);
  v.emplace_back("quad_strip", fixtures::quad_strip(3));  // polygons: split adds a corner, collapse removes it
  v.emplace_back("fan3", fixtures::fan(3, 4).model);
  v.emplace_back("fan5", fixtures::fan(5, 3).model);
  v.emplace_back("inner_joint", fixtures::inner_edge_joint(4).model);
  return v;
}

}  // namespace

TEST(Edit, SplitTriangleEdge) {
  Model m = fixtures::single_triangle();
  const auto t = count_topology(m);
  const auto r = ok(edge_split(m, m.handle(EdgeIdx{0}), midpoint(m, EdgeIdx{0})));
  ASSERT_EQ(r.nodes.size(), 1u);
  expect_euler_preserved(t, m, 0, "split");
  EXPECT_EQ(m.num_faces(), 2u);
  EXPECT_EQ(m.num_nodes(), 4u);
  EXPECT_EQ(m.num_edges(), 5u);
  for (std::uint32_t f = 0; f < 2; ++f) {
    EXPECT_EQ(m.face_degree(FaceIdx{f}), 3u);
    EXPECT_NEAR(area(m, FaceIdx{f}), 0.25, 1e-15);  // the median halves the triangle
  }
}

TEST(Edit, SplitThenCollapseRoundTripOnAllFixtures) {
  for (auto& [name, base] : all_fixtures()) {
    for (EdgeIdx e0 : live_edges(base)) {
      Model m = base;
      const auto before = face_set(m);
      const auto t = count_topology(m);
      const HalfedgeIdx h = halfedge_of(e0, 0);
      const Vec3d b = m.position(m.head(h));
      const auto s = edge_split(m, m.handle(e0), midpoint(m, e0));
      ASSERT_TRUE(s) << name << " edge " << e0.value << ": " << s.status().to_string();
      expect_euler_preserved(t, m, base.complex_holes, name.c_str());
      // The half m -> old head collapses back into the head's position.
      const NodeIdx mid = s->nodes[0].idx;
      HalfedgeIdx back;
      m.for_each_outgoing(mid, [&](HalfedgeIdx x) {
        if (m.position(m.head(x)) == b && !back.valid()) back = x;
      });
      ASSERT_TRUE(back.valid());
      const auto c = edge_collapse(m, m.handle(edge_of(back)), b);
      ASSERT_TRUE(c) << name << " edge " << e0.value << ": " << c.status().to_string();
      expect_euler_preserved(t, m, base.complex_holes, name.c_str());
      EXPECT_EQ(face_set(m), before) << name << " edge " << e0.value;
      EXPECT_EQ(m.num_nodes(), base.num_nodes());
      EXPECT_EQ(m.num_edges(), base.num_edges());
      if (HasFailure()) return;
    }
  }
}

TEST(Edit, JointSplitKeepsMembersEqualAndCoincident) {
  for (int variant = 0; variant < 3; ++variant) {
    fixtures::JointFixture f = variant == 2 ? fixtures::inner_edge_joint(4) : fixtures::fan(variant == 0 ? 3 : 5, 4);
    Model& m = f.model;
    const auto t = count_topology(m);
    const std::size_t K = f.members.size();
    // Split through each member in turn (positive and negative flags alike).
    for (std::size_t q = 0; q < K; ++q) {
      const auto chain = m.mesh_edges.halfedges.row(f.members[q].idx.value);
      const std::size_t len = chain.size();
      const EdgeIdx e = edge_of(chain[len / 2]);
      const Vec3d p = midpoint(m, e);
      const auto r = ok(edge_split(m, m.handle(e), p));
      ASSERT_EQ(r.nodes.size(), K);
      for (const Node& v : r.nodes) EXPECT_EQ(m.position(v.idx), p);
      for (const MeshEdge& me : f.members) EXPECT_EQ(m.mesh_edges.halfedges.size(me.idx.value), len + 1);
      expect_euler_preserved(t, m, f.model.complex_holes, "joint split");
      // Faces stay triangles in every surface.
      for (std::uint32_t x = 0; x < m.faces.slots.capacity(); ++x)
        if (m.alive(FaceIdx{x})) {
          EXPECT_EQ(m.face_degree(FaceIdx{x}), 3u);
        }
    }
    // Collapse a joint edge: every member loses one edge, nodes stay coincident.
    const auto chain = m.mesh_edges.halfedges.row(f.members[1].idx.value);
    const std::size_t len = chain.size();
    const EdgeIdx e = edge_of(chain[1]);
    const Vec3d p = midpoint(m, e);
    const auto c = edge_collapse(m, m.handle(e), p);
    ASSERT_TRUE(c) << c.status().to_string();
    EXPECT_EQ(c->kept.size(), K);
    for (const Node& v : c->kept) EXPECT_EQ(m.position(v.idx), p);
    for (const MeshEdge& me : f.members) EXPECT_EQ(m.mesh_edges.halfedges.size(me.idx.value), len - 1);
    expect_euler_preserved(t, m, f.model.complex_holes, "joint collapse");
  }
}

TEST(Edit, CollapseNextToJointKeepsJointNode) {
  auto f = fixtures::fan(3, 4);
  Model& m = f.model;
  const auto t = count_topology(m);
  // An edge from joint node 2 of member 0 into its surface.
  const NodeIdx j = m.tail(m.mesh_edges.halfedges.row(f.members[0].idx.value)[2]);
  const Vec3d pj = m.position(j);
  HalfedgeIdx in;
  m.for_each_outgoing(j, [&](HalfedgeIdx x) {
    if (!m.edges.mesh_edge[edge_of(x).value].valid() && !in.valid()) in = x;
  });
  ASSERT_TRUE(in.valid());
  // Whichever end the halfedge 2e starts at, the joint node is kept in place.
  const auto c = ok(edge_collapse(m, m.handle(edge_of(in)), Vec3d(9, 9, 9)));
  EXPECT_EQ(c.kept[0].idx, j);
  EXPECT_EQ(m.position(j), pj);
  expect_euler_preserved(t, m, f.model.complex_holes, "collapse next to a joint");
}

TEST(Edit, SwapRefusedOnJointsAndMeshEdges) {
  auto f = fixtures::fan(3, 3);
  Model& m = f.model;
  const Model before = m;
  for (const MeshEdge& me : f.members)
    for (HalfedgeIdx h : m.mesh_edges.halfedges.row(me.idx.value))
      EXPECT_EQ(edge_swap(m, m.handle(edge_of(h))).status().code(), ErrorCode::kJointRefused);
  auto inner = fixtures::inner_edge_joint(3);
  for (HalfedgeIdx h : inner.model.mesh_edges.halfedges.row(inner.members[1].idx.value))  // interior sheet edges
    EXPECT_EQ(edge_swap(inner.model, inner.model.handle(edge_of(h))).status().code(), ErrorCode::kJointRefused);
  auto g = fixtures::grid_patch(2, 2);
  for (HalfedgeIdx h : g.model.mesh_edges.halfedges.row(g.sides[0].idx.value))
    EXPECT_EQ(edge_swap(g.model, g.model.handle(edge_of(h))).status().code(), ErrorCode::kTopology);
  EXPECT_EQ(diff_tables(before, m), "");
}

TEST(Edit, SwapTwiceRestoresFaces) {
  auto g = fixtures::grid_patch(3, 3);
  Model& m = g.model;
  const auto before = face_set(m);
  const auto t = count_topology(m);
  const EdgeIdx e = edge_of(m.find_halfedge(g.node(1, 1), g.node(2, 2)));
  const Edge n = ok(edge_swap(m, m.handle(e)));
  expect_euler_preserved(t, m, m.complex_holes, "swap");
  // The new diagonal joins (2,1) and (1,2).
  const NodeIdx a = m.tail(halfedge_of(n.idx, 0)), b = m.head(halfedge_of(n.idx, 0));
  EXPECT_EQ(std::set<NodeIdx>({a, b}), std::set<NodeIdx>({g.node(2, 1), g.node(1, 2)}));
  EXPECT_NE(face_set(m), before);
  ASSERT_TRUE(edge_swap(m, n));
  EXPECT_EQ(face_set(m), before);
  // Swapping onto an existing edge is refused (in a tetrahedron the opposite
  // corners are always joined); in an octahedron the poles are not.
  auto tet = fixtures::tetrahedron();
  EXPECT_EQ(edge_swap(tet, tet.handle(EdgeIdx{0})).status().code(), ErrorCode::kTopology);
  auto oct = fixtures::octahedron();
  const auto to = count_topology(oct);
  ASSERT_TRUE(edge_swap(oct, oct.handle(EdgeIdx{0})));
  expect_euler_preserved(to, oct, 0, "octahedron swap");
}

TEST(Edit, CollapseRefusals) {
  // Tetrahedron: the opposite nodes would drop to valence 2.
  Model tet = fixtures::tetrahedron();
  EXPECT_EQ(edge_collapse(tet, tet.handle(EdgeIdx{0}), Vec3d::Zero()).status().code(), ErrorCode::kDegenerate);
  // Octahedron without face (0,2,4): pole 4 neighbours both ends of edge
  // (0,2) but is no longer opposite it: the link condition fails.
  Model oct = fixtures::octahedron();
  ASSERT_TRUE(kill_face_make_Chole(oct, oct.handle(FaceIdx{0})));
  const EdgeIdx e02 = edge_of(oct.find_halfedge(NodeIdx{0}, NodeIdx{2}));
  const auto r = edge_collapse(oct, oct.handle(e02), Vec3d::Zero());
  EXPECT_EQ(r.status().code(), ErrorCode::kTopology);
  EXPECT_NE(r.status().message().find("link condition"), std::string::npos) << r.status().message();
  // A lone triangle would leave dangling edges.
  Model tri = fixtures::single_triangle();
  EXPECT_EQ(edge_collapse(tri, tri.handle(EdgeIdx{0}), Vec3d::Zero()).status().code(), ErrorCode::kDegenerate);
  // Interior edge between two boundary nodes would pinch.
  auto g = fixtures::grid_patch(1, 2);
  const EdgeIdx mid = edge_of(g.model.find_halfedge(g.node(0, 1), g.node(1, 1)));
  EXPECT_EQ(edge_collapse(g.model, g.model.handle(mid), Vec3d::Zero()).status().code(), ErrorCode::kTopology);
  // Wire edge.
  auto inc = fixtures::incomplete();
  EXPECT_EQ(edge_collapse(inc.model, inc.wires[1], Vec3d::Zero()).status().code(), ErrorCode::kTopology);
  // A face holding a ring node is not replaced.
  EXPECT_EQ(edge_split(inc.model, inc.model.handle(EdgeIdx{0}), midpoint(inc.model, EdgeIdx{0})).status().code(),
            ErrorCode::kTopology);
  // A wire edge splits into two wire edges.
  const auto t = count_topology(inc.model);
  ASSERT_TRUE(edge_split(inc.model, inc.wires[1], midpoint(inc.model, inc.wires[1].idx)));
  expect_euler_preserved(t, inc.model, inc.model.complex_holes, "wire split");
}

TEST(Edit, OctahedronCollapseKeepsClosedShell) {
  Model m = fixtures::octahedron();
  const auto t = count_topology(m);
  const auto c = ok(edge_collapse(m, m.handle(EdgeIdx{0}), midpoint(m, EdgeIdx{0})));
  expect_euler_preserved(t, m, 0, "octahedron collapse");
  EXPECT_EQ(m.num_nodes(), 5u);
  EXPECT_EQ(m.num_faces(), 6u);
  EXPECT_EQ(count_topology(m).shells, 1);
  EXPECT_EQ(m.degree(c.kept[0].idx), 4u);
}

TEST(Edit, FaceSplit1to4) {
  Model m = fixtures::single_triangle();
  const auto t = count_topology(m);
  const auto r = ok(face_split_1to4(m, m.handle(FaceIdx{0})));
  expect_euler_preserved(t, m, 0, "1to4");
  EXPECT_EQ(m.num_faces(), 4u);
  EXPECT_EQ(m.num_nodes(), 6u);
  EXPECT_EQ(m.num_edges(), 9u);
  for (const Face& f : r.faces) EXPECT_NEAR(area(m, f.idx), 0.125, 1e-15);
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(m.position(r.midpoints[i].idx), 0.5 * (Vec3d(i == 1, i == 2, 0) + Vec3d(i == 0, i == 1, 0)));
  // Centre face is made of the three midpoints.
  std::vector<NodeIdx> c;
  m.face_nodes(r.faces[3].idx, c);
  EXPECT_EQ(std::set<NodeIdx>(c.begin(), c.end()),
            std::set<NodeIdx>({r.midpoints[0].idx, r.midpoints[1].idx, r.midpoints[2].idx}));

  // Interior grid triangle: its three neighbours gain a corner (Table 3).
  auto g = fixtures::grid_patch(3, 3);
  const FaceIdx f = g.model.face(g.model.find_halfedge(g.node(1, 1), g.node(2, 1)));
  std::vector<FaceIdx> nb;
  g.model.for_each_face_halfedge(f, [&](HalfedgeIdx h) { nb.push_back(g.model.face(twin(h))); });
  const auto tg = count_topology(g.model);
  ASSERT_TRUE(face_split_1to4(g.model, g.model.handle(f)));
  expect_euler_preserved(tg, g.model, g.model.complex_holes, "grid 1to4");
  for (FaceIdx x : nb) EXPECT_EQ(g.model.face_degree(x), 4u);
}

TEST(Edit, FaceSplit1to4AcrossJoint) {
  for (int variant = 0; variant < 2; ++variant) {
    fixtures::JointFixture f = variant == 0 ? fixtures::fan(3, 3) : fixtures::inner_edge_joint(3);
    Model& m = f.model;
    const std::size_t len = m.mesh_edges.halfedges.size(f.members[0].idx.value);
    // The face of member 0's middle joint edge.
    HalfedgeIdx h = m.mesh_edges.halfedges.row(f.members[0].idx.value)[1];
    if (!m.face(h).valid()) h = twin(h);
    const FaceIdx face = m.face(h);
    const auto t = count_topology(m);
    const std::size_t faces_before = m.num_faces();
    const auto r = face_split_1to4(m, m.handle(face));
    ASSERT_TRUE(r) << r.status().to_string();
    expect_euler_preserved(t, m, f.model.complex_holes, "joint 1to4");
    for (const MeshEdge& me : f.members) EXPECT_EQ(m.mesh_edges.halfedges.size(me.idx.value), len + 1);
    // Other members' faces were re-triangulated: all their faces are triangles.
    for (std::size_t q = 1; q < f.surfaces.size(); ++q)
      for (std::uint32_t x = 0; x < m.faces.slots.capacity(); ++x)
        if (m.alive(FaceIdx{x}) && m.faces.surface[x] == f.surfaces[q].idx) {
          EXPECT_EQ(m.face_degree(FaceIdx{x}), 3u) << "surface " << q;
        }
    // Face count: +3 for the split face, +1 per re-triangulated joint face
    // of the other members, + the hanging-node neighbours stay single faces.
    EXPECT_GE(m.num_faces(), faces_before + 3 + (f.surfaces.size() - 1));
  }
}

TEST(Edit, AttributesFollowSwapAndSplit) {
  auto g = fixtures::grid_patch(2, 2);
  Model& m = g.model;
  const HalfedgeIdx h = m.find_halfedge(g.node(0, 0), g.node(1, 1));
  const SurfaceIdx s = g.surface.idx;
  const AttribNodeIdx fa =
      m.new_attrib_node(s, AttribNodeKind::kFace, m.face(h).value, Vec3d(0.6, 0.3, 0.1), Vec3d::Zero());
  const AttribNodeIdx ea = m.new_attrib_node(s, AttribNodeKind::kEdge, h.value, Vec3d(0.3, 0, 0), Vec3d::Zero());
  const Vec3d pf = m.attrib_position_on_surface(fa), pe = m.attrib_position_on_surface(ea);
  ASSERT_TRUE(edge_swap(m, m.handle(edge_of(h))));
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_LT((m.attrib_position_on_surface(fa) - pf).norm(), 1e-12);
  EXPECT_EQ(m.attrib_nodes.kind[ea.value], AttribNodeKind::kFace);  // its edge is gone: now in a face
  EXPECT_LT((m.attrib_position_on_surface(ea) - pe).norm(), 1e-12);
  const EdgeIdx e2 = edge_of(m.find_halfedge(g.node(1, 0), g.node(1, 1)));
  ASSERT_TRUE(edge_split(m, m.handle(e2), midpoint(m, e2)));
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_LT((m.attrib_position_on_surface(fa) - pf).norm(), 1e-12);
  EXPECT_LT((m.attrib_position_on_surface(ea) - pe).norm(), 1e-12);
  // Collapse every interior edge at the centre node that the checks allow:
  // attribute nodes of removed faces/edges/nodes stay attached to live elements.
  int collapsed = 0;
  for (int round = 0; round < 4; ++round) {
    std::vector<HalfedgeIdx> out;
    if (!m.alive(g.node(1, 1))) break;
    m.outgoing(g.node(1, 1), out);
    for (HalfedgeIdx x : out) {
      if (!m.alive(x)) continue;
      if (edge_collapse(m, m.handle(edge_of(x)), m.position(g.node(1, 1)))) {
        ++collapsed;
        ASSERT_TRUE(validate(m)) << validate(m).to_string();
        break;
      }
    }
  }
  EXPECT_GE(collapsed, 1);
  EXPECT_TRUE(m.alive(fa) && m.alive(ea));
}

TEST(Edit, RandomSplitCollapseSwapOnGrid) {
  for (unsigned seed : {11u, 12u, 13u}) {
    auto g = fixtures::grid_patch(8, 8);
    Model& m = g.model;
    const auto t = count_topology(m);
    std::mt19937 rng(seed);
    std::map<int, int> okc, refused;
    for (int step = 0; step < 600; ++step) {
      const auto edges = live_edges(m);
      const EdgeIdx e = edges[std::uniform_int_distribution<std::size_t>(0, edges.size() - 1)(rng)];
      const int op = std::uniform_int_distribution<int>(0, 2)(rng);
      const double u = std::uniform_real_distribution<double>(0.2, 0.8)(rng);
      const HalfedgeIdx h = halfedge_of(e, 0);
      const Vec3d p = (1 - u) * m.position(m.tail(h)) + u * m.position(m.head(h));
      Status s;
      if (op == 0) s = edge_split(m, m.handle(e), p).status();
      if (op == 1) s = edge_collapse(m, m.handle(e), p).status();
      if (op == 2) s = edge_swap(m, m.handle(e)).status();
      (s ? okc : refused)[op]++;
      if (!s) {
        ASSERT_NE(s.code(), ErrorCode::kInternal) << s.message();
      }
      const Status v = validate(m);
      ASSERT_TRUE(v) << "seed " << seed << " step " << step << " op " << op << ": " << v.to_string();
    }
    expect_euler_preserved(t, m, g.model.complex_holes, "random grid");
    for (int op = 0; op < 3; ++op) EXPECT_GT(okc[op], 50) << "seed " << seed << " op " << op;
    // Still a triangulated disk whose boundary is exactly the mesh loop.
    std::size_t boundary = 0, loop = 0;
    for (EdgeIdx e : live_edges(m)) boundary += m.is_boundary(e);
    for (const MeshEdge& me : g.sides) loop += m.mesh_edges.halfedges.size(me.idx.value);
    EXPECT_EQ(boundary, loop);
    for (std::uint32_t x = 0; x < m.faces.slots.capacity(); ++x)
      if (m.alive(FaceIdx{x})) {
        EXPECT_EQ(m.face_degree(FaceIdx{x}), 3u);
      }
  }
}

TEST(Edit, RandomEditsOnJointFixtures) {
  for (int variant = 0; variant < 3; ++variant) {
    fixtures::JointFixture f = variant == 2 ? fixtures::inner_edge_joint(6) : fixtures::fan(variant == 0 ? 3 : 5, 6);
    Model& m = f.model;
    const auto t = count_topology(m);
    std::mt19937 rng(100 + variant);
    std::map<int, int> okc;
    int joint_ops = 0;
    for (int step = 0; step < 400; ++step) {
      const auto edges = live_edges(m);
      const EdgeIdx e = edges[std::uniform_int_distribution<std::size_t>(0, edges.size() - 1)(rng)];
      const int op = std::uniform_int_distribution<int>(0, 2)(rng);
      const bool on_joint = m.edges.mesh_edge[e.value].valid();
      const double u = std::uniform_real_distribution<double>(0.2, 0.8)(rng);
      const HalfedgeIdx h = halfedge_of(e, 0);
      const Vec3d p = (1 - u) * m.position(m.tail(h)) + u * m.position(m.head(h));
      Status s;
      if (op == 0) s = edge_split(m, m.handle(e), p).status();
      if (op == 1) s = edge_collapse(m, m.handle(e), p).status();
      if (op == 2) {
        s = edge_swap(m, m.handle(e)).status();
        if (on_joint) {
          EXPECT_EQ(s.code(), ErrorCode::kJointRefused);
        }
      }
      if (s) {
        okc[op]++;
        joint_ops += on_joint;
      } else {
        ASSERT_NE(s.code(), ErrorCode::kInternal) << s.message();
      }
      const Status v = validate(m);
      ASSERT_TRUE(v) << "variant " << variant << " step " << step << " op " << op << ": " << v.to_string();
    }
    expect_euler_preserved(t, m, f.model.complex_holes, "random joint edits");
    EXPECT_GT(joint_ops, 5) << "variant " << variant;
    for (int op = 0; op < 3; ++op) EXPECT_GT(okc[op], 20) << "variant " << variant << " op " << op;
    const std::size_t len = m.mesh_edges.halfedges.size(f.members[0].idx.value);
    for (const MeshEdge& me : f.members) EXPECT_EQ(m.mesh_edges.halfedges.size(me.idx.value), len);
  }
}
