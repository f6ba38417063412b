#include <atelier/engine/status_format.h>
#include <atelier/systems/mesh/edit.h>
#include <atelier/systems/mesh/euler.h>

#include <algorithm>
#include <sstream>

namespace atelier {

namespace {

bool contains(std::span<const FaceIdx> set, FaceIdx f) {
  return std::find(set.begin(), set.end(), f) != set.end();
}

/// Refuses when a ring node lies in one of `faces` (one scan of the node table).
Status check_no_rings(const Model& m, std::span<const FaceIdx> faces, const EditOptions& opt) {
  if (!opt.check_ring_nodes) return {};
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
    const FaceIdx f = m.nodes.in_face[v];
    if (f.valid() && m.nodes.slots.alive(NodeIdx{v}) && contains(faces, f))
      return status_of(ErrorCode::kTopology, "face ", f.value, " holds ring node ", v, " (kill it first)");
  }
  return {};
}

/// Face-nodes of faces about to be replaced, with their 3D surface
/// positions, re-attached to the new faces afterwards.
struct Carry {
  std::vector<std::pair<AttribNodeIdx, Vec3d>> nodes;
  void take_faces(const Model& m, std::span<const FaceIdx> faces) {
    const auto& an = m.attrib_nodes;
    if (an.slots.empty()) return;
    for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
      if (an.slots.alive(AttribNodeIdx{i}) && an.kind[i] == AttribNodeKind::kFace &&
          contains(faces, FaceIdx{an.element[i]}))
        nodes.emplace_back(AttribNodeIdx{i}, m.attrib_position_on_surface(AttribNodeIdx{i}));
  }
  void take_edge(const Model& m, EdgeIdx e) {
    const auto& an = m.attrib_nodes;
    if (an.slots.empty()) return;
    for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
      if (an.slots.alive(AttribNodeIdx{i}) && an.kind[i] == AttribNodeKind::kEdge &&
          edge_of(HalfedgeIdx{an.element[i]}) == e)
        nodes.emplace_back(AttribNodeIdx{i}, m.attrib_position_on_surface(AttribNodeIdx{i}));
  }
  void place(Model& m, std::span<const FaceIdx> candidates) {
    for (const auto& [a, w] : nodes) euler_detail::relocate_face_node(m, a, w, candidates);
    nodes.clear();
  }
};

std::uint32_t face_degree3(const Model& m, FaceIdx f) {
  // Face degree, stopping early: only "3 or more than 3" matters.
  std::uint32_t n = 0;
  HalfedgeIdx h = m.faces.halfedge[f.value];
  const HalfedgeIdx s = h;
  do {
    ++n;
    h = m.next(h);
  } while (h != s && n < 4);
  return n;
}

/// Cuts the quad f (a triangle that gained corner v) into two triangles with
/// a new edge from v to the opposite corner. Returns the two faces.
std::array<FaceIdx, 2> cut_quad(Model& m, FaceIdx f, NodeIdx v) {
  HalfedgeIdx x = m.faces.halfedge[f.value];
  while (m.tail(x) != v) x = m.next(x);
  const HalfedgeIdx y = m.next(x), z = m.next(y), w = m.next(z);  // v->b, b->c, c->a, a->v
  const NodeIdx c = m.tail(z);
  const std::uint8_t flags = m.faces.flags[f.value];
  Carry carry;
  carry.take_faces(m, std::span<const FaceIdx>(&f, 1));
  m.delete_face(f);
  const EdgeIdx d = m.new_edge(v, c);
  const HalfedgeIdx vc = halfedge_of(d, 0), cv = halfedge_of(d, 1);
  const SurfaceIdx s = m.nodes.surface[v.value];
  const HalfedgeIdx c1[3] = {x, y, cv};
  const HalfedgeIdx c2[3] = {vc, z, w};
  const FaceIdx f1 = m.new_face(s, c1), f2 = m.new_face(s, c2);
  m.faces.flags[f1.value] = m.faces.flags[f2.value] = flags;
  const std::array<FaceIdx, 2> out{f1, f2};
  carry.place(m, out);
  return out;
}

/// Splits the edge of h at p and re-triangulates its triangles except `skip`.
NodeIdx split_one(Model& m, HalfedgeIdx h, const Vec3d& p, FaceIdx skip) {
  const FaceIdx fh = m.face(h), ft = m.face(twin(h));
  const bool tri_h = fh.valid() && face_degree3(m, fh) == 3;
  const bool tri_t = ft.valid() && face_degree3(m, ft) == 3;
  const auto raw = euler_detail::split_edge_raw(m, h, p, true, nullptr);
  if (tri_h && fh != skip) (void)cut_quad(m, fh, raw.node);
  if (tri_t && ft != skip) (void)cut_quad(m, ft, raw.node);
  return raw.node;
}

bool node_on_mesh_edge(const Model& m, NodeIdx v, JointIdx* joint = nullptr) {
  bool on = false;
  m.for_each_outgoing(v, [&](HalfedgeIdx x) {
    const MeshEdgeIdx me = m.edges.mesh_edge[edge_of(x).value];
    if (!me.valid()) return;
    on = true;
    if (joint && m.mesh_edges.joint[me.value].valid()) *joint = m.mesh_edges.joint[me.value];
  });
  return on;
}

bool node_on_boundary(const Model& m, NodeIdx v) {
  bool b = false;
  m.for_each_outgoing(v, [&](HalfedgeIdx x) { b |= !m.face(x).valid() || !m.face(twin(x)).valid(); });
  return b;
}

/// Collapse checks for h = a -> b (a kept, b removed).
Status collapse_ok(const Model& m, HalfedgeIdx h) {
  const HalfedgeIdx t = twin(h);
  const EdgeIdx e = edge_of(h);
  const NodeIdx a = m.tail(h), b = m.head(h);
  const FaceIdx fl = m.face(h), fr = m.face(t);
  if (!fl.valid() && !fr.valid()) return status_of(ErrorCode::kTopology, "edge ", e.value, " is a wire edge (no face)");
  if (fl.valid() && fr.valid() && node_on_boundary(m, a) && node_on_boundary(m, b))
    return status_of(ErrorCode::kTopology, "collapsing interior edge ", e.value, " would pinch the boundary at nodes ",
                     a.value, " and ", b.value);
  NodeIdx opp[2];
  const HalfedgeIdx sides[2] = {h, t};
  for (int s = 0; s < 2; ++s) {
    const FaceIdx f = m.face(sides[s]);
    if (!f.valid() || face_degree3(m, f) != 3) continue;
    const HalfedgeIdx x1 = m.next(sides[s]), x2 = m.next(x1);
    opp[s] = m.head(x1);
    const FaceIdx g1 = m.face(twin(x1)), g2 = m.face(twin(x2));
    if (!g1.valid() && !g2.valid())
      return status_of(ErrorCode::kDegenerate, "collapsing edge ", e.value, " would leave a dangling edge of face ",
                       f.value);
    if (g1.valid() && g1 == g2)
      return status_of(ErrorCode::kDegenerate, "collapsing edge ", e.value, " would fold face ", g1.value);
    if (m.edges.mesh_edge[edge_of(x1).value].valid() && m.edges.mesh_edge[edge_of(x2).value].valid())
      return status_of(ErrorCode::kTopology, "collapsing edge ", e.value, " would merge two mesh edge edges of face ",
                       f.value);
    if (!node_on_boundary(m, opp[s]) && m.degree(opp[s]) <= 3)
      return status_of(ErrorCode::kDegenerate, "collapsing edge ", e.value, " would leave node ", opp[s].value,
                       " with valence 2");
  }
  if (opp[0].valid() && opp[0] == opp[1])
    return status_of(ErrorCode::kDegenerate, "both faces of edge ", e.value, " have the same opposite node");
  // Link condition: every common neighbour of a and b is opposite e in a triangle.
  std::vector<NodeIdx> na;
  m.for_each_outgoing(a, [&](HalfedgeIdx x) { na.push_back(m.head(x)); });
  Status st;
  m.for_each_outgoing(b, [&](HalfedgeIdx x) {
    const NodeIdx w = m.head(x);
    if (!st.is_ok()) return;
    if (w != opp[0] && w != opp[1] && std::find(na.begin(), na.end(), w) != na.end())
      st = status_of(ErrorCode::kTopology, "link condition fails for edge ", e.value, ": node ", w.value,
                     " neighbours both ends (collapse would make parallel edges)");
  });
  if (!st) return st;
  // A polygon around b (other than the faces of e) that also has corner a
  // would visit the kept node twice.
  std::vector<NodeIdx> corners;
  m.for_each_outgoing(b, [&](HalfedgeIdx x) {
    const FaceIdx f = m.face(x);
    if (!st || !f.valid() || f == fl || f == fr || face_degree3(m, f) == 3) return;
    m.face_nodes(f, corners);
    if (std::find(corners.begin(), corners.end(), a) != corners.end())
      st = status_of(ErrorCode::kTopology, "collapsing edge ", e.value, " would make face ", f.value, " visit node ",
                     a.value, " twice");
  });
  return st;
}

/// Collapses h = a -> b into a (at p). Preconditions: collapse_ok.
void collapse_one(Model& m, HalfedgeIdx h, const Vec3d& p) {
  const HalfedgeIdx t = twin(h);
  const EdgeIdx e = edge_of(h);
  const NodeIdx a = m.tail(h), b = m.head(h);
  auto& an = m.attrib_nodes;
  const bool has_attr = !an.slots.empty();
  Carry carry;
  std::vector<FaceIdx> kept_faces;

  for (HalfedgeIdx x : {h, t}) {
    const FaceIdx f = m.face(x);
    if (!f.valid()) continue;
    if (face_degree3(m, f) == 3) {
      const HalfedgeIdx x1 = m.next(x), x2 = m.next(x1);
      // The edge touching b goes unless only it is on a mesh edge.
      const HalfedgeIdx b_side = m.tail(x1) == b ? x1 : x2;
      const HalfedgeIdx a_side = b_side == x1 ? x2 : x1;
      const bool keep_b = m.edges.mesh_edge[edge_of(b_side).value].valid();
      const HalfedgeIdx kin = keep_b ? b_side : a_side, rin = keep_b ? a_side : b_side, rout = twin(rin);
      const EdgeIdx ke = edge_of(kin), re = edge_of(rin);
      carry.take_faces(m, std::span<const FaceIdx>(&f, 1));
      m.delete_face(f);
      if (const FaceIdx g = edit_detail::hand_over_side(m, rout, kin); g.valid()) kept_faces.push_back(g);
      if (const MeshEdgeIdx me = m.edges.mesh_edge[re.value]; me.valid()) {
        for (HalfedgeIdx& c : m.mesh_edges.halfedges.row_mut(me.value))
          if (c == rout)
            c = kin;
          else if (c == rin)
            c = twin(kin);
        m.edges.mesh_edge[ke.value] = me;
      }
      m.edges.flags[ke.value] |= m.edges.flags[re.value];
      if (has_attr)
        for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
          if (an.slots.alive(AttribNodeIdx{i}) && an.kind[i] == AttribNodeKind::kEdge) {
            if (an.element[i] == rout.value)
              an.element[i] = kin.value;
            else if (an.element[i] == rin.value)
              an.element[i] = twin(kin).value;
          }
      m.delete_edge(re);
    } else {
      m.link_face(m.prev(x), m.next(x));
      if (m.faces.halfedge[f.value] == x) m.faces.halfedge[f.value] = m.next(x);
      m.halfedges.face[x.value] = {};
      m.halfedges.next[x.value] = m.halfedges.prev[x.value] = {};
      kept_faces.push_back(f);
    }
  }
  if (const MeshEdgeIdx me = m.edges.mesh_edge[e.value]; me.valid()) {
    auto row = m.mesh_edges.halfedges.row(me.value);
    for (std::size_t k = 0; k < row.size(); ++k)
      if (edge_of(row[k]) == e) {
        m.mesh_edges.halfedges.erase(me.value, k);
        break;
      }
  }
  if (has_attr)  // the collapsed edge's attribute nodes now sit on the kept node
    for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
      if (an.slots.alive(AttribNodeIdx{i}) &&
          ((an.kind[i] == AttribNodeKind::kEdge && edge_of(HalfedgeIdx{an.element[i]}) == e) ||
           (an.kind[i] == AttribNodeKind::kVertex && an.element[i] == b.value))) {
        an.kind[i] = AttribNodeKind::kVertex;
        an.element[i] = a.value;
        an.param[i] = Vec3d::Zero();
        an.corner[i] = 0;
      }
  m.delete_edge(e);
  std::vector<HalfedgeIdx> out;
  m.outgoing(b, out);
  for (HalfedgeIdx x : out) m.set_tail(x, a);
  m.delete_node(b);
  m.nodes.position[a.value] = p;
  ++m.geometry_version;
  if (!carry.nodes.empty()) {
    m.for_each_outgoing(a, [&](HalfedgeIdx x) {
      if (m.face(x).valid()) kept_faces.push_back(m.face(x));
    });
    carry.place(m, kept_faces);
  }
}

}  // namespace

