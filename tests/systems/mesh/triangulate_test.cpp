// Face triangulation (seed 000 section 3, Fig. 5c): attributes become nodes
// and constraint edges; the result covers the face exactly, keeps its
// orientation and keeps the model valid.
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/mesh/triangulate.h>
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "tests/support/expect.h"

using namespace atelier;

namespace {

using atelier::testing::expect_valid;

Vec3d tri_normal(const Model& m, FaceIdx f) {
  std::vector<NodeIdx> c;
  m.face_nodes(f, c);
  Vec3d n = Vec3d::Zero();
  for (std::size_t k = 0; k < c.size(); ++k) n += m.position(c[k]).cross(m.position(c[(k + 1) % c.size()]));
  return 0.5 * n;  // area vector (exact for planar faces)
}

// A tilted plane so the projection to 2D is exercised.
Vec3d place(double x, double y) {
  const Mat3d R = (Eigen::AngleAxisd(0.7, Vec3d(1, 2, 3).normalized())).toRotationMatrix();
  return R * Vec3d(x, y, 0) + Vec3d(0.3, -1, 2);
}

struct Square {
  Model m;
  SurfaceIdx s;
  NodeIdx a, b, c, d;
  FaceIdx abc, acd;
};

// Square a b c d split along a-c into faces (a,b,c) and (a,c,d).
Square square() {
  Square q;
  std::vector<Vec3d> p = {place(0, 0), place(2, 0), place(2, 2), place(0, 2)};
  std::vector<std::uint32_t> off = {0, 3, 6}, idx = {0, 1, 2, 0, 2, 3};
  q.s = add_polygon_surface(q.m, "sq", {p, off, idx}).value().idx;
  q.a = NodeIdx{0}, q.b = NodeIdx{1}, q.c = NodeIdx{2}, q.d = NodeIdx{3};
  q.abc = q.m.face(q.m.find_halfedge(q.a, q.b));
  q.acd = q.m.face(q.m.find_halfedge(q.c, q.d));
  return q;
}

AttribNodeIdx edge_node(Model& m, NodeIdx from, NodeIdx to, double u) {
  const HalfedgeIdx h = m.find_halfedge(from, to);
  const AttribNodeIdx a =
      m.new_attrib_node(m.nodes.surface[from.value], AttribNodeKind::kEdge, h.value, Vec3d(u, 0, 0), Vec3d::Zero());
  m.attrib_nodes.position[a.value] = m.attrib_position_on_surface(a);
  return a;
}

AttribNodeIdx face_node(Model& m, FaceIdx f, const Vec3d& bary) {
  const AttribNodeIdx a =
      m.new_attrib_node(m.faces.surface[f.value], AttribNodeKind::kFace, f.value, bary, Vec3d::Zero());
  m.attrib_nodes.position[a.value] = m.attrib_position_on_surface(a);
  return a;
}

/// 2D point-in-polygon (even-odd) in the plane z = 0.
bool inside(const std::vector<Vec2d>& poly, const Vec2d& p) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    if ((poly[i].y() > p.y()) != (poly[j].y() > p.y()) &&
        p.x() < (poly[j].x() - poly[i].x()) * (p.y() - poly[i].y()) / (poly[j].y() - poly[i].y()) + poly[i].x())
      in = !in;
  return in;
}

}  // namespace

