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

// ------------------------------------------------------------------ compact

namespace {
template <class Tag>
Idx<Tag> map_idx(const std::vector<Idx<Tag>>& remap, Idx<Tag> i) {
  return i.valid() ? remap[i.value] : i;
}
}  // namespace

CompactRemap Model::compact() {
  CompactRemap r;
  r.nodes = nodes.slots.compact();
  r.edges = edges.slots.compact();
  r.faces = faces.slots.compact();
  r.surfaces = surfaces.slots.compact();
  r.mesh_edges = mesh_edges.slots.compact();
  r.mesh_loops = mesh_loops.slots.compact();
  r.joints = joints.slots.compact();
  r.attrib_nodes = attrib_nodes.slots.compact();
  r.attrib_edges = attrib_edges.slots.compact();
  auto mh = [&](HalfedgeIdx h) { return h.valid() ? r.halfedge(h) : h; };

  // Nodes.
  const std::size_t nn = nodes.slots.capacity();
  compact_column(nodes.position, r.nodes, nn);
  compact_column(nodes.position_backup, r.nodes, nn);
  compact_column(nodes.uv, r.nodes, nn);
  compact_column(nodes.out, r.nodes, nn);
  compact_column(nodes.surface, r.nodes, nn);
  compact_column(nodes.in_face, r.nodes, nn);
  nodes.props.compact(r.nodes, nn);
  for (auto& h : nodes.out) h = mh(h);
  for (auto& s : nodes.surface) s = map_idx(r.surfaces, s);
  for (auto& f : nodes.in_face) f = map_idx(r.faces, f);

  // Edges and halfedges.
  const std::size_t ne = edges.slots.capacity();
  compact_column(edges.flags, r.edges, ne);
  compact_column(edges.mesh_edge, r.edges, ne);
  edges.props.compact(r.edges, ne);
  for (auto& m : edges.mesh_edge) m = map_idx(r.mesh_edges, m);
  {
    std::vector<HalfedgeIdx> hr(2 * r.edges.size());
    for (std::size_t e = 0; e < r.edges.size(); ++e)
      for (unsigned s = 0; s < 2; ++s)
        hr[2 * e + s] = r.edges[e].valid() ? halfedge_of(r.edges[e], s) : HalfedgeIdx{};
    compact_column(halfedges.tail, hr, 2 * ne);
    halfedges.props.compact(hr, 2 * ne);
    compact_column(halfedges.face, hr, 2 * ne);
    compact_column(halfedges.next, hr, 2 * ne);
    compact_column(halfedges.prev, hr, 2 * ne);
    compact_column(halfedges.vnext, hr, 2 * ne);
    compact_column(halfedges.vprev, hr, 2 * ne);
    for (auto& v : halfedges.tail) v = map_idx(r.nodes, v);
    for (auto& f : halfedges.face) f = map_idx(r.faces, f);
    for (auto* c : {&halfedges.next, &halfedges.prev, &halfedges.vnext, &halfedges.vprev})
      for (auto& h : *c) h = mh(h);
  }

  // Faces.
  const std::size_t nf = faces.slots.capacity();
  compact_column(faces.halfedge, r.faces, nf);
  compact_column(faces.surface, r.faces, nf);
  compact_column(faces.flags, r.faces, nf);
  faces.props.compact(r.faces, nf);
  for (auto& h : faces.halfedge) h = mh(h);
  for (auto& s : faces.surface) s = map_idx(r.surfaces, s);

  // Surfaces.
  const std::size_t ns = surfaces.slots.capacity();
  compact_column(surfaces.name, r.surfaces, ns);
  compact_column(surfaces.flags, r.surfaces, ns);
  surfaces.props.compact(r.surfaces, ns);

  // Mesh edges, loops, joints.
  const std::size_t nm = mesh_edges.slots.capacity();
  compact_column(mesh_edges.surface, r.mesh_edges, nm);
  compact_column(mesh_edges.loop, r.mesh_edges, nm);
  compact_column(mesh_edges.joint, r.mesh_edges, nm);
  mesh_edges.halfedges.compact(r.mesh_edges, nm);
  for (auto& s : mesh_edges.surface) s = map_idx(r.surfaces, s);
  for (auto& l : mesh_edges.loop) l = map_idx(r.mesh_loops, l);
  for (auto& j : mesh_edges.joint) j = map_idx(r.joints, j);
  mesh_edges.halfedges.transform_values(mh);

  const std::size_t nl = mesh_loops.slots.capacity();
  compact_column(mesh_loops.surface, r.mesh_loops, nl);
  mesh_loops.mesh_edges.compact(r.mesh_loops, nl);
  for (auto& s : mesh_loops.surface) s = map_idx(r.surfaces, s);
  mesh_loops.mesh_edges.transform_values([&](MeshEdgeIdx m) { return map_idx(r.mesh_edges, m); });

  joints.members.compact(r.joints, joints.slots.capacity());
  joints.members.transform_values([&](JointMember m) {
    m.mesh_edge = map_idx(r.mesh_edges, m.mesh_edge);
    return m;
  });

  // Attributes.
  const std::size_t na = attrib_nodes.slots.capacity();
  auto& an = attrib_nodes;
  compact_column(an.kind, r.attrib_nodes, na);
  compact_column(an.element, r.attrib_nodes, na);
  compact_column(an.corner, r.attrib_nodes, na);
  compact_column(an.param, r.attrib_nodes, na);
  compact_column(an.position, r.attrib_nodes, na);
  compact_column(an.owner, r.attrib_nodes, na);
  compact_column(an.surface, r.attrib_nodes, na);
  for (std::size_t i = 0; i < na; ++i) {
    switch (an.kind[i]) {
      case AttribNodeKind::kVertex: an.element[i] = r.nodes[an.element[i]].value; break;
      case AttribNodeKind::kEdge: an.element[i] = r.halfedge(HalfedgeIdx{an.element[i]}).value; break;
      case AttribNodeKind::kFace: an.element[i] = r.faces[an.element[i]].value; break;
    }
    an.owner[i] = map_idx(r.attrib_edges, an.owner[i]);
    an.surface[i] = map_idx(r.surfaces, an.surface[i]);
  }
  const std::size_t nae = attrib_edges.slots.capacity();
  auto& ae = attrib_edges;
  compact_column(ae.surface, r.attrib_edges, nae);
  compact_column(ae.feature_id, r.attrib_edges, nae);
  ae.nodes.compact(r.attrib_edges, nae);
  ae.props.compact(r.attrib_edges, nae);
  for (auto& s : ae.surface) s = map_idx(r.surfaces, s);
  ae.nodes.transform_values([&](AttribNodeIdx a) { return map_idx(r.attrib_nodes, a); });

  ++topology_version;
  return r;
}

