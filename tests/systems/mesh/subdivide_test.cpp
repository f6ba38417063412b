// Uniform 1-to-4 split: analytic counts, exact midpoints, orientation,
// joints, attribute remapping, determinism and parity with the naive split.
#include <atelier/storage/builder.h>
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/mesh/subdivide.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <vector>

#include "tests/support/expect.h"

using namespace atelier;

namespace {

struct Arrays {
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> off{0}, idx;
  void face(std::initializer_list<std::uint32_t> f) {
    idx.insert(idx.end(), f);
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  }
  SurfaceIdx add(Model& m, const char* name) const {
    auto s = add_polygon_surface(m, name, {p, off, idx});
    EXPECT_TRUE(s) << s.status().to_string();
    return s->idx;
  }
};

// nx x ny grid of cells, mapped through g(i, j); quads or two triangles per cell.
template <class G>
Arrays grid(int nx, int ny, bool quads, G&& g) {
  Arrays a;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) a.p.push_back(g(i, j));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (quads) {
        a.face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        a.face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        a.face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      }
    }
  return a;
}

Arrays octahedron() {
  Arrays a;
  a.p = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  a.face({0, 2, 4});
  a.face({2, 1, 4});
  a.face({1, 3, 4});
  a.face({3, 0, 4});
  a.face({2, 0, 5});
  a.face({1, 2, 5});
  a.face({3, 1, 5});
  a.face({0, 3, 5});
  return a;
}

Vec3d newell(const Model& m, FaceIdx f) {
  Vec3d n = Vec3d::Zero();
  m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
    const Vec3d& a = m.position(m.tail(h));
    const Vec3d& b = m.position(m.head(h));
    n += a.cross(b);
  });
  return 0.5 * n;  // area vector for planar faces
}

/// Canonical face set: corner positions in cycle order, rotated to start at
/// the smallest; sorted. Equal sets mean the same faces with the same
/// orientation, whatever their indices.
std::vector<std::vector<std::array<double, 3>>> face_positions(const Model& m) {
  std::vector<std::vector<std::array<double, 3>>> out;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    std::vector<std::array<double, 3>> c;
    m.for_each_face_halfedge(FaceIdx{f}, [&](HalfedgeIdx h) {
      const Vec3d& p = m.position(m.tail(h));
      c.push_back({p.x(), p.y(), p.z()});
    });
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    out.push_back(std::move(c));
  }
  std::sort(out.begin(), out.end());
  return out;
}

NodeIdx node_at(const Model& m, SurfaceIdx s, const Vec3d& p) {
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}) && m.nodes.surface[v] == s && (m.position(NodeIdx{v}) - p).norm() < 1e-12)
      return NodeIdx{v};
  ADD_FAILURE() << "no node at " << p.transpose();
  return {};
}

std::vector<HalfedgeIdx> path(const Model& m, SurfaceIdx s, std::initializer_list<Vec3d> pts) {
  std::vector<HalfedgeIdx> out;
  const Vec3d* p = pts.begin();
  for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
    const HalfedgeIdx h = m.find_halfedge(node_at(m, s, p[k]), node_at(m, s, p[k + 1]));
    EXPECT_TRUE(h.valid());
    out.push_back(h);
  }
  return out;
}

/// Two surfaces meeting along y = z = 0 (x from 0 to 1), joined by a joint;
/// surface A also has a mesh loop around its boundary, wire edges and
/// attribute nodes/edges (edge nodes, face nodes, vertex nodes).
Model joint_model() {
  Model m;
  const SurfaceIdx a = grid(2, 1, false, [](int i, int j) { return Vec3d(0.5 * i, 1.0 * j, 0); }).add(m, "A");
  const SurfaceIdx b = grid(2, 1, false, [](int i, int j) { return Vec3d(0.5 * i, 0, 0.7 * j); }).add(m, "B");
  const auto ca = path(m, a, {{0, 0, 0}, {0.5, 0, 0}, {1, 0, 0}});
  const auto cb = path(m, b, {{1, 0, 0}, {0.5, 0, 0}, {0, 0, 0}});
  const MeshEdgeIdx ma = m.new_mesh_edge(a, ca);
  const MeshEdgeIdx mb = m.new_mesh_edge(b, cb);
  m.new_joint(std::vector<JointMember>{{ma, true}, {mb, false}});
  const auto rest = path(m, a, {{1, 0, 0}, {1, 1, 0}, {0.5, 1, 0}, {0, 1, 0}, {0, 0, 0}});
  const MeshEdgeIdx mr = m.new_mesh_edge(a, rest);
  m.new_mesh_loop(a, std::vector<MeshEdgeIdx>{ma, mr});
  // A wire polyline in surface A, away from the faces.
  const NodeIdx w0 = m.new_node(a, {2, 0, 0}), w1 = m.new_node(a, {3, 0.5, 0}), w2 = m.new_node(a, {3, 1, 0.25});
  (void)m.new_edge(w0, w1);
  (void)m.new_edge(w2, w1);
  return m;
}