FaceIdx edit_detail::hand_over_side(Model& m, HalfedgeIdx rout, HalfedgeIdx kin) {
  const FaceIdx g = m.face(rout);
  if (!g.valid()) return g;
  m.halfedges.face[kin.value] = g;
  m.link_face(m.prev(rout), kin);
  m.link_face(kin, m.next(rout));
  if (m.faces.halfedge[g.value] == rout) m.faces.halfedge[g.value] = kin;
  m.halfedges.face[rout.value] = {};
  m.halfedges.next[rout.value] = m.halfedges.prev[rout.value] = {};
  return g;
}

std::vector<HalfedgeIdx> joint_corresponding_halfedges(const Model& m, HalfedgeIdx h) {
  std::vector<HalfedgeIdx> out{h};
  const MeshEdgeIdx me = m.edges.mesh_edge[edge_of(h).value];
  if (!me.valid()) return out;
  const JointIdx j = m.mesh_edges.joint[me.value];
  if (!j.valid()) return out;
  auto chain = m.mesh_edges.halfedges.row(me.value);
  const std::size_t len = chain.size();
  std::size_t k = 0;
  while (k < len && edge_of(chain[k]) != edge_of(h)) ++k;
  auto members = m.joints.members.row(j.value);
  bool pos_me = true;
  for (const JointMember& x : members)
    if (x.mesh_edge == me) pos_me = x.positive;
  // Segment index along the joint direction, and whether h runs along it
  // (seed 001 section 3: a negative member runs against the joint).
  const std::size_t seg = pos_me ? k : len - 1 - k;
  const bool h_along = (chain[k] == h) == pos_me;
  for (const JointMember& x : members) {
    if (x.mesh_edge == me) continue;
    auto c = m.mesh_edges.halfedges.row(x.mesh_edge.value);
    const HalfedgeIdx cn = c[x.positive ? seg : len - 1 - seg];
    out.push_back(x.positive == h_along ? cn : twin(cn));
  }
  return out;
}