// --------------------------------------------------------------- diff_tables

namespace {

struct Differ {
  std::ostringstream out;
  bool found = false;
  template <class A, class B>
  void note(const char* what, std::size_t i, const A&, const B&) {
    if (found) return;
    found = true;
    out << what << " differs at " << i;
  }
};

template <class Tag>
bool live_sets_equal(const SlotTable<Tag>& a, const SlotTable<Tag>& b, const char* kind, Differ& d) {
  const std::size_t n = std::max(a.capacity(), b.capacity());
  for (std::size_t i = 0; i < n; ++i) {
    const bool la = a.alive(Idx<Tag>{static_cast<std::uint32_t>(i)});
    const bool lb = b.alive(Idx<Tag>{static_cast<std::uint32_t>(i)});
    if (la != lb) {
      if (!d.found) {
        d.found = true;
        d.out << kind << " " << i << " is " << (la ? "alive" : "dead") << " in the first model and "
              << (lb ? "alive" : "dead") << " in the second";
      }
      return false;
    }
  }
  return true;
}

template <class T>
bool bits_equal(const T& a, const T& b) {
  if constexpr (std::is_same_v<T, Vec3d> || std::is_same_v<T, Vec2d>) {
    return std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
  } else {
    return a == b;
  }
}

template <class Tag, class T>
void cmp_col(const SlotTable<Tag>& slots, const std::vector<T>& a, const std::vector<T>& b, const char* what,
             Differ& d, std::size_t stride = 1) {
  if (d.found) return;
  for (std::size_t i = 0; i < slots.capacity(); ++i) {
    if (!slots.alive(Idx<Tag>{static_cast<std::uint32_t>(i)})) continue;
    for (std::size_t s = 0; s < stride; ++s)
      if (!bits_equal(a[stride * i + s], b[stride * i + s])) {
        d.found = true;
        d.out << what << " differs at " << stride * i + s;
        return;
      }
  }
}

template <class Tag, class T>
void cmp_ragged(const SlotTable<Tag>& slots, const RaggedColumn<T>& a, const RaggedColumn<T>& b, const char* what,
                Differ& d) {
  if (d.found) return;
  for (std::size_t i = 0; i < slots.capacity(); ++i) {
    if (!slots.alive(Idx<Tag>{static_cast<std::uint32_t>(i)})) continue;
    auto ra = a.row(i), rb = b.row(i);
    if (!std::equal(ra.begin(), ra.end(), rb.begin(), rb.end())) {
      d.found = true;
      d.out << what << " list differs at " << i;
      return;
    }
  }
}

}  // namespace

