// The Model's queries and primitives (storage/model.h): adding and deleting
// rows of every table with their incidences kept symmetric. compact() is in
// model_compact.cpp, diff_tables in model_diff.cpp.
#include <atelier/storage/model.h>

#include <algorithm>
#include <sstream>

namespace atelier {

namespace {
template <class T>
void put(std::vector<T>& col, std::uint32_t i, bool appended, const T& v) {
  if (appended)
    col.push_back(v);
  else
    col[i] = v;
}
}  // namespace

std::string Model::stale_message(const char* kind, std::uint32_t index, std::uint32_t generation) {
  std::ostringstream s;
  s << kind << " " << index << " (generation " << generation << ") is dead or was reused";
  return s.str();
}

std::size_t Model::degree(NodeIdx v) const noexcept {
  std::size_t n = 0;
  for_each_outgoing(v, [&](HalfedgeIdx) { ++n; });
  return n;
}

std::size_t Model::face_degree(FaceIdx f) const noexcept {
  std::size_t n = 0;
  for_each_face_halfedge(f, [&](HalfedgeIdx) { ++n; });
  return n;
}

HalfedgeIdx Model::find_halfedge(NodeIdx a, NodeIdx b) const noexcept {
  HalfedgeIdx found;
  for_each_outgoing(a, [&](HalfedgeIdx h) {
    if (!found.valid() && head(h) == b) found = h;
  });
  return found;
}

void Model::face_nodes(FaceIdx f, std::vector<NodeIdx>& out) const {
  out.clear();
  for_each_face_halfedge(f, [&](HalfedgeIdx h) { out.push_back(tail(h)); });
}

void Model::face_halfedges(FaceIdx f, std::vector<HalfedgeIdx>& out) const {
  out.clear();
  for_each_face_halfedge(f, [&](HalfedgeIdx h) { out.push_back(h); });
}

void Model::outgoing(NodeIdx v, std::vector<HalfedgeIdx>& out) const {
  out.clear();
  for_each_outgoing(v, [&](HalfedgeIdx h) { out.push_back(h); });
}

Vec3d Model::attrib_position_on_surface(AttribNodeIdx a) const {
  const auto i = a.value;
  const Vec3d& prm = attrib_nodes.param[i];
  switch (attrib_nodes.kind[i]) {
    case AttribNodeKind::kVertex:
      return position(NodeIdx{attrib_nodes.element[i]});
    case AttribNodeKind::kEdge: {
      const HalfedgeIdx h{attrib_nodes.element[i]};
      return (1.0 - prm.x()) * position(tail(h)) + prm.x() * position(head(h));
    }
    case AttribNodeKind::kFace: {
      const FaceIdx f{attrib_nodes.element[i]};
      const HalfedgeIdx h0 = faces.halfedge[f.value];
      HalfedgeIdx h1 = next(h0);
      for (unsigned k = 0; k < attrib_nodes.corner[i]; ++k) h1 = next(h1);
      const HalfedgeIdx h2 = next(h1);
      return prm.x() * position(tail(h0)) + prm.y() * position(tail(h1)) + prm.z() * position(tail(h2));
    }
  }
  return Vec3d::Zero();
}

// --------------------------------------------------------------- primitives

void Model::sync_node_columns() {
  const std::size_t n = nodes.slots.capacity();
  nodes.position.resize(n, Vec3d::Zero());
  nodes.position_backup.resize(n, Vec3d::Zero());
  nodes.uv.resize(n, Vec2d::Zero());
  nodes.out.resize(n);
  nodes.surface.resize(n);
  nodes.in_face.resize(n);
  nodes.props.resize(n);
}

void Model::sync_edge_columns() {
  const std::size_t n = edges.slots.capacity();
  edges.flags.resize(n, 0);
  edges.mesh_edge.resize(n);
  edges.props.resize(n);
  halfedges.tail.resize(2 * n);
  halfedges.face.resize(2 * n);
  halfedges.next.resize(2 * n);
  halfedges.prev.resize(2 * n);
  halfedges.vnext.resize(2 * n);
  halfedges.vprev.resize(2 * n);
  halfedges.props.resize(2 * n);
}

void Model::sync_face_columns() {
  const std::size_t n = faces.slots.capacity();
  faces.halfedge.resize(n);
  faces.surface.resize(n);
  faces.flags.resize(n, 0);
  faces.props.resize(n);
}

void Model::reserve(std::size_t n_nodes, std::size_t n_edges, std::size_t n_faces) {
  nodes.position.reserve(n_nodes);
  nodes.position_backup.reserve(n_nodes);
  nodes.uv.reserve(n_nodes);
  nodes.out.reserve(n_nodes);
  nodes.surface.reserve(n_nodes);
  nodes.in_face.reserve(n_nodes);
  edges.flags.reserve(n_edges);
  edges.mesh_edge.reserve(n_edges);
  for (auto* c : {&halfedges.next, &halfedges.prev, &halfedges.vnext, &halfedges.vprev}) c->reserve(2 * n_edges);
  halfedges.tail.reserve(2 * n_edges);
  halfedges.face.reserve(2 * n_edges);
  faces.halfedge.reserve(n_faces);
  faces.surface.reserve(n_faces);
  faces.flags.reserve(n_faces);
}

Surface Model::add_surface(std::string name) {
  bool app = false;
  const SurfaceIdx s = surfaces.slots.allocate(app);
  put(surfaces.name, s.value, app, std::move(name));
  put(surfaces.flags, s.value, app, std::uint8_t{0});
  if (app)
    surfaces.props.resize(surfaces.slots.capacity());
  else
    surfaces.props.reset(s);
  ++topology_version;
  return handle(s);
}

void Model::remove_surface(SurfaceIdx s) {
  surfaces.name[s.value].clear();
  surfaces.flags[s.value] = 0;
  surfaces.props.reset(s);
  surfaces.slots.release(s);
  ++topology_version;
}

NodeIdx Model::new_node(SurfaceIdx s, const Vec3d& p) {
  bool app = false;
  const NodeIdx v = nodes.slots.allocate(app);
  put(nodes.position, v.value, app, p);
  put(nodes.position_backup, v.value, app, Vec3d(Vec3d::Zero()));
  put(nodes.uv, v.value, app, Vec2d(Vec2d::Zero()));
  put(nodes.out, v.value, app, HalfedgeIdx{});
  put(nodes.surface, v.value, app, s);
  put(nodes.in_face, v.value, app, FaceIdx{});
  if (app)
    nodes.props.resize(nodes.slots.capacity());
  else
    nodes.props.reset(v);
  ++topology_version;
  return v;
}

void Model::delete_node(NodeIdx v) {
  nodes.position[v.value] = Vec3d::Zero();
  nodes.position_backup[v.value] = Vec3d::Zero();
  nodes.uv[v.value] = Vec2d::Zero();
  nodes.out[v.value] = {};
  nodes.surface[v.value] = {};
  nodes.in_face[v.value] = {};
  nodes.props.reset(v);
  nodes.slots.release(v);
  ++topology_version;
}

void Model::link_out(HalfedgeIdx h) {
  const NodeIdx v = tail(h);
  HalfedgeIdx& head_of_ring = nodes.out[v.value];
  auto& vn = halfedges.vnext;
  auto& vp = halfedges.vprev;
  if (!head_of_ring.valid()) {
    head_of_ring = h;
    vn[h.value] = vp[h.value] = h;
    return;
  }
  // Sorted insertion: before the first element greater than h. New
  // halfedges usually have the largest index, so try the end of the ring first.
  const HalfedgeIdx start = head_of_ring;
  HalfedgeIdx x = start;
  if (!(vp[start.value] < h)) {
    do {
      if (x > h) break;
      x = vn[x.value];
    } while (x != start);
  }
  // Insert h before x (if no greater element was found, x == start: insert at end).
  const HalfedgeIdx p = vp[x.value];
  vn[p.value] = h;
  vp[h.value] = p;
  vn[h.value] = x;
  vp[x.value] = h;
  if (h < start) head_of_ring = h;
}

void Model::unlink_out(HalfedgeIdx h) {
  const NodeIdx v = tail(h);
  auto& vn = halfedges.vnext;
  auto& vp = halfedges.vprev;
  if (vn[h.value] == h) {
    nodes.out[v.value] = {};
  } else {
    const HalfedgeIdx p = vp[h.value], n = vn[h.value];
    vn[p.value] = n;
    vp[n.value] = p;
    if (nodes.out[v.value] == h) nodes.out[v.value] = n;
  }
  vn[h.value] = vp[h.value] = {};
}

EdgeIdx Model::new_edge(NodeIdx a, NodeIdx b) {
  bool app = false;
  const EdgeIdx e = edges.slots.allocate(app);
  if (app) {
    sync_edge_columns();
  } else {
    edges.props.reset(e);
    halfedges.props.reset(halfedge_of(e, 0));
    halfedges.props.reset(halfedge_of(e, 1));
  }
  edges.flags[e.value] = 0;
  edges.mesh_edge[e.value] = {};
  const HalfedgeIdx h0 = halfedge_of(e, 0), h1 = halfedge_of(e, 1);
  halfedges.tail[h0.value] = a;
  halfedges.tail[h1.value] = b;
  for (HalfedgeIdx h : {h0, h1}) {
    halfedges.face[h.value] = {};
    halfedges.next[h.value] = halfedges.prev[h.value] = {};
  }
  link_out(h0);
  link_out(h1);
  ++topology_version;
  return e;
}

void Model::delete_edge(EdgeIdx e) {
  for (unsigned s = 0; s < 2; ++s) {
    const HalfedgeIdx h = halfedge_of(e, s);
    unlink_out(h);
    halfedges.tail[h.value] = {};
    halfedges.face[h.value] = {};
    halfedges.next[h.value] = halfedges.prev[h.value] = {};
  }
  edges.flags[e.value] = 0;
  edges.mesh_edge[e.value] = {};
  edges.props.reset(e);
  halfedges.props.reset(halfedge_of(e, 0));
  halfedges.props.reset(halfedge_of(e, 1));
  edges.slots.release(e);
  ++topology_version;
}

FaceIdx Model::new_face(SurfaceIdx s, std::span<const HalfedgeIdx> cycle) {
  bool app = false;
  const FaceIdx f = faces.slots.allocate(app);
  put(faces.halfedge, f.value, app, cycle.front());
  put(faces.surface, f.value, app, s);
  put(faces.flags, f.value, app, std::uint8_t{0});
  if (app)
    faces.props.resize(faces.slots.capacity());
  else
    faces.props.reset(f);
  const std::size_t n = cycle.size();
  for (std::size_t i = 0; i < n; ++i) {
    halfedges.face[cycle[i].value] = f;
    link_face(cycle[i], cycle[(i + 1) % n]);
  }
  ++topology_version;
  return f;
}

void Model::delete_face(FaceIdx f) {
  const HalfedgeIdx start = faces.halfedge[f.value];
  HalfedgeIdx h = start;
  do {
    const HalfedgeIdx n = halfedges.next[h.value];
    halfedges.face[h.value] = {};
    halfedges.next[h.value] = halfedges.prev[h.value] = {};
    h = n;
  } while (h != start);
  faces.halfedge[f.value] = {};
  faces.surface[f.value] = {};
  faces.flags[f.value] = 0;
  faces.props.reset(f);
  faces.slots.release(f);
  ++topology_version;
}

void Model::set_tail(HalfedgeIdx h, NodeIdx v) {
  unlink_out(h);
  halfedges.tail[h.value] = v;
  link_out(h);
  ++topology_version;
}

MeshEdgeIdx Model::new_mesh_edge(SurfaceIdx s, std::span<const HalfedgeIdx> chain) {
  bool app = false;
  const MeshEdgeIdx m = mesh_edges.slots.allocate(app);
  put(mesh_edges.surface, m.value, app, s);
  put(mesh_edges.loop, m.value, app, MeshLoopIdx{});
  put(mesh_edges.joint, m.value, app, JointIdx{});
  if (app) mesh_edges.halfedges.resize_rows(mesh_edges.slots.capacity());
  mesh_edges.halfedges.assign(m.value, chain);
  for (HalfedgeIdx h : chain) edges.mesh_edge[edge_of(h).value] = m;
  ++topology_version;
  return m;
}

void Model::delete_mesh_edge(MeshEdgeIdx m) {
  for (HalfedgeIdx h : mesh_edges.halfedges.row(m.value))
    if (alive(h) && edges.mesh_edge[edge_of(h).value] == m) edges.mesh_edge[edge_of(h).value] = {};
  mesh_edges.halfedges.clear_row(m.value);
  mesh_edges.surface[m.value] = {};
  mesh_edges.loop[m.value] = {};
  mesh_edges.joint[m.value] = {};
  mesh_edges.slots.release(m);
  ++topology_version;
}

MeshLoopIdx Model::new_mesh_loop(SurfaceIdx s, std::span<const MeshEdgeIdx> list) {
  bool app = false;
  const MeshLoopIdx l = mesh_loops.slots.allocate(app);
  put(mesh_loops.surface, l.value, app, s);
  if (app) mesh_loops.mesh_edges.resize_rows(mesh_loops.slots.capacity());
  mesh_loops.mesh_edges.assign(l.value, list);
  for (MeshEdgeIdx m : list) mesh_edges.loop[m.value] = l;
  ++topology_version;
  return l;
}

void Model::delete_mesh_loop(MeshLoopIdx l) {
  for (MeshEdgeIdx m : mesh_loops.mesh_edges.row(l.value))
    if (alive(m) && mesh_edges.loop[m.value] == l) mesh_edges.loop[m.value] = {};
  mesh_loops.mesh_edges.clear_row(l.value);
  mesh_loops.surface[l.value] = {};
  mesh_loops.slots.release(l);
  ++topology_version;
}

JointIdx Model::new_joint(std::span<const JointMember> members) {
  bool app = false;
  const JointIdx j = joints.slots.allocate(app);
  if (app) joints.members.resize_rows(joints.slots.capacity());
  joints.members.assign(j.value, members);
  for (const JointMember& m : members) mesh_edges.joint[m.mesh_edge.value] = j;
  ++topology_version;
  return j;
}

void Model::delete_joint(JointIdx j) {
  for (const JointMember& m : joints.members.row(j.value))
    if (alive(m.mesh_edge) && mesh_edges.joint[m.mesh_edge.value] == j) mesh_edges.joint[m.mesh_edge.value] = {};
  joints.members.clear_row(j.value);
  joints.slots.release(j);
  ++topology_version;
}

AttribNodeIdx Model::new_attrib_node(SurfaceIdx s, AttribNodeKind kind, std::uint32_t element, const Vec3d& param,
                                     const Vec3d& pos, std::uint8_t corner) {
  bool app = false;
  auto& t = attrib_nodes;
  const AttribNodeIdx a = t.slots.allocate(app);
  put(t.kind, a.value, app, kind);
  put(t.element, a.value, app, element);
  put(t.corner, a.value, app, corner);
  put(t.param, a.value, app, param);
  put(t.position, a.value, app, pos);
  put(t.owner, a.value, app, AttribEdgeIdx{});
  put(t.surface, a.value, app, s);
  return a;
}

void Model::delete_attrib_node(AttribNodeIdx a) {
  auto& t = attrib_nodes;
  t.kind[a.value] = AttribNodeKind::kVertex;
  t.element[a.value] = 0;
  t.corner[a.value] = 0;
  t.param[a.value] = Vec3d::Zero();
  t.position[a.value] = Vec3d::Zero();
  t.owner[a.value] = {};
  t.surface[a.value] = {};
  t.slots.release(a);
}

AttribEdgeIdx Model::new_attrib_edge(SurfaceIdx s, std::int32_t feature_id, std::span<const AttribNodeIdx> list) {
  bool app = false;
  auto& t = attrib_edges;
  const AttribEdgeIdx a = t.slots.allocate(app);
  put(t.surface, a.value, app, s);
  put(t.feature_id, a.value, app, feature_id);
  if (app) {
    t.nodes.resize_rows(t.slots.capacity());
    t.props.resize(t.slots.capacity());
  } else {
    t.props.reset(a);
  }
  t.nodes.assign(a.value, list);
  for (AttribNodeIdx n : list) attrib_nodes.owner[n.value] = a;
  return a;
}

void Model::delete_attrib_edge(AttribEdgeIdx a) {
  auto& t = attrib_edges;
  for (AttribNodeIdx n : t.nodes.row(a.value))
    if (alive(n) && attrib_nodes.owner[n.value] == a) attrib_nodes.owner[n.value] = {};
  t.nodes.clear_row(a.value);
  t.surface[a.value] = {};
  t.feature_id[a.value] = 0;
  t.props.reset(a);
  t.slots.release(a);
}

}  // namespace atelier