Expected<EdgeSplitResult> edge_split(Model& m, Edge eh, const Vec3d& position, const EditOptions& opt) {
  if (auto r = m.resolve(eh); !r) return r.status();
  if (!position.allFinite())
    return status_of(ErrorCode::kDegenerate, "non-finite split position on edge ", eh.idx.value);
  const auto hs = joint_corresponding_halfedges(m, halfedge_of(eh.idx, 0));
  if (opt.check_ring_nodes) {
    std::vector<FaceIdx> faces;
    for (HalfedgeIdx h : hs)
      for (HalfedgeIdx x : {h, twin(h)})
        if (m.face(x).valid()) faces.push_back(m.face(x));
    if (Status s = check_no_rings(m, faces, opt); !s) return s;
  }
  EdgeSplitResult r;
  for (HalfedgeIdx h : hs) r.nodes.push_back(m.handle(split_one(m, h, position, FaceIdx{})));
  return r;
}

Expected<EdgeCollapseResult> edge_collapse(Model& m, Edge eh, const Vec3d& position, const EditOptions& opt) {
  if (auto r = m.resolve(eh); !r) return r.status();
  if (!position.allFinite())
    return status_of(ErrorCode::kDegenerate, "non-finite position for collapsing edge ", eh.idx.value);
  const EdgeIdx e = eh.idx;
  HalfedgeIdx h = halfedge_of(e, 0);
  Vec3d pos = position;
  std::vector<HalfedgeIdx> hs;
  if (const MeshEdgeIdx me = m.edges.mesh_edge[e.value]; me.valid()) {
    if (m.mesh_edges.halfedges.size(me.value) < 2)
      return status_of(ErrorCode::kTopology, "edge ", e.value, " is the only edge of mesh edge ", me.value);
    hs = joint_corresponding_halfedges(m, h);
  } else {
    const bool a_on = node_on_mesh_edge(m, m.tail(h)), b_on = node_on_mesh_edge(m, m.head(h));
    if (a_on && b_on)
      return status_of(ErrorCode::kTopology, "both ends of edge ", e.value,
                       " lie on mesh edges that do not hold it: collapsing would pinch them");
    if (b_on) h = twin(h);
    JointIdx j;
    if (node_on_mesh_edge(m, m.tail(h), &j) && j.valid()) pos = m.position(m.tail(h));
    hs = {h};
  }
  std::vector<FaceIdx> faces;
  for (HalfedgeIdx x : hs) {
    if (Status s = collapse_ok(m, x); !s) return s;
    for (HalfedgeIdx y : {x, twin(x)})
      if (m.face(y).valid()) faces.push_back(m.face(y));
  }
  if (Status s = check_no_rings(m, faces, opt); !s) return s;
  EdgeCollapseResult r;
  for (HalfedgeIdx x : hs) {
    if (!m.alive(x)) return status_of(ErrorCode::kInternal, "joint member edge vanished during collapse");
    const NodeIdx a = m.tail(x);
    collapse_one(m, x, pos);
    r.kept.push_back(m.handle(a));
  }
  return r;
}

