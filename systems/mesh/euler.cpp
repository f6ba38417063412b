#include <atelier/systems/mesh/euler.h>

#include <algorithm>
#include <limits>
#include <sstream>

#include <atelier/engine/status_format.h>

namespace atelier {

namespace {

NodeRecord node_record(const Model& m, NodeIdx v) {
  NodeRecord r;
  r.surface = m.nodes.surface[v.value];
  r.position = m.nodes.position[v.value];
  r.position_backup = m.nodes.position_backup[v.value];
  r.uv = m.nodes.uv[v.value];
  r.in_face = m.nodes.in_face[v.value];
  return r;
}

NodeIdx new_node_from(Model& m, const NodeRecord& r) {
  const NodeIdx v = m.new_node(r.surface, r.position);
  m.nodes.position_backup[v.value] = r.position_backup;
  m.nodes.uv[v.value] = r.uv;
  m.nodes.in_face[v.value] = r.in_face;
  return v;
}

bool is_ring(const Model& m, NodeIdx v) {
  return m.nodes.in_face[v.value].valid();
}

// Attribute references: O(number of attribute nodes), which is small next to
// the mesh (profiles and feature points).
bool node_has_attrib(const Model& m, NodeIdx v) {
  const auto& an = m.attrib_nodes;
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
    if (an.slots.alive(AttribNodeIdx{i}) && an.kind[i] == AttribNodeKind::kVertex && an.element[i] == v.value)
      return true;
  return false;
}
bool edge_has_attrib(const Model& m, EdgeIdx e) {
  const auto& an = m.attrib_nodes;
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
    if (an.slots.alive(AttribNodeIdx{i}) && an.kind[i] == AttribNodeKind::kEdge &&
        edge_of(HalfedgeIdx{an.element[i]}) == e)
      return true;
  return false;
}
bool face_has_attrib(const Model& m, FaceIdx f) {
  const auto& an = m.attrib_nodes;
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
    if (an.slots.alive(AttribNodeIdx{i}) && an.kind[i] == AttribNodeKind::kFace && an.element[i] == f.value)
      return true;
  return false;
}
bool face_has_ring(const Model& m, FaceIdx f) {
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.nodes.in_face[v] == f && m.nodes.slots.alive(NodeIdx{v})) return true;
  return false;
}

/// Common checks of the edge makers: live, distinct nodes of one surface not
/// yet joined (parallel edges are invalid).
Status check_new_edge(const Model& m, Node a, Node b) {
  if (auto r = m.resolve(a); !r) return r.status();
  if (auto r = m.resolve(b); !r) return r.status();
  if (a.idx == b.idx) return status_of(ErrorCode::kTopology, "cannot join node ", a.idx.value, " to itself");
  if (m.nodes.surface[a.idx.value] != m.nodes.surface[b.idx.value])
    return status_of(ErrorCode::kInvalidArgument, "nodes ", a.idx.value, " and ", b.idx.value,
                     " are in different surfaces (surfaces meet only through joints)");
  if (m.find_halfedge(a.idx, b.idx).valid())
    return status_of(ErrorCode::kTopology, "nodes ", a.idx.value, " and ", b.idx.value,
                     " are already joined (parallel edges are invalid)");
  return {};
}

/// Common checks of the edge killers: a live wire edge outside mesh edges
/// and carrying no attribute node.
Status check_kill_edge(const Model& m, Edge e) {
  if (auto r = m.resolve(e); !r) return r.status();
  const EdgeIdx ei = e.idx;
  if (!m.is_wire(ei))
    return status_of(ErrorCode::kTopology, "edge ", ei.value,
                     " bounds a face; kill the face first (kill_face_make_Chole)");
  if (m.edges.mesh_edge[ei.value].valid())
    return status_of(ErrorCode::kTopology, "edge ", ei.value, " belongs to mesh edge ",
                     m.edges.mesh_edge[ei.value].value);
  if (edge_has_attrib(m, ei))
    return status_of(ErrorCode::kTopology, "edge ", ei.value, " carries attribute edge-nodes");
  return {};
}

EdgeRecord edge_record(const Model& m, EdgeIdx e) {
  return {m.tail(halfedge_of(e, 0)), m.tail(halfedge_of(e, 1)), m.edges.flags[e.value]};
}

double split_param(const Vec3d& a, const Vec3d& b, const Vec3d& p) {
  const Vec3d d = b - a;
  const double l2 = d.squaredNorm();
  if (!(l2 > 0)) return 0.5;
  return std::clamp((p - a).dot(d) / l2, 0.0, 1.0);
}

AttribChange snapshot(const Model& m, AttribNodeIdx a) {
  const auto& an = m.attrib_nodes;
  return {a, an.kind[a.value], an.element[a.value], an.corner[a.value], an.param[a.value]};
}

/// Attribute nodes on the edge of h and in the faces of h and twin(h).
struct TouchedAttribs {
  std::vector<AttribNodeIdx> edge_nodes;
  std::vector<std::pair<AttribNodeIdx, Vec3d>> face_nodes;
};
TouchedAttribs touched_attribs(const Model& m, HalfedgeIdx h) {
  TouchedAttribs t;
  const auto& an = m.attrib_nodes;
  if (an.slots.empty()) return t;
  const EdgeIdx e = edge_of(h);
  const FaceIdx f0 = m.face(h), f1 = m.face(twin(h));
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i) {
    const AttribNodeIdx a{i};
    if (!an.slots.alive(a)) continue;
    if (an.kind[i] == AttribNodeKind::kEdge && edge_of(HalfedgeIdx{an.element[i]}) == e) t.edge_nodes.push_back(a);
    if (an.kind[i] == AttribNodeKind::kFace &&
        ((f0.valid() && an.element[i] == f0.value) || (f1.valid() && an.element[i] == f1.value)))
      t.face_nodes.emplace_back(a, m.attrib_position_on_surface(a));
  }
  return t;
}

}  // namespace

