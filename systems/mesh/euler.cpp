// The make/kill Euler operators (systems/mesh/euler.h) and the connectivity
// queries they use; split_edge / merge_edge are in euler_split.cpp.
#include <atelier/systems/mesh/euler.h>

#include <algorithm>
#include <limits>
#include <sstream>

#include <atelier/engine/status_format.h>

#include "euler_detail.h"

namespace atelier {

namespace {

using euler_detail::node_has_attrib;
using euler_detail::node_record;

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

}  // namespace atelier
