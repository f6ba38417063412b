#include "support/fixtures.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <atelier/storage/builder.h>
#include <atelier/systems/mesh/euler.h>

namespace atelier::fixtures {

namespace {

Surface build(Model& m, const std::string& name, const std::vector<Vec3d>& p,
              const std::vector<std::vector<std::uint32_t>>& faces) {
  std::vector<std::uint32_t> off{0}, idx;
  for (const auto& f : faces) {
    idx.insert(idx.end(), f.begin(), f.end());
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  }
  auto s = add_polygon_surface(m, name, {p, off, idx}, ExecContext::sequential());
  if (!s) throw Error(s.status());
  return *s;
}

HalfedgeIdx must_find(const Model& m, NodeIdx a, NodeIdx b) {
  const HalfedgeIdx h = m.find_halfedge(a, b);
  if (!h.valid()) throw std::logic_error("fixture: missing halfedge");
  return h;
}

template <class T>
T must(Expected<T> e) {
  if (!e) throw Error(e.status());
  return std::move(e).value();
}

struct Strip {
  Surface surface;
  std::vector<HalfedgeIdx> chain;  // along row 0, face side, in chain order
  bool positive = true;            // chain runs along +x
};

/// Strip of `rows` x L cells: node (i, r) at base[i] + r * d; row 0 is the
/// joint polyline. flip reverses the winding.
Strip add_strip(Model& m, const std::string& name, int segments, const Vec3d& d, int rows, bool flip) {
  const int L = segments;
  std::vector<Vec3d> p;
  for (int r = 0; r <= rows; ++r)
    for (int i = 0; i <= L; ++i) p.push_back(Vec3d(i, 0, 0) + r * d);
  auto id = [&](int i, int r) { return static_cast<std::uint32_t>(r * (L + 1) + i); };
  std::vector<std::vector<std::uint32_t>> faces;
  for (int r = 0; r < rows; ++r)
    for (int i = 0; i < L; ++i) {
      if (!flip) {
        faces.push_back({id(i, r), id(i + 1, r), id(i + 1, r + 1)});
        faces.push_back({id(i, r), id(i + 1, r + 1), id(i, r + 1)});
      } else {
        faces.push_back({id(i, r), id(i + 1, r + 1), id(i + 1, r)});
        faces.push_back({id(i, r), id(i, r + 1), id(i + 1, r + 1)});
      }
    }
  const std::uint32_t first = static_cast<std::uint32_t>(m.nodes.slots.capacity());
  Strip s;
  s.surface = build(m, name, p, faces);
  s.positive = !flip;
  for (int k = 0; k < L; ++k) {
    const int i = flip ? L - 1 - k : k;
    const NodeIdx a{first + id(flip ? i + 1 : i, 0)}, b{first + id(flip ? i : i + 1, 0)};
    s.chain.push_back(must_find(m, a, b));
  }
  return s;
}

}  // namespace

Model single_triangle() {
  Model m;
  build(m, "triangle", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  return m;
}

Model quad_strip(int n) {
  Model m;
  std::vector<Vec3d> p;
  for (int i = 0; i <= n; ++i) p.emplace_back(i, 0, 0);
  for (int i = 0; i <= n; ++i) p.emplace_back(i, 1, 0);
  const auto t = static_cast<std::uint32_t>(n + 1);
  std::vector<std::vector<std::uint32_t>> f;
  for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(n); ++i) f.push_back({i, i + 1, t + i + 1, t + i});
  build(m, "quad_strip", p, f);
  return m;
}

Model tetrahedron() {
  Model m;
  build(m, "tetrahedron", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}});
  return m;
}

Model octahedron() {
  Model m;
  build(m, "octahedron", {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}},
        {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}});
  return m;
}

