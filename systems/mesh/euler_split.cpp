// Edge split and merge (systems/mesh/euler.h): split_edge, its inverse
// merge_edge, and the unchecked building blocks shared with
// systems/mesh/edit.cpp (euler_detail::split_edge_raw, relocate_face_node,
// restore_attribs). Attribute nodes on the split or merged edges and in
// their faces move with the geometry (seed 001 Fig. 6b).
#include <atelier/systems/mesh/euler.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <atelier/engine/status_format.h>
#include <atelier/storage/mesh_edge_chain.h>

#include "euler_detail.h"

namespace atelier {

namespace {

using euler_detail::node_has_attrib;
using euler_detail::node_record;

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
  chain_split_edge(m, h, gs);
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