// ------------------------------------------------------------- queries

bool edge_connected(const Model& m, NodeIdx a, NodeIdx b, EdgeIdx skip) {
  if (a == b) return true;
  std::vector<std::uint8_t> seen(m.nodes.slots.capacity(), 0);
  std::vector<NodeIdx> stack{a};
  seen[a.value] = 1;
  while (!stack.empty()) {
    const NodeIdx v = stack.back();
    stack.pop_back();
    bool found = false;
    m.for_each_outgoing(v, [&](HalfedgeIdx h) {
      if (found || edge_of(h) == skip) return;
      const NodeIdx w = m.head(h);
      if (w == b) found = true;
      if (!seen[w.value]) {
        seen[w.value] = 1;
        stack.push_back(w);
      }
    });
    if (found) return true;
  }
  return false;
}

bool face_group_closed(const Model& m, FaceIdx f) {
  // Most calls end at once: an open face has a faceless twin.
  bool open = false;
  m.for_each_face_halfedge(f, [&](HalfedgeIdx h) { open |= !m.face(twin(h)).valid(); });
  if (open) return false;
  std::vector<std::uint8_t> seen(m.faces.slots.capacity(), 0);
  std::vector<FaceIdx> stack{f};
  seen[f.value] = 1;
  while (!stack.empty()) {
    const FaceIdx g = stack.back();
    stack.pop_back();
    m.for_each_face_halfedge(g, [&](HalfedgeIdx h) {
      const FaceIdx o = m.face(twin(h));
      if (!o.valid()) {
        open = true;
      } else if (!seen[o.value]) {
        seen[o.value] = 1;
        stack.push_back(o);
      }
    });
    if (open) return false;
  }
  return true;
}

// ------------------------------------------------------------- vertices

Expected<Node> make_vertex_complex(Model& m, Surface s, const Vec3d& position) {
  if (auto r = m.resolve(s); !r) return r.status();
  if (!position.allFinite()) return status_of(ErrorCode::kDegenerate, "non-finite position for a new node");
  return m.handle(m.new_node(s.idx, position));
}

Expected<Node> make_vertex_complex(Model& m, const NodeRecord& r) {
  if (!r.surface.valid() || !m.alive(r.surface))
    return status_of(ErrorCode::kStaleHandle, "surface ", r.surface.value, " is dead");
  if (r.in_face.valid()) return status_of(ErrorCode::kInvalidArgument, "record is a ring node: use make_vertex_ring");
  return m.handle(new_node_from(m, r));
}

Expected<NodeRecord> kill_vertex_complex(Model& m, Node v) {
  if (auto r = m.resolve(v); !r) return r.status();
  if (!m.is_isolated(v.idx))
    return status_of(ErrorCode::kTopology, "node ", v.idx.value, " has ", m.degree(v.idx), " edges (must be isolated)");
  if (is_ring(m, v.idx))
    return status_of(ErrorCode::kTopology, "node ", v.idx.value, " is a ring node: use kill_vertex_ring");
  if (node_has_attrib(m, v.idx))
    return status_of(ErrorCode::kTopology, "node ", v.idx.value, " carries attribute nodes");
  NodeRecord r = node_record(m, v.idx);
  m.delete_node(v.idx);
  return r;
}

Expected<VertexEdge> make_vertex_edge(Model& m, Node anchor, const Vec3d& position) {
  if (auto r = m.resolve(anchor); !r) return r.status();
  VertexEdgeRecord rec;
  rec.anchor = anchor.idx;
  rec.node.surface = m.nodes.surface[anchor.idx.value];
  rec.node.position = position;
  rec.node.in_face = m.nodes.in_face[anchor.idx.value];  // joins the anchor's ring, if any
  return make_vertex_edge(m, rec);
}