void add_attributes(Model& m, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<AttribNodeIdx> chain;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e})) continue;
    const HalfedgeIdx h = halfedge_of(EdgeIdx{e}, e % 2);
    const double u = e % 5 == 0 ? 0.5 : U(rng);  // include the exact midpoint
    const Vec3d prm(u, 0, 0);
    const auto an = m.new_attrib_node(m.surface_of(EdgeIdx{e}), AttribNodeKind::kEdge, h.value, prm, Vec3d::Zero());
    m.attrib_nodes.position[an.value] = m.attrib_position_on_surface(an);
    if (e % 3 == 0) chain.push_back(an);
  }
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    const std::size_t deg = m.face_degree(FaceIdx{f});
    for (int k = 0; k < 3; ++k) {
      Vec3d b(U(rng), U(rng), U(rng));
      if (k == 1) b = Vec3d(0.5, 0.25, 0.25);  // on the boundary of two children
      b /= b.sum();
      const auto corner = static_cast<std::uint8_t>(k % (deg - 2));  // fan triangle of a polygon
      const auto an = m.new_attrib_node(m.faces.surface[f], AttribNodeKind::kFace, f, b, Vec3d::Zero(), corner);
      m.attrib_nodes.position[an.value] = m.attrib_position_on_surface(an);
      if (m.faces.surface[f] == m.attrib_nodes.surface[chain.front().value] && k == 0) chain.push_back(an);
    }
  }
  // Keep the attribute edge in one surface.
  std::vector<AttribNodeIdx> same;
  for (auto an : chain)
    if (m.attrib_nodes.surface[an.value] == m.attrib_nodes.surface[chain.front().value]) same.push_back(an);
  (void)m.new_attrib_edge(m.attrib_nodes.surface[same.front().value], 7, same);
  (void)m.new_attrib_node(SurfaceIdx{0}, AttribNodeKind::kVertex, 0, Vec3d::Zero(), m.position(NodeIdx{0}));
}

using atelier::testing::expect_valid;

}  // namespace

TEST(Subdivide, TriangleCountsAndTopology) {
  Model m;
  octahedron().add(m, "oct");
  expect_valid(m);
  const auto before = count_topology(m);
  const std::size_t V = m.num_nodes(), E = m.num_edges(), F = m.num_faces();
  auto r = subdivide_uniform(m, ExecContext::sequential());
  ASSERT_TRUE(r) << r.status().to_string();
  expect_valid(m);
  EXPECT_EQ(m.num_nodes(), V + E);
  EXPECT_EQ(m.num_edges(), 2 * E + 3 * F);
  EXPECT_EQ(m.num_faces(), 4 * F);
  const auto after = count_topology(m);
  EXPECT_EQ(after.euler(), before.euler());
  EXPECT_EQ(after.components, before.components);
  EXPECT_EQ(after.shells, 1);
  EXPECT_FALSE(r->compacted);
  // Split twice more: still closed, counts follow the same law.
  for (int it = 0; it < 2; ++it) {
    const std::size_t v = m.num_nodes(), e = m.num_edges(), f = m.num_faces();
    ASSERT_TRUE(subdivide_uniform(m));
    expect_valid(m);
    EXPECT_EQ(m.num_nodes(), v + e);
    EXPECT_EQ(m.num_edges(), 2 * e + 3 * f);
    EXPECT_EQ(m.num_faces(), 4 * f);
  }
  // New nodes are regular (valence 6) on a closed triangle mesh (seed 000 Fig. 15a).
  for (std::uint32_t v = 6; v < m.nodes.slots.capacity(); ++v) EXPECT_EQ(m.degree(NodeIdx{v}), 6u) << v;
}