TEST(Triangulate, AttributesBecomeNodesAndConstraints) {
  Square q = square();
  Model& m = q.m;
  // Edge nodes on a-b, on the shared diagonal a-c (one from each side), face
  // nodes inside (a,b,c), one face node in the neighbour, an attribute edge
  // ab(0.5) -> p1 -> ac(0.6), and mesh edges over a->b and c->a.
  const auto e_ab = edge_node(m, q.a, q.b, 0.5);
  const auto e_ac1 = edge_node(m, q.a, q.c, 0.3);
  const auto e_ac2 = edge_node(m, q.c, q.a, 0.4);  // = 0.6 from a
  const auto p1 = face_node(m, q.abc, Vec3d(0.25, 0.5, 0.25));
  const auto p2 = face_node(m, q.abc, Vec3d(0.5, 0.4, 0.1));
  const auto p3 = face_node(m, q.abc, Vec3d(0.2, 0.2, 0.6));
  const auto nb = face_node(m, q.acd, Vec3d(0.2, 0.5, 0.3));
  const std::vector<AttribNodeIdx> chain = {e_ab, p1, e_ac2};
  (void)m.new_attrib_edge(q.s, 3, chain);
  const MeshEdgeIdx me1 = m.new_mesh_edge(q.s, std::vector<HalfedgeIdx>{m.find_halfedge(q.a, q.b)});
  const MeshEdgeIdx me2 = m.new_mesh_edge(q.s, std::vector<HalfedgeIdx>{m.find_halfedge(q.c, q.a)});
  expect_valid(m);
  const Model old = m;
  const Vec3d n0 = tri_normal(m, q.abc);
  const std::size_t deg_nb = m.face_degree(q.acd);

  auto r = triangulate_face(m, m.handle(q.abc));
  ASSERT_TRUE(r) << r.status().to_string();
  expect_valid(m);
  // B = 3 corners + 3 edge points, I = 3 face points: B - 2 + 2I triangles.
  EXPECT_EQ(r->faces.size(), 6u - 2 + 2 * 3);
  EXPECT_EQ(r->new_nodes.size(), 6u);
  EXPECT_EQ(m.complex_holes, old.complex_holes);
  double area = 0;
  for (FaceIdx f : r->faces) {
    ASSERT_EQ(m.face_degree(f), 3u);
    const Vec3d n = tri_normal(m, f);
    EXPECT_GT(n.dot(n0) / (n.norm() * n0.norm()), 1 - 1e-9) << "triangle " << f.value << " is flipped or tilted";
    area += n.norm();
  }
  EXPECT_NEAR(area, n0.norm(), 1e-12);
  // Converted attribute nodes sit on their nodes, at their old positions.
  for (AttribNodeIdx a : {e_ab, e_ac1, e_ac2, p1, p2, p3}) {
    ASSERT_EQ(m.attrib_nodes.kind[a.value], AttribNodeKind::kVertex);
    EXPECT_LT((m.attrib_position_on_surface(a) - old.attrib_position_on_surface(a)).norm(), 1e-12);
  }
  // Every constraint segment is an edge of the result.
  for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
    const NodeIdx x{m.attrib_nodes.element[chain[k].value]}, y{m.attrib_nodes.element[chain[k + 1].value]};
    EXPECT_TRUE(m.find_halfedge(x, y).valid()) << "constraint " << k << " is not an edge";
  }
  // The neighbour gained the two diagonal points and keeps its face node.
  ASSERT_EQ(r->grown_faces.size(), 1u);
  EXPECT_EQ(r->grown_faces[0], q.acd);
  EXPECT_EQ(m.face_degree(q.acd), deg_nb + 2);
  EXPECT_LT((m.attrib_position_on_surface(nb) - old.attrib_position_on_surface(nb)).norm(), 1e-12);
  EXPECT_LT((tri_normal(m, q.acd) - tri_normal(old, q.acd)).norm(), 1e-12);
  // Mesh edges follow the splits, direction kept.
  EXPECT_EQ(m.mesh_edges.halfedges.size(me1.value), 2u);
  EXPECT_EQ(m.mesh_edges.halfedges.size(me2.value), 3u);
  EXPECT_EQ(m.tail(m.mesh_edges.halfedges.row(me2.value).front()), q.c);
  EXPECT_EQ(m.head(m.mesh_edges.halfedges.row(me2.value).back()), q.a);
}

TEST(Triangulate, GrownNeighboursOnRequest) {
  Square q = square();
  Model& m = q.m;
  (void)edge_node(m, q.a, q.c, 0.5);
  (void)face_node(m, q.acd, Vec3d(0.3, 0.3, 0.4));
  const double total = tri_normal(m, q.abc).norm() + tri_normal(m, q.acd).norm();
  const Vec3d n0 = tri_normal(m, q.abc);
  TriangulateOptions opt;
  opt.triangulate_grown = true;
  auto r = triangulate_face(m, m.handle(q.abc), opt);
  ASSERT_TRUE(r) << r.status().to_string();
  expect_valid(m);
  EXPECT_TRUE(r->grown_faces.empty());
  // Neighbour (a, m, c, d) plus its face node: B = 4, I = 1 -> 4 triangles; ours: 2.
  EXPECT_EQ(m.num_faces(), 6u);
  double area = 0;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    EXPECT_EQ(m.face_degree(FaceIdx{f}), 3u);
    const Vec3d n = tri_normal(m, FaceIdx{f});
    EXPECT_GT(n.dot(n0), 0);
    area += n.norm();
  }
  EXPECT_NEAR(area, total, 1e-12);
}