Expected<VertexEdge> make_vertex_edge(Model& m, const VertexEdgeRecord& r) {
  if (!r.anchor.valid() || !m.alive(r.anchor))
    return status_of(ErrorCode::kStaleHandle, "anchor node ", r.anchor.value, " is dead");
  if (!r.node.position.allFinite()) return status_of(ErrorCode::kDegenerate, "non-finite position for a new node");
  if (r.node.surface != m.nodes.surface[r.anchor.value] || r.node.in_face != m.nodes.in_face[r.anchor.value])
    return status_of(ErrorCode::kInvalidArgument, "new node must lie in the surface and ring of anchor node ",
                     r.anchor.value);
  const NodeIdx v = new_node_from(m, r.node);
  const EdgeIdx e = r.from_anchor ? m.new_edge(r.anchor, v) : m.new_edge(v, r.anchor);
  m.edges.flags[e.value] = r.flags;
  return VertexEdge{m.handle(v), m.handle(e)};
}

Expected<VertexEdgeRecord> kill_vertex_edge(Model& m, Node v) {
  if (auto r = m.resolve(v); !r) return r.status();
  if (m.degree(v.idx) != 1)
    return status_of(ErrorCode::kTopology, "node ", v.idx.value, " has ", m.degree(v.idx),
                     " edges (must have exactly 1)");
  const HalfedgeIdx h = m.nodes.out[v.idx.value];
  const EdgeIdx e = edge_of(h);
  if (Status s = check_kill_edge(m, m.handle(e)); !s) return s;
  if (node_has_attrib(m, v.idx))
    return status_of(ErrorCode::kTopology, "node ", v.idx.value, " carries attribute nodes");
  VertexEdgeRecord r;
  r.anchor = m.head(h);
  r.node = node_record(m, v.idx);
  r.from_anchor = !is_forward(h);  // h runs v -> anchor; 2e runs anchor -> v when h is 2e+1
  r.flags = m.edges.flags[e.value];
  m.delete_edge(e);
  m.delete_node(v.idx);
  return r;
}

// ---------------------------------------------------------------- edges

Expected<Edge> make_edge_Chole(Model& m, Node a, Node b) {
  if (Status s = check_new_edge(m, a, b); !s) return s;
  const bool ra = is_ring(m, a.idx), rb = is_ring(m, b.idx);
  if (ra != rb || (ra && m.nodes.in_face[a.idx.value] != m.nodes.in_face[b.idx.value]))
    return status_of(ErrorCode::kTopology, "nodes ", a.idx.value, " and ", b.idx.value,
                     " are not in the same ring (ring nodes join only nodes of their face's rings)");
  if (!edge_connected(m, a.idx, b.idx))
    return status_of(ErrorCode::kTopology, "nodes ", a.idx.value, " and ", b.idx.value, " are in different ",
                     ra ? "rings (use make_edge_kill_ring)" : "components (use make_edge_kill_complex)");
  const EdgeIdx e = m.new_edge(a.idx, b.idx);
  ++m.complex_holes;
  return m.handle(e);
}

Expected<Edge> make_edge_Chole(Model& m, const EdgeRecord& r) {
  auto e = make_edge_Chole(m, m.handle(r.tail), m.handle(r.head));
  if (e) m.edges.flags[e->idx.value] = r.flags;
  return e;
}

Expected<EdgeRecord> kill_edge_Chole(Model& m, Edge e) {
  if (Status s = check_kill_edge(m, e); !s) return s;
  const EdgeRecord r = edge_record(m, e.idx);
  if (!edge_connected(m, r.tail, r.head, e.idx))
    return status_of(
        ErrorCode::kTopology, "edge ", e.idx.value, " is a bridge: killing it splits ",
        is_ring(m, r.tail) ? "a ring (use kill_edge_make_ring)" : "a component (use kill_edge_make_complex)");
  if (m.complex_holes <= 0) return status_of(ErrorCode::kInternal, "complex hole count is already 0");
  m.delete_edge(e.idx);
  --m.complex_holes;
  return r;
}

Expected<Edge> make_edge_kill_complex(Model& m, Node a, Node b) {
  if (Status s = check_new_edge(m, a, b); !s) return s;
  if (is_ring(m, a.idx) || is_ring(m, b.idx))
    return status_of(ErrorCode::kTopology, "ring node ", (is_ring(m, a.idx) ? a : b).idx.value,
                     " joins only nodes of its face (use make_edge_kill_ring)");
  if (edge_connected(m, a.idx, b.idx))
    return status_of(ErrorCode::kTopology, "nodes ", a.idx.value, " and ", b.idx.value,
                     " are in the same component (use make_edge_Chole)");
  return m.handle(m.new_edge(a.idx, b.idx));
}