TEST(Subdivide, QuadsAndPolygonsCounts) {
  Model m;
  grid(3, 2, true, [](int i, int j) { return Vec3d(i, j, 0.1 * i * j); }).add(m, "quads");
  Arrays mixed;
  mixed.p = {{0, 0, 5}, {2, 0, 5}, {3, 1.5, 5}, {1, 3, 5}, {-1, 1.5, 5}, {1, -2, 5}};
  mixed.face({0, 1, 2, 3, 4});  // pentagon
  mixed.face({0, 5, 1});        // triangle below it
  mixed.add(m, "mixed");
  expect_valid(m);
  const std::size_t V = m.num_nodes(), E = m.num_edges(), F = m.num_faces();
  std::size_t sides_ngon = 0, tris = 0, ngons = 0;
  for (std::uint32_t f = 0; f < F; ++f) {
    const std::size_t n = m.face_degree(FaceIdx{f});
    (n == 3 ? tris : ngons) += 1;
    if (n > 3) sides_ngon += n;
  }
  const Model old = m;
  auto r = subdivide_uniform(m);
  ASSERT_TRUE(r) << r.status().to_string();
  expect_valid(m);
  EXPECT_EQ(m.num_nodes(), V + E + ngons);
  EXPECT_EQ(m.num_edges(), 2 * E + 3 * tris + sides_ngon);
  EXPECT_EQ(m.num_faces(), 4 * tris + sides_ngon);
  // Centre nodes sit at the centroid of their face; n-gons become n quads.
  for (std::uint32_t f = 0; f < F; ++f) {
    const std::size_t n = old.face_degree(FaceIdx{f});
    const NodeIdx c = r->face_centre[f];
    EXPECT_EQ(c.valid(), n != 3);
    const std::size_t kids = 1 + r->face_child_begin[f + 1].value - r->face_child_begin[f].value;
    EXPECT_EQ(kids, n == 3 ? 4u : n);
    if (!c.valid()) continue;
    Vec3d s = Vec3d::Zero();
    old.for_each_face_halfedge(FaceIdx{f}, [&](HalfedgeIdx h) { s += old.position(old.tail(h)); });
    EXPECT_LT((m.position(c) - s / double(n)).norm(), 1e-14);
    EXPECT_EQ(m.face_degree(FaceIdx{f}), 4u);
    EXPECT_EQ(m.degree(c), n);
  }
}

TEST(Subdivide, MidpointsExactAndOldNodesKept) {
  Model m;
  grid(4, 3, false, [](int i, int j) { return Vec3d(i * 0.3, j * 0.7, std::sin(i + j)); }).add(m, "g");
  const Model old = m;
  auto r = subdivide_uniform(m);
  ASSERT_TRUE(r);
  expect_valid(m);
  for (std::uint32_t v = 0; v < old.nodes.slots.capacity(); ++v) {
    EXPECT_TRUE(r->is_old(NodeIdx{v}));
    EXPECT_EQ(m.position(NodeIdx{v}), old.position(NodeIdx{v}));
  }
  for (std::uint32_t e = 0; e < old.edges.slots.capacity(); ++e) {
    const HalfedgeIdx h{2 * e};
    const NodeIdx a = old.tail(h), b = old.head(h), mid = r->edge_midpoint[e];
    EXPECT_FALSE(r->is_old(mid));
    EXPECT_EQ(m.position(mid), 0.5 * (old.position(a) + old.position(b)));
    // Both halves, direction kept, for both sides of the old edge.
    for (HalfedgeIdx x : {h, twin(h)}) {
      EXPECT_EQ(m.tail(r->first_half(x)), old.tail(x));
      EXPECT_EQ(m.head(r->first_half(x)), mid);
      EXPECT_EQ(m.tail(r->second_half(x)), mid);
      EXPECT_EQ(m.head(r->second_half(x)), old.head(x));
    }
  }
}