TEST(Triangulate, RandomPointsCoverTheFaceExactly) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> U(0.02, 0.98);
  for (int trial = 0; trial < 20; ++trial) {
    Square q = square();
    Model& m = q.m;
    const int nf = 1 + trial % 7, ne = trial % 4;
    std::vector<AttribNodeIdx> pts;
    for (int i = 0; i < ne; ++i) pts.push_back(edge_node(m, i % 2 ? q.b : q.c, i % 2 ? q.c : q.b, U(rng)));
    for (int i = 0; i < nf; ++i) {
      Vec3d b(U(rng), U(rng), U(rng));
      pts.push_back(face_node(m, q.abc, b / b.sum()));
    }
    const Vec3d n0 = tri_normal(m, q.abc);
    auto r = triangulate_face(m, m.handle(q.abc));
    ASSERT_TRUE(r) << r.status().to_string();
    expect_valid(m);
    EXPECT_EQ(r->faces.size(), static_cast<std::size_t>(3 + ne - 2 + 2 * nf));
    double area = 0;
    for (FaceIdx f : r->faces) {
      const Vec3d n = tri_normal(m, f);
      EXPECT_GT(n.dot(n0), 0);
      area += n.norm();
    }
    EXPECT_NEAR(area, n0.norm(), 1e-12);
    for (AttribNodeIdx a : pts) EXPECT_EQ(m.attrib_nodes.kind[a.value], AttribNodeKind::kVertex);
  }
}

TEST(Triangulate, CrossingConstraintsRefusedModelUntouched) {
  Square q = square();
  Model& m = q.m;
  const auto a1 = edge_node(m, q.a, q.b, 0.5), b1 = edge_node(m, q.a, q.c, 0.75);
  const auto a2 = edge_node(m, q.a, q.b, 0.75), b2 = edge_node(m, q.a, q.c, 0.5);
  (void)m.new_attrib_edge(q.s, 1, std::vector<AttribNodeIdx>{a1, b1});
  (void)m.new_attrib_edge(q.s, 2, std::vector<AttribNodeIdx>{a2, b2});
  expect_valid(m);
  const Model old = m;
  auto r = triangulate_face(m, m.handle(q.abc));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), ErrorCode::kDegenerate);
  EXPECT_EQ(diff_tables(m, old), "");
}

TEST(Triangulate, JointPartnersSplitTheSameWay) {
  // Two triangles of two surfaces joined along (0,0,0)-(1,0,0); the members
  // run in opposite directions to exercise the direction flags.
  for (int flip = 0; flip < 2; ++flip) {
    Model m;
    std::vector<Vec3d> pa = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, pb = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
    std::vector<std::uint32_t> off = {0, 3}, ia = {0, 1, 2}, ib = {1, 0, 2};
    const SurfaceIdx sa = add_polygon_surface(m, "A", {pa, off, ia}).value().idx;
    const SurfaceIdx sb = add_polygon_surface(m, "B", {pb, off, ib}).value().idx;
    const MeshEdgeIdx ma = m.new_mesh_edge(sa, std::vector<HalfedgeIdx>{m.find_halfedge(NodeIdx{0}, NodeIdx{1})});
    const HalfedgeIdx hb = flip ? m.find_halfedge(NodeIdx{4}, NodeIdx{3}) : m.find_halfedge(NodeIdx{3}, NodeIdx{4});
    const MeshEdgeIdx mb = m.new_mesh_edge(sb, std::vector<HalfedgeIdx>{hb});
    (void)m.new_joint(std::vector<JointMember>{{ma, true}, {mb, flip == 0}});
    (void)edge_node(m, NodeIdx{0}, NodeIdx{1}, 0.25);
    (void)edge_node(m, NodeIdx{1}, NodeIdx{0}, 0.4);  // 0.6 from node 0
    const auto fb = face_node(m, FaceIdx{1}, Vec3d(0.3, 0.3, 0.4));
    expect_valid(m);
    const Model old = m;
    auto r = triangulate_face(m, m.handle(FaceIdx{0}));
    ASSERT_TRUE(r) << r.status().to_string();
    expect_valid(m);  // joint: equal lengths, coincident nodes
    EXPECT_EQ(m.mesh_edges.halfedges.size(ma.value), 3u);
    EXPECT_EQ(m.mesh_edges.halfedges.size(mb.value), 3u);
    EXPECT_EQ(r->faces.size(), 3u);
    EXPECT_EQ(r->new_nodes.size(), 4u);  // two in A, their partners in B
    ASSERT_EQ(r->grown_faces.size(), 1u);
    EXPECT_EQ(m.face_degree(FaceIdx{1}), 5u);
    EXPECT_LT((m.attrib_position_on_surface(fb) - old.attrib_position_on_surface(fb)).norm(), 1e-12);
    for (NodeIdx v : r->new_nodes) EXPECT_DOUBLE_EQ(m.position(v).y() + m.position(v).z(), 0.0);
  }
}