Expected<Edge> make_edge_kill_complex(Model& m, const EdgeRecord& r) {
  auto e = make_edge_kill_complex(m, m.handle(r.tail), m.handle(r.head));
  if (e) m.edges.flags[e->idx.value] = r.flags;
  return e;
}

Expected<EdgeRecord> kill_edge_make_complex(Model& m, Edge e) {
  if (Status s = check_kill_edge(m, e); !s) return s;
  const EdgeRecord r = edge_record(m, e.idx);
  if (is_ring(m, r.tail))
    return status_of(ErrorCode::kTopology, "edge ", e.idx.value, " is a ring edge (use kill_edge_make_ring)");
  if (edge_connected(m, r.tail, r.head, e.idx))
    return status_of(ErrorCode::kTopology, "edge ", e.idx.value, " is not a bridge (use kill_edge_Chole)");
  m.delete_edge(e.idx);
  return r;
}

Expected<Edge> make_edge_kill_ring(Model& m, Node a, Node b) {
  if (Status s = check_new_edge(m, a, b); !s) return s;
  if (!is_ring(m, a.idx) || !is_ring(m, b.idx) || m.nodes.in_face[a.idx.value] != m.nodes.in_face[b.idx.value])
    return status_of(ErrorCode::kTopology, "nodes ", a.idx.value, " and ", b.idx.value,
                     " are not both ring nodes of one face");
  if (edge_connected(m, a.idx, b.idx))
    return status_of(ErrorCode::kTopology, "nodes ", a.idx.value, " and ", b.idx.value,
                     " are in the same ring (use make_edge_Chole)");
  return m.handle(m.new_edge(a.idx, b.idx));
}

Expected<Edge> make_edge_kill_ring(Model& m, const EdgeRecord& r) {
  auto e = make_edge_kill_ring(m, m.handle(r.tail), m.handle(r.head));
  if (e) m.edges.flags[e->idx.value] = r.flags;
  return e;
}

Expected<EdgeRecord> kill_edge_make_ring(Model& m, Edge e) {
  if (Status s = check_kill_edge(m, e); !s) return s;
  const EdgeRecord r = edge_record(m, e.idx);
  if (!is_ring(m, r.tail)) return status_of(ErrorCode::kTopology, "edge ", e.idx.value, " is not a ring edge");
  if (edge_connected(m, r.tail, r.head, e.idx))
    return status_of(ErrorCode::kTopology, "edge ", e.idx.value, " is not a bridge of its ring (use kill_edge_Chole)");
  m.delete_edge(e.idx);
  return r;
}

// ---------------------------------------------------------------- faces

Expected<Face> make_face_kill_Chole(Model& m, std::span<const HalfedgeIdx> cycle) {
  const std::size_t n = cycle.size();
  if (n < 3) return status_of(ErrorCode::kTopology, "a face needs a closed chain of at least 3 halfedges, got ", n);
  for (HalfedgeIdx h : cycle)
    if (!h.valid() || h.value >= m.halfedges.tail.size() || !m.alive(h))
      return status_of(ErrorCode::kStaleHandle, "halfedge ", h.value, " is dead");
  std::vector<NodeIdx> corners;
  corners.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const HalfedgeIdx h = cycle[i];
    if (m.face(h).valid())
      return status_of(ErrorCode::kTopology, "halfedge ", h.value, " already bounds face ", m.face(h).value);
    if (m.head(h) != m.tail(cycle[(i + 1) % n]))
      return status_of(ErrorCode::kTopology, "chain is not closed: halfedge ", h.value, " ends at node ",
                       m.head(h).value, " but halfedge ", cycle[(i + 1) % n].value, " starts at node ",
                       m.tail(cycle[(i + 1) % n]).value);
    if (is_ring(m, m.tail(h)))
      return status_of(ErrorCode::kTopology, "node ", m.tail(h).value, " is a ring node inside face ",
                       m.nodes.in_face[m.tail(h).value].value);
    corners.push_back(m.tail(h));
  }
  std::sort(corners.begin(), corners.end());
  if (auto it = std::adjacent_find(corners.begin(), corners.end()); it != corners.end())
    return status_of(ErrorCode::kDegenerate, "chain visits node ", it->value, " twice");
  const FaceIdx f = m.new_face(m.nodes.surface[m.tail(cycle[0]).value], cycle);
  // Seed 000 Table A-1: the face fills a complex hole, unless it closes a
  // shell (S+1, H unchanged): decided by the closure of its face group.
  if (!face_group_closed(m, f)) {
    if (m.complex_holes <= 0) {
      m.delete_face(f);
      return status_of(ErrorCode::kInternal, "complex hole count is already 0 (model does not satisfy Euler-Poincare)");
    }
    --m.complex_holes;
  }
  return m.handle(f);
}