TEST(Subdivide, OrientationAndAreaPreserved) {
  Model m;
  octahedron().add(m, "oct");
  grid(3, 3, true, [](int i, int j) { return Vec3d(i, j, 4); }).add(m, "flat quads");
  const Model old = m;
  auto r = subdivide_uniform(m);
  ASSERT_TRUE(r);
  expect_valid(m);
  for (std::uint32_t f = 0; f < old.faces.slots.capacity(); ++f) {
    const Vec3d np = newell(old, FaceIdx{f});
    Vec3d sum = newell(m, FaceIdx{f});
    std::vector<FaceIdx> kids{FaceIdx{f}};
    for (auto c = r->face_child_begin[f].value; c < r->face_child_begin[f + 1].value; ++c) kids.push_back(FaceIdx{c});
    for (std::size_t k = 1; k < kids.size(); ++k) sum += newell(m, kids[k]);
    for (FaceIdx c : kids) {
      const Vec3d nc = newell(m, c);
      EXPECT_GT(nc.dot(np) / (nc.norm() * np.norm()), 1 - 1e-12) << "child " << c.value << " of face " << f;
    }
    EXPECT_LT((sum - np).norm(), 1e-12 * np.norm());
  }
}

TEST(Subdivide, JointsLoopsAndWiresCarriedOver) {
  Model m = joint_model();
  expect_valid(m);
  const Model old = m;
  auto r = subdivide_uniform(m);
  ASSERT_TRUE(r) << r.status().to_string();
  expect_valid(m);  // joint members have equal lengths and coincident nodes
  for (std::uint32_t me = 0; me < old.mesh_edges.slots.capacity(); ++me) {
    const auto a = old.mesh_edges.halfedges.row(me), b = m.mesh_edges.halfedges.row(me);
    ASSERT_EQ(b.size(), 2 * a.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
      EXPECT_EQ(b[2 * k], r->first_half(a[k]));
      EXPECT_EQ(b[2 * k + 1], r->second_half(a[k]));
      EXPECT_EQ(m.tail(b[2 * k]), old.tail(a[k]));
      EXPECT_EQ(m.head(b[2 * k + 1]), old.head(a[k]));
    }
  }
  // Joint partners: the same midpoint positions bit for bit (no crack).
  const auto j = m.joints.members.row(0);
  ASSERT_EQ(j.size(), 2u);
  const auto ca = m.mesh_edges.halfedges.row(j[0].mesh_edge.value);
  const auto cb = m.mesh_edges.halfedges.row(j[1].mesh_edge.value);
  for (std::size_t t = 0; t < ca.size(); ++t)
    EXPECT_EQ(m.position(m.tail(ca[t])), m.position(m.head(cb[cb.size() - 1 - t])));
  EXPECT_EQ(m.mesh_loops.mesh_edges.row(0).size(), 2u);
  EXPECT_EQ(m.complex_holes, old.complex_holes);
  // Wire edges were split: 2 wire edges -> 4, each midpoint of degree 2.
  std::size_t wires = 0;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) wires += m.is_wire(EdgeIdx{e});
  EXPECT_EQ(wires, 4u);
}

TEST(Subdivide, AttributesRemappedExactly) {
  Model m = joint_model();
  add_attributes(m, 11);
  expect_valid(m);
  const Model old = m;
  auto r = subdivide_uniform(m);
  ASSERT_TRUE(r) << r.status().to_string();
  expect_valid(m);
  std::size_t edge_nodes = 0, face_nodes = 0;
  for (std::uint32_t a = 0; a < old.attrib_nodes.slots.capacity(); ++a) {
    const Vec3d p0 = old.attrib_position_on_surface(AttribNodeIdx{a});
    const Vec3d p1 = m.attrib_position_on_surface(AttribNodeIdx{a});
    EXPECT_LT((p0 - p1).norm(), 1e-12) << "attribute node " << a;
    EXPECT_EQ(m.attrib_nodes.position[a], old.attrib_nodes.position[a]);
    const auto kind = m.attrib_nodes.kind[a];
    edge_nodes += kind == AttribNodeKind::kEdge;
    face_nodes += kind == AttribNodeKind::kFace;
    if (kind == AttribNodeKind::kEdge) {
      // The new halfedge lies on the old one's line and keeps its direction.
      const HalfedgeIdx h{m.attrib_nodes.element[a]}, h0{old.attrib_nodes.element[a]};
      const Vec3d d0 = old.position(old.head(h0)) - old.position(old.tail(h0));
      const Vec3d d1 = m.position(m.head(h)) - m.position(m.tail(h));
      EXPECT_GT(d0.dot(d1), 0);
    }
  }
  EXPECT_GT(edge_nodes, 10u);
  EXPECT_GT(face_nodes, 10u);
  // Attribute edges unchanged, in order.
  for (std::uint32_t e = 0; e < old.attrib_edges.slots.capacity(); ++e) {
    const auto a = old.attrib_edges.nodes.row(e), b = m.attrib_edges.nodes.row(e);
    EXPECT_TRUE(std::equal(a.begin(), a.end(), b.begin(), b.end()));
  }
}