Expected<Edge> edge_swap(Model& m, Edge eh, const EditOptions& opt) {
  if (auto r = m.resolve(eh); !r) return r.status();
  const EdgeIdx e = eh.idx;
  if (const MeshEdgeIdx me = m.edges.mesh_edge[e.value]; me.valid()) {
    if (m.mesh_edges.joint[me.value].valid())
      return status_of(ErrorCode::kJointRefused, "edge ", e.value, " is on mesh edge ", me.value, " of joint ",
                       m.mesh_edges.joint[me.value].value, ": swapping is not allowed (seed 000 section 3)");
    return status_of(ErrorCode::kTopology, "edge ", e.value, " is on mesh edge ", me.value,
                     ": swapping would break the chain");
  }
  const HalfedgeIdx h = halfedge_of(e, 0), t = halfedge_of(e, 1);
  const FaceIdx f0 = m.face(h), f1 = m.face(t);
  if (!f0.valid() || !f1.valid()) return status_of(ErrorCode::kTopology, "edge ", e.value, " is not interior");
  if (face_degree3(m, f0) != 3 || face_degree3(m, f1) != 3)
    return status_of(ErrorCode::kUnsupported, "edge swap needs two triangles at edge ", e.value);
  const HalfedgeIdx h1 = m.next(h), h2 = m.next(h1), t1 = m.next(t), t2 = m.next(t1);
  const NodeIdx c = m.head(h1), d = m.head(t1);
  if (c == d) return status_of(ErrorCode::kDegenerate, "both faces of edge ", e.value, " have the same opposite node");
  if (m.find_halfedge(c, d).valid())
    return status_of(ErrorCode::kTopology, "nodes ", c.value, " and ", d.value, " are already joined: swapping edge ",
                     e.value, " would make parallel edges");
  const FaceIdx fs[2] = {f0, f1};
  if (Status s = check_no_rings(m, fs, opt); !s) return s;
  Carry carry;
  carry.take_faces(m, fs);
  carry.take_edge(m, e);
  const SurfaceIdx s = m.faces.surface[f0.value];
  const std::uint8_t fl0 = m.faces.flags[f0.value], fl1 = m.faces.flags[f1.value];
  // Table 3: kill_face_make_Chole x2, kill_edge_Chole, make_edge_Chole, make_face_kill_Chole x2.
  m.delete_face(f1);
  m.delete_face(f0);
  m.delete_edge(e);
  const EdgeIdx n = m.new_edge(c, d);
  const HalfedgeIdx a0[3] = {halfedge_of(n, 0), t2, h1};  // c->d, d->b, b->c
  const HalfedgeIdx a1[3] = {halfedge_of(n, 1), h2, t1};  // d->c, c->a, a->d
  const FaceIdx g0 = m.new_face(s, a0), g1 = m.new_face(s, a1);
  m.faces.flags[g0.value] = fl0;
  m.faces.flags[g1.value] = fl1;
  const FaceIdx gs[2] = {g0, g1};
  carry.place(m, gs);
  return m.handle(n);
}