Expected<Face> make_face_kill_Chole(Model& m, const FaceRecord& r) {
  auto f = make_face_kill_Chole(m, std::span<const HalfedgeIdx>(r.cycle));
  if (f) m.faces.flags[f->idx.value] = r.flags;
  return f;
}

Expected<FaceRecord> kill_face_make_Chole(Model& m, Face f) {
  if (auto r = m.resolve(f); !r) return r.status();
  if (face_has_ring(m, f.idx))
    return status_of(ErrorCode::kTopology, "face ", f.idx.value, " holds ring nodes (kill them first)");
  if (face_has_attrib(m, f.idx))
    return status_of(ErrorCode::kTopology, "face ", f.idx.value, " holds attribute face-nodes");
  FaceRecord r;
  r.surface = m.faces.surface[f.idx.value];
  r.flags = m.faces.flags[f.idx.value];
  m.face_halfedges(f.idx, r.cycle);
  r.closed_shell = face_group_closed(m, f.idx);
  m.delete_face(f.idx);
  if (!r.closed_shell) ++m.complex_holes;
  return r;
}

// ---------------------------------------------------------------- rings

Expected<Node> make_vertex_ring(Model& m, Face f, const Vec3d& position) {
  if (auto r = m.resolve(f); !r) return r.status();
  NodeRecord r;
  r.surface = m.faces.surface[f.idx.value];
  r.position = position;
  r.in_face = f.idx;
  return make_vertex_ring(m, r);
}

Expected<Node> make_vertex_ring(Model& m, const NodeRecord& r) {
  if (!r.in_face.valid() || !m.alive(r.in_face))
    return status_of(ErrorCode::kStaleHandle, "face ", r.in_face.value, " is dead");
  if (r.surface != m.faces.surface[r.in_face.value])
    return status_of(ErrorCode::kInvalidArgument, "ring node must be in the surface of face ", r.in_face.value);
  if (!r.position.allFinite()) return status_of(ErrorCode::kDegenerate, "non-finite position for a new node");
  return m.handle(new_node_from(m, r));
}

Expected<NodeRecord> kill_vertex_ring(Model& m, Node v) {
  if (auto r = m.resolve(v); !r) return r.status();
  if (!is_ring(m, v.idx)) return status_of(ErrorCode::kTopology, "node ", v.idx.value, " is not a ring node");
  if (!m.is_isolated(v.idx))
    return status_of(ErrorCode::kTopology, "ring node ", v.idx.value, " has ", m.degree(v.idx),
                     " edges (must be isolated)");
  if (node_has_attrib(m, v.idx))
    return status_of(ErrorCode::kTopology, "node ", v.idx.value, " carries attribute nodes");
  NodeRecord r = node_record(m, v.idx);
  m.delete_node(v.idx);
  return r;
}

// ------------------------------------------------------------ split/merge