TEST(Subdivide, SplitTriangleBarycentricIsExactOnDyadics) {
  // Brute force: the point rebuilt from the child coordinates equals the
  // original; dyadic coordinates make every step exact.
  const Vec3d v[3] = {{0, 0, 0}, {4, 0, 0}, {1, 3, 0}};
  const Vec3d mid[3] = {0.5 * (v[0] + v[1]), 0.5 * (v[1] + v[2]), 0.5 * (v[2] + v[0])};
  const std::array<std::array<Vec3d, 3>, 4> child = {
      {{v[0], mid[0], mid[2]}, {v[1], mid[1], mid[0]}, {v[2], mid[2], mid[1]}, {mid[0], mid[1], mid[2]}}};
  for (int i = 0; i <= 16; ++i)
    for (int j = 0; i + j <= 16; ++j) {
      const Vec3d b(i / 16.0, j / 16.0, (16 - i - j) / 16.0);
      const auto cb = split_triangle_barycentric(b);
      ASSERT_LT(cb.child, 4u);
      EXPECT_GE(cb.param.minCoeff(), 0.0);
      EXPECT_EQ(cb.param.sum(), 1.0);
      const Vec3d p = b.x() * v[0] + b.y() * v[1] + b.z() * v[2];
      const auto& t = child[cb.child];
      const Vec3d q = cb.param.x() * t[0] + cb.param.y() * t[1] + cb.param.z() * t[2];
      EXPECT_LT((p - q).norm(), 1e-15) << i << "," << j;
    }
}

TEST(Subdivide, DeterministicAcrossThreadCounts) {
  Model base;
  grid(110, 100, false, [](int i, int j) {
    return Vec3d(i, j, std::cos(0.1 * i) * std::sin(0.07 * j));
  }).add(base, "big");
  grid(20, 20, true, [](int i, int j) { return Vec3d(i, j, 10); }).add(base, "quads");
  add_attributes(base, 5);
  Model a = base, b = base;
  ExecContext one = ExecContext::sequential();
  ExecContext two;
  two.threads = 2;
  two.sequential_threshold = 64;
  two.grain = 97;
  ASSERT_TRUE(subdivide_uniform(a, one));
  ASSERT_TRUE(subdivide_uniform(b, two));
  expect_valid(b);
  EXPECT_EQ(diff_tables(a, b), "");
}

TEST(Subdivide, ParityWithNaive) {
  for (int variant = 0; variant < 2; ++variant) {
    Model base = joint_model();
    grid(5, 4, true, [](int i, int j) { return Vec3d(i, j, -3 + 0.2 * j); }).add(base, "quads");
    Arrays mixed;
    mixed.p = {{0, 0, 9}, {2, 0, 9}, {3, 1.5, 9}, {1, 3, 9}, {-1, 1.5, 9}, {1, -2, 9}};
    mixed.face({0, 1, 2, 3, 4});
    mixed.face({0, 5, 1});
    mixed.add(base, "mixed");
    if (variant == 1) {
      // Tombstones: both versions compact first.
      base.delete_face(FaceIdx{2});
      base.complex_holes += 1;  // a face removed, its edges kept: V - E + F drops by 1
      ASSERT_TRUE(validate(base)) << validate(base).to_string();
    }
    add_attributes(base, 3);
    Model fast = base, naive = base;
    auto rf = subdivide_uniform(fast);
    auto rn = subdivide_uniform_naive(naive);
    ASSERT_TRUE(rf) << rf.status().to_string();
    ASSERT_TRUE(rn) << rn.status().to_string();
    expect_valid(fast);
    expect_valid(naive);
    EXPECT_EQ(rf->compacted, variant == 1);
    EXPECT_EQ(face_positions(fast), face_positions(naive));
    EXPECT_EQ(diff_tables(fast, naive), "");
    EXPECT_EQ(rf->edge_midpoint, rn->edge_midpoint);
    EXPECT_EQ(rf->face_child_begin, rn->face_child_begin);
  }
}