Grid grid_patch(int n, int mm) {
  Grid g;
  g.n = n;
  g.m = mm;
  std::vector<Vec3d> p;
  for (int j = 0; j <= mm; ++j)
    for (int i = 0; i <= n; ++i) p.emplace_back(i, j, 0);
  std::vector<std::vector<std::uint32_t>> f;
  for (int j = 0; j < mm; ++j)
    for (int i = 0; i < n; ++i) {
      const auto v = [&](int a, int b) { return static_cast<std::uint32_t>(b * (n + 1) + a); };
      f.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      f.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  g.surface = build(g.model, "grid", p, f);
  Model& m = g.model;
  std::vector<HalfedgeIdx> bottom, right, top, left;
  for (int i = 0; i < n; ++i) bottom.push_back(must_find(m, g.node(i, 0), g.node(i + 1, 0)));
  for (int j = 0; j < mm; ++j) right.push_back(must_find(m, g.node(n, j), g.node(n, j + 1)));
  for (int i = n; i > 0; --i) top.push_back(must_find(m, g.node(i, mm), g.node(i - 1, mm)));
  for (int j = mm; j > 0; --j) left.push_back(must_find(m, g.node(0, j), g.node(0, j - 1)));
  std::vector<MeshEdgeIdx> me;
  for (const auto* c : {&bottom, &right, &top, &left}) {
    me.push_back(m.new_mesh_edge(g.surface.idx, *c));
    g.sides.push_back(m.handle(me.back()));
  }
  g.loop = m.handle(m.new_mesh_loop(g.surface.idx, me));
  return g;
}

JointFixture fan(int k, int segments) {
  JointFixture f;
  f.segments = segments;
  std::vector<Strip> strips;
  for (int s = 0; s < k; ++s) {
    const double th = 2.0 * std::numbers::pi * s / k;
    strips.push_back(add_strip(f.model, "fan" + std::to_string(s), segments, Vec3d(0, std::cos(th), std::sin(th)), 2,
                               s % 2 == 1));
  }
  // Clockwise about +x (right-hand rule): decreasing angle, starting at 0.
  std::vector<JointMember> members;
  for (int q = 0; q < k; ++q) {
    const int s = q == 0 ? 0 : k - q;
    const MeshEdgeIdx me = f.model.new_mesh_edge(strips[s].surface.idx, strips[s].chain);
    members.push_back({me, strips[s].positive});
    f.surfaces.push_back(strips[s].surface);
    f.members.push_back(f.model.handle(me));
    f.positive.push_back(strips[s].positive);
  }
  f.joint = f.model.handle(f.model.new_joint(members));
  return f;
}

JointFixture inner_edge_joint(int segments) {
  JointFixture f;
  f.segments = segments;
  Model& m = f.model;
  const int L = segments;
  // Sheet: rows y = -1, 0, 1; the y = 0 row is interior.
  std::vector<Vec3d> p;
  for (int r = 0; r <= 2; ++r)
    for (int i = 0; i <= L; ++i) p.emplace_back(i, r - 1, 0);
  auto id = [&](int i, int r) { return static_cast<std::uint32_t>(r * (L + 1) + i); };
  std::vector<std::vector<std::uint32_t>> faces;
  for (int r = 0; r < 2; ++r)
    for (int i = 0; i < L; ++i) {
      faces.push_back({id(i, r), id(i + 1, r), id(i + 1, r + 1)});
      faces.push_back({id(i, r), id(i + 1, r + 1), id(i, r + 1)});
    }
  const std::uint32_t first = static_cast<std::uint32_t>(m.nodes.slots.capacity());
  const Surface sheet = build(m, "sheet", p, faces);
  std::vector<HalfedgeIdx> inner;
  for (int i = 0; i < L; ++i) inner.push_back(must_find(m, NodeIdx{first + id(i, 1)}, NodeIdx{first + id(i + 1, 1)}));
  const Strip up = add_strip(m, "fin_up", segments, Vec3d(0, 0, 1), 1, false);
  const Strip down = add_strip(m, "fin_down", segments, Vec3d(0, 0, -1), 1, true);
  const MeshEdgeIdx m_sheet = m.new_mesh_edge(sheet.idx, inner);
  const MeshEdgeIdx m_up = m.new_mesh_edge(up.surface.idx, up.chain);
  const MeshEdgeIdx m_down = m.new_mesh_edge(down.surface.idx, down.chain);
  const std::vector<JointMember> members{{m_down, down.positive}, {m_sheet, true}, {m_up, up.positive}};
  f.joint = m.handle(m.new_joint(members));
  f.surfaces = {down.surface, sheet, up.surface};
  f.members = {m.handle(m_down), m.handle(m_sheet), m.handle(m_up)};
  f.positive = {down.positive, true, up.positive};
  return f;
}

Incomplete incomplete() {
  Incomplete r;
  Model& m = r.model;
  r.surface = build(m, "incomplete", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {3, 0, 0}, {4, 0, 0}, {4, 1, 0}, {3, 1, 0}},
                    {{0, 1, 2}, {3, 4, 5, 6}});
  r.triangle = m.handle(FaceIdx{0});
  r.quad = m.handle(FaceIdx{1});
  r.ring = must(make_vertex_ring(m, r.triangle, Vec3d(0.25, 0.25, 0)));
  // A dangling wire edge on the triangle and a free polyline of two edges.
  r.wires.push_back(must(make_vertex_edge(m, m.handle(NodeIdx{1}), Vec3d(2, -1, 0))).edge);
  const Node p0 = must(make_vertex_complex(m, r.surface, Vec3d(0, 3, 0)));
  const VertexEdge p1 = must(make_vertex_edge(m, p0, Vec3d(1, 3, 0)));
  r.wires.push_back(p1.edge);
  r.wires.push_back(must(make_vertex_edge(m, p1.node, Vec3d(2, 3.5, 0))).edge);
  r.isolated.push_back(must(make_vertex_complex(m, r.surface, Vec3d(5, 5, 0))));
  r.isolated.push_back(must(make_vertex_complex(m, r.surface, Vec3d(-2, 4, 1))));
  return r;
}

}  // namespace atelier::fixtures