namespace euler_detail {

void restore_attribs(Model& m, std::span<const AttribChange> changes) {
  auto& an = m.attrib_nodes;
  for (const AttribChange& c : changes) {
    an.kind[c.node.value] = c.kind;
    an.element[c.node.value] = c.element;
    an.corner[c.node.value] = c.corner;
    an.param[c.node.value] = c.param;
  }
}

namespace {
/// Areal coordinates of p projected on triangle (a, b, c); false when degenerate.
bool barycentric(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c, Vec3d& out) {
  const Vec3d v0 = b - a, v1 = c - a, v2 = p - a;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
  const double den = d00 * d11 - d01 * d01;
  if (!(std::abs(den) > 1e-300)) return false;
  const double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
  out = Vec3d(1.0 - v - w, v, w);
  return out.allFinite();
}
}  // namespace

void relocate_face_node(Model& m, AttribNodeIdx a, const Vec3d& where, std::span<const FaceIdx> candidates) {
  double best = -std::numeric_limits<double>::infinity();
  FaceIdx best_f;
  std::uint8_t best_k = 0;
  Vec3d best_b(1, 0, 0);
  std::vector<NodeIdx> c;
  for (FaceIdx f : candidates) {
    if (!f.valid() || !m.alive(f)) continue;
    m.face_nodes(f, c);
    for (std::size_t k = 0; k + 2 < c.size() && k < 255; ++k) {
      Vec3d b;
      if (!barycentric(where, m.position(c[0]), m.position(c[k + 1]), m.position(c[k + 2]), b)) continue;
      if (b.minCoeff() > best) {
        best = b.minCoeff();
        best_f = f;
        best_k = static_cast<std::uint8_t>(k);
        best_b = b;
      }
    }
    if (!best_f.valid()) {  // only degenerate fan triangles so far: keep the face, first corner
      best_f = f;
      best_k = 0;
      best_b = Vec3d(1, 0, 0);
    }
  }
  if (!best_f.valid()) return;
  best_b = best_b.cwiseMax(0.0);
  const double s = best_b.sum();
  best_b = s > 0 ? Vec3d(best_b / s) : Vec3d(1, 0, 0);
  auto& an = m.attrib_nodes;
  an.kind[a.value] = AttribNodeKind::kFace;
  an.element[a.value] = best_f.value;
  an.corner[a.value] = best_k;
  an.param[a.value] = best_b;
}

RawSplit split_edge_raw(Model& m, HalfedgeIdx h, const Vec3d& p, bool new_forward, std::vector<AttribChange>* changes) {
  const HalfedgeIdx t = twin(h);
  const EdgeIdx e = edge_of(h);
  const NodeIdx a = m.tail(h), b = m.head(h);
  const FaceIdx fh = m.face(h), ft = m.face(t);
  const TouchedAttribs touched = touched_attribs(m, h);
  if (changes) {
    for (AttribNodeIdx x : touched.edge_nodes) changes->push_back(snapshot(m, x));
    for (const auto& [x, w] : touched.face_nodes) changes->push_back(snapshot(m, x));
  }
  const double s = split_param(m.position(a), m.position(b), p);

  const NodeIdx v = m.new_node(m.nodes.surface[a.value], p);
  m.nodes.in_face[v.value] = m.nodes.in_face[a.value];
  m.nodes.uv[v.value] = (1.0 - s) * m.nodes.uv[a.value] + s * m.nodes.uv[b.value];
  m.nodes.position_backup[v.value] =
      (1.0 - s) * m.nodes.position_backup[a.value] + s * m.nodes.position_backup[b.value];
  const EdgeIdx g = new_forward ? m.new_edge(v, b) : m.new_edge(b, v);
  const HalfedgeIdx gs = halfedge_of(g, new_forward ? 0u : 1u);  // v -> b, along h
  const HalfedgeIdx gt = twin(gs);                               // b -> v, along t
  m.edges.flags[g.value] = m.edges.flags[e.value];
  m.set_tail(t, v);
  if (fh.valid()) {
    const HalfedgeIdx n = m.next(h);
    m.halfedges.face[gs.value] = fh;
    m.link_face(h, gs);
    m.link_face(gs, n);
  }
  if (ft.valid()) {
    const HalfedgeIdx pr = m.prev(t);
    m.halfedges.face[gt.value] = ft;
    m.link_face(pr, gt);
    m.link_face(gt, t);
    if (m.faces.halfedge[ft.value] == t) m.faces.halfedge[ft.value] = gt;  // keep the face's first corner b
  }
  // Mesh edge chain: the new edge goes next to e, in chain order.
  if (const MeshEdgeIdx me = m.edges.mesh_edge[e.value]; me.valid()) {
    auto row = m.mesh_edges.halfedges.row(me.value);
    for (std::size_t k = 0; k < row.size(); ++k) {
      if (row[k] == h) {
        m.mesh_edges.halfedges.insert(me.value, k + 1, gs);
        break;
      }
      if (row[k] == t) {
        m.mesh_edges.halfedges.insert(me.value, k, gt);
        break;
      }
    }
    m.edges.mesh_edge[g.value] = me;
  }
  // ATTRIB_EDGENODEs: to the half holding them, u reparametrised (seed 001 Fig. 6b).
  auto& an = m.attrib_nodes;
  for (AttribNodeIdx x : touched.edge_nodes) {
    const bool on_h = HalfedgeIdx{an.element[x.value]} == h;
    const double u = an.param[x.value].x();
    const double sh = on_h ? u : 1.0 - u;  // parameter along a -> b
    const bool first = s >= 1.0 || (s > 0.0 && sh <= s);
    double un;
    HalfedgeIdx el;
    if (first) {
      const double q = s > 0 ? sh / s : 0.0;  // along a -> v
      el = on_h ? h : t;
      un = on_h ? q : 1.0 - q;
    } else {
      const double q = s < 1 ? (sh - s) / (1.0 - s) : 1.0;  // along v -> b
      el = on_h ? gs : gt;
      un = on_h ? q : 1.0 - q;
    }
    an.element[x.value] = el.value;
    an.param[x.value] = Vec3d(std::clamp(un, 0.0, 1.0), 0, 0);
  }
  const FaceIdx cand[2] = {fh, ft};
  for (const auto& [x, w] : touched.face_nodes) relocate_face_node(m, x, w, cand);
  return {v, g};
}

}  // namespace euler_detail