TEST(Subdivide, FaceNodesInPolygonsKeepTheirPositions) {
  Model m;
  grid(3, 2, true, [](int i, int j) { return Vec3d(0.5 * i, j + 0.1 * i, 0.3 * i - 0.2 * j); }).add(m, "planar quads");
  Arrays mixed;
  mixed.p = {{0, 0, 5}, {2, 0, 5}, {3, 1.5, 5}, {1, 3, 5}, {-1, 1.5, 5}, {1, -2, 5}};
  mixed.face({0, 1, 2, 3, 4});
  mixed.face({0, 5, 1});
  mixed.add(m, "mixed");
  add_attributes(m, 9);
  expect_valid(m);
  const Model old = m;
  auto r = subdivide_uniform(m);
  ASSERT_TRUE(r) << r.status().to_string();
  expect_valid(m);
  std::size_t in_polygons = 0;
  for (std::uint32_t a = 0; a < old.attrib_nodes.slots.capacity(); ++a) {
    if (old.attrib_nodes.kind[a] != AttribNodeKind::kFace) continue;
    in_polygons += old.face_degree(FaceIdx{old.attrib_nodes.element[a]}) > 3;
    EXPECT_LT(
        (m.attrib_position_on_surface(AttribNodeIdx{a}) - old.attrib_position_on_surface(AttribNodeIdx{a})).norm(),
        1e-12)
        << "attribute node " << a;
    // It lies in a child of its old face.
    const std::uint32_t f = old.attrib_nodes.element[a], g = m.attrib_nodes.element[a];
    EXPECT_TRUE(g == f || (g >= r->face_child_begin[f].value && g < r->face_child_begin[f + 1].value));
  }
  EXPECT_GE(in_polygons, 15u);
}

TEST(Subdivide, CancelledOnEntry) {
  ExecContext c;
  c.cancel.cancel();
  Model t;
  octahedron().add(t, "o");
  const Model old = t;
  EXPECT_EQ(subdivide_uniform(t, c).status().code(), ErrorCode::kCancelled);
  EXPECT_EQ(diff_tables(t, old), "");
}

TEST(Subdivide, RingNodesStayInTheirFace) {
  // Two ring nodes joined by a wire edge inside face 0 (a stand-alone
  // polyline on a face: R = 1, which leaves V - E + F - R unchanged).
  for (int naive = 0; naive < 2; ++naive) {
    Model m;
    grid(2, 2, false, [](int i, int j) { return Vec3d(i, j, 0); }).add(m, "g");
    const NodeIdx r0 = m.new_node(SurfaceIdx{0}, {0.6, 0.2, 0}), r1 = m.new_node(SurfaceIdx{0}, {0.8, 0.3, 0});
    m.nodes.in_face[r0.value] = m.nodes.in_face[r1.value] = FaceIdx{0};
    (void)m.new_edge(r0, r1);
    expect_valid(m);
    const auto before = count_topology(m);
    auto r = naive ? subdivide_uniform_naive(m) : subdivide_uniform(m);
    ASSERT_TRUE(r) << r.status().to_string();
    expect_valid(m);
    const auto after = count_topology(m);
    EXPECT_EQ(after.rings, before.rings);
    EXPECT_EQ(after.components, before.components);
    const NodeIdx mid = r->edge_midpoint[r->old_edges - 1];  // the wire edge is the last old edge
    EXPECT_EQ(m.nodes.in_face[mid.value], FaceIdx{0});
    EXPECT_EQ(m.position(mid), Vec3d(0.7, 0.25, 0));
  }
}