TEST(Triangulate, JointPartnerWithItsOwnEdgeNodesRefused) {
  Model m;
  std::vector<Vec3d> pa = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, pb = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  std::vector<std::uint32_t> off = {0, 3}, ia = {0, 1, 2}, ib = {1, 0, 2};
  const SurfaceIdx sa = add_polygon_surface(m, "A", {pa, off, ia}).value().idx;
  const SurfaceIdx sb = add_polygon_surface(m, "B", {pb, off, ib}).value().idx;
  const MeshEdgeIdx ma = m.new_mesh_edge(sa, std::vector<HalfedgeIdx>{m.find_halfedge(NodeIdx{0}, NodeIdx{1})});
  const MeshEdgeIdx mb = m.new_mesh_edge(sb, std::vector<HalfedgeIdx>{m.find_halfedge(NodeIdx{3}, NodeIdx{4})});
  (void)m.new_joint(std::vector<JointMember>{{ma, true}, {mb, true}});
  (void)edge_node(m, NodeIdx{0}, NodeIdx{1}, 0.5);
  (void)edge_node(m, NodeIdx{3}, NodeIdx{4}, 0.7);
  expect_valid(m);
  const Model old = m;
  auto r = triangulate_face(m, m.handle(FaceIdx{0}));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), ErrorCode::kJointRefused);
  EXPECT_EQ(diff_tables(m, old), "");
  // Without attributes on it the joint edge is kept and the face stays one triangle.
  Model plain = old;
  plain.delete_attrib_node(AttribNodeIdx{0});
  plain.delete_attrib_node(AttribNodeIdx{1});
  auto r2 = triangulate_face(plain, plain.handle(FaceIdx{0}));
  ASSERT_TRUE(r2) << r2.status().to_string();
  expect_valid(plain);
  EXPECT_EQ(r2->faces.size(), 1u);
}

TEST(Triangulate, PolygonsOfTheWholeModel) {
  Model m;
  // Concave L-shaped hexagon (area 3), a planar pentagon with a face node and
  // a non-planar quad, next to a triangle that must stay as it is.
  const std::vector<Vec2d> L = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  std::vector<Vec3d> p;
  for (const Vec2d& v : L) p.emplace_back(v.x(), v.y(), 0);
  p.insert(p.end(), {{5, 0, 0}, {7, 0, 0}, {8, 1.5, 0}, {6, 3, 0}, {4, 1.5, 0}, {6, -2, 0}});
  p.insert(p.end(), {{10, 0, 0}, {11, 0, 0.2}, {11, 1, 0}, {10, 1, 0.2}});
  std::vector<std::uint32_t> off = {0, 6, 11, 14, 18};
  std::vector<std::uint32_t> idx = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 6, 11, 7, 12, 13, 14, 15};
  (void)add_polygon_surface(m, "polys", {p, off, idx}).value();
  const FaceIdx pent{1};
  const auto fn = face_node(m, pent, Vec3d(0.2, 0.3, 0.5));
  m.attrib_nodes.corner[fn.value] = 1;
  m.attrib_nodes.position[fn.value] = m.attrib_position_on_surface(fn);
  expect_valid(m);
  const Model old = m;
  const Vec3d quad_n = tri_normal(m, FaceIdx{3});
  auto r = triangulate_polygons(m);
  ASSERT_TRUE(r) << r.status().to_string();
  EXPECT_EQ(*r, 3u);
  expect_valid(m);
  EXPECT_EQ(m.num_nodes(), old.num_nodes());
  EXPECT_EQ(m.num_faces(), 4u + 3u + 1u + 2u);
  EXPECT_EQ(m.complex_holes, old.complex_holes);
  double area_L = 0;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    ASSERT_EQ(m.face_degree(FaceIdx{f}), 3u);
    std::vector<NodeIdx> c;
    m.face_nodes(FaceIdx{f}, c);
    const Vec3d n = tri_normal(m, FaceIdx{f});
    if (c[0].value < 6) {  // the L: inside it, counter-clockwise, area adds up
      const Vec3d g = (m.position(c[0]) + m.position(c[1]) + m.position(c[2])) / 3;
      EXPECT_TRUE(inside(L, Vec2d(g.x(), g.y()))) << "triangle " << f << " lies outside the L";
      EXPECT_GT(n.z(), 0);
      area_L += n.norm();
    } else if (c[0].value >= 12) {
      EXPECT_GT(n.dot(quad_n), 0) << "non-planar quad triangle flipped";
    } else {
      EXPECT_GT(n.z(), 0);
    }
  }
  EXPECT_NEAR(area_L, 3.0, 1e-12);
  EXPECT_LT((m.attrib_position_on_surface(fn) - old.attrib_position_on_surface(fn)).norm(), 1e-12);
  EXPECT_EQ(m.attrib_nodes.kind[fn.value], AttribNodeKind::kFace);
}