Expected<SplitEdgeResult> split_edge(Model& m, Halfedge hh, const Vec3d& position) {
  if (!m.alive(hh)) return status_of(ErrorCode::kStaleHandle, "halfedge ", hh.idx.value, " is dead or was reused");
  const HalfedgeIdx h = hh.idx;
  const EdgeIdx e = edge_of(h);
  if (!position.allFinite()) return status_of(ErrorCode::kDegenerate, "non-finite split position on edge ", e.value);
  if (const MeshEdgeIdx me = m.edges.mesh_edge[e.value]; me.valid() && m.mesh_edges.joint[me.value].valid())
    return status_of(ErrorCode::kJointRefused, "edge ", e.value, " is on mesh edge ", me.value, " of joint ",
                     m.mesh_edges.joint[me.value].value, ": use edge_split, which splits every joint member");
  SplitEdgeResult r;
  const auto raw = euler_detail::split_edge_raw(m, h, position, true, &r.attribs);
  r.node = m.handle(raw.node);
  r.new_edge = m.handle(raw.edge);
  return r;
}

Expected<SplitEdgeResult> split_edge(Model& m, Edge e, const Vec3d& position) {
  if (auto r = m.resolve(e); !r) return r.status();
  return split_edge(m, m.handle(halfedge_of(e.idx, 0)), position);
}

Expected<SplitEdgeResult> split_edge(Model& m, const MergeEdgeRecord& r) {
  if (!r.kept.valid() || r.kept.value >= m.halfedges.tail.size() || !m.alive(r.kept))
    return status_of(ErrorCode::kStaleHandle, "kept halfedge ", r.kept.value, " is dead");
  const EdgeIdx e = edge_of(r.kept);
  if (const MeshEdgeIdx me = m.edges.mesh_edge[e.value]; me.valid() && m.mesh_edges.joint[me.value].valid())
    return status_of(ErrorCode::kJointRefused, "edge ", e.value, " is on a joint mesh edge");
  if (r.node.surface != m.nodes.surface[m.tail(r.kept).value])
    return status_of(ErrorCode::kInvalidArgument, "record's node is not in the surface of edge ", e.value);
  const HalfedgeIdx h = r.kept, t = twin(h);
  const auto raw = euler_detail::split_edge_raw(m, h, r.node.position, r.removed_forward, nullptr);
  const NodeIdx v = raw.node;
  m.nodes.position_backup[v.value] = r.node.position_backup;
  m.nodes.uv[v.value] = r.node.uv;
  m.nodes.in_face[v.value] = r.node.in_face;
  m.edges.flags[raw.edge.value] = r.removed_flags;
  const HalfedgeIdx gs = halfedge_of(raw.edge, r.removed_forward ? 0u : 1u), gt = twin(gs);
  if (const FaceIdx fh = m.face(h); fh.valid() && r.face_start_on_removed[0]) m.faces.halfedge[fh.value] = gs;
  if (const FaceIdx ft = m.face(t); ft.valid()) {
    if (r.face_start_on_removed[1])
      m.faces.halfedge[ft.value] = gt;
    else if (m.faces.halfedge[ft.value] == gt)
      m.faces.halfedge[ft.value] = t;
  }
  euler_detail::restore_attribs(m, r.attribs);
  SplitEdgeResult out;
  out.node = m.handle(v);
  out.new_edge = m.handle(raw.edge);
  return out;
}