Expected<FaceSplitResult> face_split_1to4(Model& m, Face fh, const EditOptions& opt) {
  if (auto r = m.resolve(fh); !r) return r.status();
  const FaceIdx f = fh.idx;
  std::vector<HalfedgeIdx> hs;
  m.face_halfedges(f, hs);
  if (hs.size() != 3)
    return status_of(ErrorCode::kUnsupported, "face ", f.value, " has ", hs.size(),
                     " sides (1-to-4 split needs a triangle)");
  // All halfedges to split, for the ring check.
  std::array<std::vector<HalfedgeIdx>, 3> corr;
  std::vector<FaceIdx> faces{f};
  for (int i = 0; i < 3; ++i) {
    corr[i] = joint_corresponding_halfedges(m, hs[i]);
    for (std::size_t k = 0; k < corr[i].size(); ++k)
      for (HalfedgeIdx x : {corr[i][k], twin(corr[i][k])})
        if (m.face(x).valid() && (corr[i].size() > 1 || m.face(x) == f)) faces.push_back(m.face(x));
  }
  if (Status s = check_no_rings(m, faces, opt); !s) return s;
  std::array<Vec3d, 3> mid;
  for (int i = 0; i < 3; ++i) mid[i] = 0.5 * (m.position(m.tail(hs[i])) + m.position(m.head(hs[i])));
  FaceSplitResult r;
  std::array<NodeIdx, 3> mn;
  for (int i = 0; i < 3; ++i) {
    if (corr[i].size() > 1) {
      // Joint edge: every member gets the midpoint; their faces other than f
      // are re-triangulated (seed 000 section 3, face split).
      for (HalfedgeIdx x : corr[i]) {
        const NodeIdx v = split_one(m, x, mid[i], f);
        if (x == hs[i]) mn[i] = v;
      }
    } else {
      mn[i] = euler_detail::split_edge_raw(m, hs[i], mid[i], true, nullptr).node;
    }
  }
  // f is now the hexagon h0 g0 h1 g1 h2 g2 (g_i = m_i -> c_{i+1}).
  std::array<HalfedgeIdx, 3> g;
  for (int i = 0; i < 3; ++i) g[i] = m.next(hs[i]);
  const std::uint8_t flags = m.faces.flags[f.value];
  const SurfaceIdx s = m.faces.surface[f.value];
  Carry carry;
  carry.take_faces(m, std::span<const FaceIdx>(&f, 1));
  m.delete_face(f);
  const EdgeIdx x0 = m.new_edge(mn[0], mn[2]), x1 = m.new_edge(mn[1], mn[0]), x2 = m.new_edge(mn[2], mn[1]);
  const HalfedgeIdx c0[3] = {hs[0], halfedge_of(x0, 0), g[2]};
  const HalfedgeIdx c1[3] = {g[0], hs[1], halfedge_of(x1, 0)};
  const HalfedgeIdx c2[3] = {g[1], hs[2], halfedge_of(x2, 0)};
  const HalfedgeIdx cc[3] = {halfedge_of(x1, 1), halfedge_of(x2, 1), halfedge_of(x0, 1)};
  std::array<FaceIdx, 4> nf{m.new_face(s, c0), m.new_face(s, c1), m.new_face(s, c2), m.new_face(s, cc)};
  for (FaceIdx x : nf) m.faces.flags[x.value] = flags;
  carry.place(m, nf);
  for (int i = 0; i < 4; ++i) r.faces[i] = m.handle(nf[i]);
  for (int i = 0; i < 3; ++i) r.midpoints[i] = m.handle(mn[i]);
  return r;
}

}  // namespace atelier
