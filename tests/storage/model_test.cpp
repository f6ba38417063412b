#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <atelier/storage/builder.h>
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>

using namespace atelier;

namespace {

struct Soup {
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> off{0}, idx;
  void face(std::initializer_list<std::uint32_t> f) {
    idx.insert(idx.end(), f);
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  }
  [[nodiscard]] PolygonSoupView arrays() const { return {p, off, idx}; }
};

Soup torus(int nu, int nv) {  // quad torus: chi = 0, one hole pair (genus 1)
  Soup s;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      s.p.emplace_back((2 + std::cos(v)) * std::cos(u), (2 + std::cos(v)) * std::sin(u), std::sin(v));
    }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) s.face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  return s;
}

Soup grid(int n) {  // open triangulated square: chi = 1
  Soup s;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) s.p.emplace_back(i, j, 0);
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      s.face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return s;
}

Soup cube() {
  Soup s;
  for (int i = 0; i < 8; ++i) s.p.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  s.face({0, 2, 3, 1});
  s.face({4, 5, 7, 6});
  s.face({0, 1, 5, 4});
  s.face({2, 6, 7, 3});
  s.face({0, 4, 6, 2});
  s.face({1, 3, 7, 5});
  return s;
}

}  // namespace

TEST(Builder, CountsAndEulerPoincareOnKnownShapes) {
  struct Case {
    Soup s;
    std::int64_t v, e, f, c, s_shells, h;
  };
  const int n = 6;
  std::vector<Case> cases = {
      {cube(), 8, 12, 6, 1, 1, 0},
      {grid(n), (n + 1) * (n + 1), 3 * n * n + 2 * n, 2 * n * n, 1, 0, 0},
      {torus(8, 5), 40, 80, 40, 1, 1, 2},  // V-E+F = 0 = C - H + S -> H = 2 (the torus' two cycles)
  };
  for (const auto& k : cases) {
    Model m;
    auto s = add_polygon_surface(m, "x", k.s.arrays());
    ASSERT_TRUE(s) << s.status().to_string();
    ASSERT_TRUE(validate(m)) << validate(m).to_string();
    const auto t = count_topology(m);
    EXPECT_EQ(t.nodes, k.v);
    EXPECT_EQ(t.edges, k.e);
    EXPECT_EQ(t.faces, k.f);
    EXPECT_EQ(t.components, k.c);
    EXPECT_EQ(t.shells, k.s_shells);
    EXPECT_EQ(m.complex_holes, k.h);
  }
}

TEST(Builder, EveryEdgeHasConsistentTwinsAndRingsAreSorted) {
  Model m;
  auto s = torus(12, 7);
  ASSERT_TRUE(add_polygon_surface(m, "t", s.arrays()));
  // Independent check: each face corner (a,b) appears as a halfedge a->b of that face.
  std::vector<NodeIdx> fn;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    m.face_nodes(FaceIdx{f}, fn);
    const auto b = s.off[f], e = s.off[f + 1];
    ASSERT_EQ(fn.size(), e - b);
    for (std::uint32_t k = b; k < e; ++k) EXPECT_EQ(fn[k - b].value, s.idx[k]);
    for (std::uint32_t k = b; k < e; ++k) {
      const auto a = NodeIdx{s.idx[k]}, c = NodeIdx{s.idx[k + 1 < e ? k + 1 : b]};
      const HalfedgeIdx h = m.find_halfedge(a, c);
      ASSERT_TRUE(h.valid());
      EXPECT_EQ(m.face(h).value, f);
    }
  }
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) EXPECT_EQ(m.degree(NodeIdx{v}), 4u);
}

TEST(Builder, RejectsBadInputNamingTheElement) {
  auto expect_error = [](Soup s, ErrorCode code, const std::string& fragment) {
    Model m;
    auto r = add_polygon_surface(m, "bad", s.arrays());
    ASSERT_FALSE(r) << "expected failure: " << fragment;
    EXPECT_EQ(r.status().code(), code);
    EXPECT_NE(r.status().message().find(fragment), std::string::npos) << r.status().message();
    EXPECT_EQ(m.num_nodes(), 0u);  // nothing half-built
  };
  Soup s = cube();
  s.idx[5] = 99;
  expect_error(s, ErrorCode::kInvalidArgument, "face 1 refers to node 99");
  s = cube();
  s.p[3] = Vec3d(std::nan(""), 0, 0);
  expect_error(s, ErrorCode::kDegenerate, "node 3 has a non-finite position");
  s = cube();
  s.idx[1] = s.idx[0];
  expect_error(s, ErrorCode::kDegenerate, "face 0 uses node 0 twice");
  s = cube();
  s.face({0, 1, 5});  // third face on edge (0,1)
  expect_error(s, ErrorCode::kNonManifold, "shared by 3 faces");
  s = cube();
  std::swap(s.idx[0], s.idx[1]);  // flip face 0's orientation
  expect_error(s, ErrorCode::kNonManifold, "same direction");
  Soup two;
  two.p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  two.idx = {0, 1};
  two.off = {0, 2};
  expect_error(two, ErrorCode::kDegenerate, "face 0 has 2 nodes");
}