Expected<MergeEdgeRecord> merge_edge(Model& m, Node vh, Edge keep, std::span<const AttribChange> restore) {
  if (auto r = m.resolve(vh); !r) return r.status();
  if (auto r = m.resolve(keep); !r) return r.status();
  const NodeIdx v = vh.idx;
  if (m.degree(v) != 2)
    return status_of(ErrorCode::kTopology, "node ", v.value, " has ", m.degree(v), " edges (merge needs exactly 2)");
  HalfedgeIdx kt, rs;  // kt: v -> a on the kept edge; rs: v -> b on the removed edge
  m.for_each_outgoing(v, [&](HalfedgeIdx x) { (edge_of(x) == keep.idx ? kt : rs) = x; });
  if (!kt.valid())
    return status_of(ErrorCode::kInvalidArgument, "edge ", keep.idx.value, " does not end at node ", v.value);
  const HalfedgeIdx k = twin(kt), rt = twin(rs);
  const EdgeIdx re = edge_of(rs);
  const NodeIdx a = m.tail(k), b = m.head(rs);
  if (a == b)
    return status_of(ErrorCode::kTopology, "merging at node ", v.value, " would make a loop edge on node ", a.value);
  if (m.find_halfedge(a, b).valid())
    return status_of(ErrorCode::kTopology, "nodes ", a.value, " and ", b.value, " are already joined: merging at node ",
                     v.value, " would make parallel edges");
  const MeshEdgeIdx mk = m.edges.mesh_edge[keep.idx.value], mr = m.edges.mesh_edge[re.value];
  if (mk != mr)
    return status_of(ErrorCode::kTopology, "edges ", keep.idx.value, " and ", re.value, " at node ", v.value,
                     " are not in the same mesh edge");
  std::size_t chain_pos = 0;
  if (mk.valid()) {
    if (m.mesh_edges.joint[mk.value].valid())
      return status_of(ErrorCode::kJointRefused, "node ", v.value, " is on mesh edge ", mk.value, " of joint ",
                       m.mesh_edges.joint[mk.value].value);
    auto row = m.mesh_edges.halfedges.row(mk.value);
    std::size_t pk = row.size(), pr = row.size();
    for (std::size_t i = 0; i < row.size(); ++i) {
      if (edge_of(row[i]) == keep.idx) pk = i;
      if (edge_of(row[i]) == re) pr = i;
    }
    if (pk + 1 != pr && pr + 1 != pk)
      return status_of(ErrorCode::kTopology, "node ", v.value, " is an end of mesh edge ", mk.value);
    chain_pos = pr;
  }
  for (HalfedgeIdx x : {k, kt})
    if (const FaceIdx f = m.face(x); f.valid() && m.face_degree(f) <= 3)
      return status_of(ErrorCode::kDegenerate, "merging at node ", v.value, " would leave face ", f.value,
                       " with 2 sides");
  if (node_has_attrib(m, v)) return status_of(ErrorCode::kTopology, "node ", v.value, " carries attribute nodes");

  MergeEdgeRecord rec;
  rec.kept = k;
  rec.node = node_record(m, v);
  rec.removed_forward = is_forward(rs);
  rec.removed_flags = m.edges.flags[re.value];
  const FaceIdx fk = m.face(k), fkt = m.face(kt);
  rec.face_start_on_removed[0] = fk.valid() && m.faces.halfedge[fk.value] == rs;
  rec.face_start_on_removed[1] = fkt.valid() && m.faces.halfedge[fkt.value] == rt;

  // Attributes on both edges and in both faces, positions taken before the change.
  std::vector<AttribNodeIdx> edge_nodes;
  std::vector<std::pair<AttribNodeIdx, Vec3d>> face_nodes;
  {
    const TouchedAttribs t1 = touched_attribs(m, k), t2 = touched_attribs(m, rs);
    edge_nodes = t1.edge_nodes;
    edge_nodes.insert(edge_nodes.end(), t2.edge_nodes.begin(), t2.edge_nodes.end());
    face_nodes = t1.face_nodes;  // the faces of k and rs are the same two faces
    for (AttribNodeIdx x : edge_nodes) rec.attribs.push_back(snapshot(m, x));
    for (const auto& [x, w] : face_nodes) rec.attribs.push_back(snapshot(m, x));
  }
  const double s = split_param(m.position(a), m.position(b), m.position(v));

  if (fk.valid()) {
    m.link_face(k, m.next(rs));
    if (m.faces.halfedge[fk.value] == rs) m.faces.halfedge[fk.value] = k;
  }
  if (fkt.valid()) {
    m.link_face(m.prev(rt), kt);
    if (m.faces.halfedge[fkt.value] == rt) m.faces.halfedge[fkt.value] = kt;
  }
  for (HalfedgeIdx x : {rs, rt}) {
    m.halfedges.face[x.value] = {};
    m.halfedges.next[x.value] = m.halfedges.prev[x.value] = {};
  }
  if (mk.valid()) m.mesh_edges.halfedges.erase(mk.value, chain_pos);
  m.set_tail(kt, b);
  m.delete_edge(re);
  m.delete_node(v);

  auto& an = m.attrib_nodes;
  for (AttribNodeIdx x : edge_nodes) {
    const HalfedgeIdx el{an.element[x.value]};
    const double u = an.param[x.value].x();
    double sab;  // parameter along a -> b
    if (el == k)
      sab = u * s;
    else if (el == kt)
      sab = (1.0 - u) * s;
    else if (el == rs)
      sab = s + u * (1.0 - s);
    else
      sab = 1.0 - u * (1.0 - s);  // rt: b -> v
    const bool along = el == k || el == rs;
    an.element[x.value] = (along ? k : kt).value;
    an.param[x.value] = Vec3d(std::clamp(along ? sab : 1.0 - sab, 0.0, 1.0), 0, 0);
  }
  const FaceIdx cand[2] = {fk, fkt};
  for (const auto& [x, w] : face_nodes) euler_detail::relocate_face_node(m, x, w, cand);
  euler_detail::restore_attribs(m, restore);
  return rec;
}

}  // namespace atelier