std::string diff_tables(const Model& a, const Model& b) {
  Differ d;
  if (a.complex_holes != b.complex_holes) {
    d.found = true;
    d.out << "complex hole count differs: " << a.complex_holes << " vs " << b.complex_holes;
    return d.out.str();
  }
  if (live_sets_equal(a.nodes.slots, b.nodes.slots, "node", d)) {
    const auto& s = a.nodes.slots;
    cmp_col(s, a.nodes.position, b.nodes.position, "node position", d);
    cmp_col(s, a.nodes.position_backup, b.nodes.position_backup, "node backup position", d);
    cmp_col(s, a.nodes.uv, b.nodes.uv, "node uv", d);
    cmp_col(s, a.nodes.out, b.nodes.out, "node outgoing halfedge", d);
    cmp_col(s, a.nodes.surface, b.nodes.surface, "node surface", d);
    cmp_col(s, a.nodes.in_face, b.nodes.in_face, "node in_face", d);
  }
  if (!d.found && live_sets_equal(a.edges.slots, b.edges.slots, "edge", d)) {
    const auto& s = a.edges.slots;
    cmp_col(s, a.edges.flags, b.edges.flags, "edge flags", d);
    cmp_col(s, a.edges.mesh_edge, b.edges.mesh_edge, "edge mesh edge", d);
    cmp_col(s, a.halfedges.tail, b.halfedges.tail, "halfedge tail", d, 2);
    cmp_col(s, a.halfedges.face, b.halfedges.face, "halfedge face", d, 2);
    cmp_col(s, a.halfedges.next, b.halfedges.next, "halfedge next", d, 2);
    cmp_col(s, a.halfedges.prev, b.halfedges.prev, "halfedge prev", d, 2);
    cmp_col(s, a.halfedges.vnext, b.halfedges.vnext, "halfedge vnext", d, 2);
    cmp_col(s, a.halfedges.vprev, b.halfedges.vprev, "halfedge vprev", d, 2);
  }
  if (!d.found && live_sets_equal(a.faces.slots, b.faces.slots, "face", d)) {
    const auto& s = a.faces.slots;
    cmp_col(s, a.faces.halfedge, b.faces.halfedge, "face halfedge", d);
    cmp_col(s, a.faces.surface, b.faces.surface, "face surface", d);
    cmp_col(s, a.faces.flags, b.faces.flags, "face flags", d);
  }
  if (!d.found && live_sets_equal(a.surfaces.slots, b.surfaces.slots, "surface", d))
    cmp_col(a.surfaces.slots, a.surfaces.name, b.surfaces.name, "surface name", d);
  if (!d.found && live_sets_equal(a.mesh_edges.slots, b.mesh_edges.slots, "mesh edge", d)) {
    const auto& s = a.mesh_edges.slots;
    cmp_col(s, a.mesh_edges.surface, b.mesh_edges.surface, "mesh edge surface", d);
    cmp_col(s, a.mesh_edges.loop, b.mesh_edges.loop, "mesh edge loop", d);
    cmp_col(s, a.mesh_edges.joint, b.mesh_edges.joint, "mesh edge joint", d);
    cmp_ragged(s, a.mesh_edges.halfedges, b.mesh_edges.halfedges, "mesh edge halfedge", d);
  }
  if (!d.found && live_sets_equal(a.mesh_loops.slots, b.mesh_loops.slots, "mesh loop", d)) {
    cmp_col(a.mesh_loops.slots, a.mesh_loops.surface, b.mesh_loops.surface, "mesh loop surface", d);
    cmp_ragged(a.mesh_loops.slots, a.mesh_loops.mesh_edges, b.mesh_loops.mesh_edges, "mesh loop", d);
  }
  if (!d.found && live_sets_equal(a.joints.slots, b.joints.slots, "joint", d))
    cmp_ragged(a.joints.slots, a.joints.members, b.joints.members, "joint member", d);
  if (!d.found && live_sets_equal(a.attrib_nodes.slots, b.attrib_nodes.slots, "attribute node", d)) {
    const auto& s = a.attrib_nodes.slots;
    cmp_col(s, a.attrib_nodes.kind, b.attrib_nodes.kind, "attribute node kind", d);
    cmp_col(s, a.attrib_nodes.element, b.attrib_nodes.element, "attribute node element", d);
    cmp_col(s, a.attrib_nodes.corner, b.attrib_nodes.corner, "attribute node corner", d);
    cmp_col(s, a.attrib_nodes.param, b.attrib_nodes.param, "attribute node param", d);
    cmp_col(s, a.attrib_nodes.position, b.attrib_nodes.position, "attribute node position", d);
    cmp_col(s, a.attrib_nodes.owner, b.attrib_nodes.owner, "attribute node owner", d);
  }
  if (!d.found && live_sets_equal(a.attrib_edges.slots, b.attrib_edges.slots, "attribute edge", d)) {
    const auto& s = a.attrib_edges.slots;
    cmp_col(s, a.attrib_edges.surface, b.attrib_edges.surface, "attribute edge surface", d);
    cmp_col(s, a.attrib_edges.feature_id, b.attrib_edges.feature_id, "attribute edge feature", d);
    cmp_ragged(s, a.attrib_edges.nodes, b.attrib_edges.nodes, "attribute edge node", d);
  }
  return d.out.str();
}

}  // namespace atelier