TEST(Model, StaleHandlesAreRefused) {
  Model m;
  const Surface s = m.add_surface("s");
  const NodeIdx a = m.new_node(s.idx, {0, 0, 0});
  const Node h = m.handle(a);
  EXPECT_TRUE(m.resolve(h));
  m.delete_node(a);
  auto r = m.resolve(h);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), ErrorCode::kStaleHandle);
  EXPECT_NE(r.status().message().find("node 0"), std::string::npos);
  const NodeIdx b = m.new_node(s.idx, {1, 0, 0});
  EXPECT_EQ(b, a);                 // slot reused
  EXPECT_FALSE(m.alive(h));        // but the old handle stays stale
  EXPECT_TRUE(m.alive(m.handle(b)));
}

TEST(Model, RingsStaySortedWhateverTheLinkOrder) {
  // Star of wire edges added in random order: the ring around the centre
  // must come out identical.
  auto build = [](unsigned seed) {
    Model m;
    const Surface s = m.add_surface("s");
    std::vector<NodeIdx> leaves;
    const NodeIdx c = m.new_node(s.idx, {0, 0, 0});
    for (int i = 0; i < 12; ++i) leaves.push_back(m.new_node(s.idx, {std::cos(i), std::sin(i), 0}));
    std::vector<EdgeIdx> e;
    for (auto l : leaves) e.push_back(m.new_edge(c, l));
    // Delete and re-create a random subset in a random order: LIFO slots +
    // sorted rings must give back the same tables.
    std::mt19937 rng(seed);
    std::vector<int> order(12);
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), rng);
    order.resize(7);
    for (int i : order) m.delete_edge(e[i]);
    for (auto it = order.rbegin(); it != order.rend(); ++it) m.new_edge(c, leaves[*it]);
    m.complex_holes = count_topology(m).implied_holes();
    return m;
  };
  Model a = build(1), b = build(2);
  EXPECT_TRUE(validate(a)) << validate(a).to_string();
  EXPECT_EQ(diff_tables(a, b), "");
}

TEST(Model, CompactKeepsTheModelValidAndGeometryIntact) {
  Model m;
  auto s = grid(5);
  ASSERT_TRUE(add_polygon_surface(m, "g", s.arrays()));
  // Kill every third face and a wire edge, add an isolated node.
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); f += 3) m.delete_face(FaceIdx{f});
  const NodeIdx iso = m.new_node(SurfaceIdx{0}, {9, 9, 9});
  m.complex_holes = count_topology(m).implied_holes();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  const auto before = count_topology(m);
  std::vector<Vec3d> face_centres;
  std::vector<NodeIdx> fn;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    m.face_nodes(FaceIdx{f}, fn);
    Vec3d c = Vec3d::Zero();
    for (auto v : fn) c += m.position(v);
    face_centres.push_back(c / fn.size());
  }
  const CompactRemap r = m.compact();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  const auto after = count_topology(m);
  EXPECT_EQ(before.faces, after.faces);
  EXPECT_EQ(before.edges, after.edges);
  EXPECT_EQ(m.faces.slots.capacity(), m.faces.slots.size());
  EXPECT_EQ(m.position(r.nodes[iso.value]), Vec3d(9, 9, 9));
  std::size_t k = 0;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    m.face_nodes(FaceIdx{f}, fn);
    Vec3d c = Vec3d::Zero();
    for (auto v : fn) c += m.position(v);
    EXPECT_TRUE((c / fn.size() - face_centres[k++]).norm() < 1e-15);
  }
}

TEST(Model, DiffTablesSeesAnyChange) {
  Model a;
  ASSERT_TRUE(add_polygon_surface(a, "c", cube().arrays()));
  Model b = a;
  EXPECT_EQ(diff_tables(a, b), "");
  b.nodes.position[3].x() = std::nextafter(b.nodes.position[3].x(), 2.0);
  EXPECT_NE(diff_tables(a, b).find("node position"), std::string::npos);
  b = a;
  b.halfedges.next[0] = b.halfedges.prev[0];
  EXPECT_NE(diff_tables(a, b).find("halfedge next"), std::string::npos);
}

TEST(Validate, CatchesBrokenInvariants) {
  Model base;
  ASSERT_TRUE(add_polygon_surface(base, "c", cube().arrays()));
  {
    Model m = base;
    m.halfedges.next[0] = m.halfedges.next[m.halfedges.next[0].value];
    EXPECT_FALSE(validate(m));
  }
  {
    Model m = base;
    std::swap(m.halfedges.vnext[m.nodes.out[0].value], m.halfedges.vprev[m.nodes.out[0].value]);
    EXPECT_FALSE(validate(m));
  }
  {
    Model m = base;
    m.complex_holes = 1;
    auto s = validate(m);
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find("Euler-Poincare"), std::string::npos);
  }
  {
    Model m = base;
    m.faces.surface[2] = SurfaceIdx{7};
    EXPECT_FALSE(validate(m));
  }
  {
    Model m = base;
    m.nodes.position[1].y() = std::numeric_limits<double>::infinity();
    EXPECT_FALSE(validate(m));
  }
}
