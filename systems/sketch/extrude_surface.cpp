// The extruded part as its own MESHSURFACE (issue 21, beyond seed 002),
// joined to the base along B by MESHJOINTs, also where B runs along a seam
// that a joint already holds (the project top's right armhole runs 16 edges
// along the seam of its collar piece): the paper's joints are non-manifold
// (seed 000 section 3, Fig. 4: "each MESHJOINT has a collection of
// MESHEDGEs ... stored in a clockwise order by the right-hand rule", Fig. 17:
// three and more surfaces on one joint), so there the part's mesh edge
// becomes one more member of that joint: a seam of three surfaces.
//
// The part is known (the faces reached from B's part side without crossing
// B), so it is moved directly rather than through partition_along_curves,
// which refuses curves along existing mesh edges (its seams must be new).
#include <atelier/storage/topology.h>
#include <atelier/systems/sketch/extrude.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "extrude_detail.h"

namespace atelier::extrude_detail {

namespace {

/// Cuts mesh edge `me` at the chain positions `cuts` (0 < cut < its length,
/// sorted, unique) into consecutive mesh edges; when it is in a joint, every
/// member is cut at the same joint positions and the joint becomes one joint
/// per stretch (members in the same order, with the same direction flags),
/// so that corresponding nodes still coincide. A mesh loop holding a cut
/// mesh edge holds its pieces in its place, in chain order.
void cut_mesh_edge(Model& m, MeshEdgeIdx me, const std::vector<std::size_t>& cuts) {
  if (cuts.empty()) return;
  const JointIdx j = m.mesh_edges.joint[me.value];
  std::vector<JointMember> members;
  if (j.valid()) {
    const auto row = m.joints.members.row(j.value);
    members.assign(row.begin(), row.end());
  } else {
    members.push_back({me, true});
  }
  const std::size_t len = m.mesh_edges.halfedges.size(me.value);
  bool me_positive = true;
  for (const JointMember& jm : members)
    if (jm.mesh_edge == me) me_positive = jm.positive;
  // Stretch boundaries in the joint's direction.
  std::vector<std::size_t> at{0, len};
  for (std::size_t c : cuts) at.push_back(me_positive ? c : len - c);
  std::sort(at.begin(), at.end());
  const std::size_t stretches = at.size() - 1;
  if (j.valid()) m.delete_joint(j);
  std::vector<std::vector<JointMember>> joint_members(stretches);
  for (const JointMember& jm : members) {
    const auto row = m.mesh_edges.halfedges.row(jm.mesh_edge.value);
    const std::vector<HalfedgeIdx> chain(row.begin(), row.end());
    const SurfaceIdx s = m.mesh_edges.surface[jm.mesh_edge.value];
    const MeshLoopIdx loop = m.mesh_edges.loop[jm.mesh_edge.value];
    std::vector<MeshEdgeIdx> loop_list;
    if (loop.valid()) {
      const auto l = m.mesh_loops.mesh_edges.row(loop.value);
      loop_list.assign(l.begin(), l.end());
      m.delete_mesh_loop(loop);
    }
    m.delete_mesh_edge(jm.mesh_edge);
    std::vector<MeshEdgeIdx> pieces(stretches);  // by stretch
    for (std::size_t k = 0; k < stretches; ++k) {
      const std::size_t a = jm.positive ? at[k] : len - at[k + 1], b = jm.positive ? at[k + 1] : len - at[k];
      pieces[k] = m.new_mesh_edge(s, std::span<const HalfedgeIdx>(chain.data() + a, b - a));
      joint_members[k].push_back({pieces[k], jm.positive});
    }
    if (loop.valid()) {
      std::vector<MeshEdgeIdx> list;
      for (MeshEdgeIdx x : loop_list) {
        if (x != jm.mesh_edge) {
          list.push_back(x);
          continue;
        }
        if (jm.positive)
          list.insert(list.end(), pieces.begin(), pieces.end());
        else
          list.insert(list.end(), pieces.rbegin(), pieces.rend());
      }
      (void)m.new_mesh_loop(s, list);
    }
  }
  if (j.valid())
    for (const auto& mem : joint_members) (void)m.new_joint(mem);
}

/// Where member `jm`'s surface leaves the joint at its middle edge: the unit
/// direction from that edge towards the centroid of its face, across the
/// joint direction; and the joint direction there.
void member_side(const Model& m, const JointMember& jm, Vec3d& side, Vec3d& dir) {
  const auto chain = m.mesh_edges.halfedges.row(jm.mesh_edge.value);
  const std::size_t t = chain.size() / 2;
  const HalfedgeIdx h = chain[jm.positive ? t : chain.size() - 1 - t];
  const Vec3d a = m.position(m.tail(h)), b = m.position(m.head(h));
  dir = (jm.positive ? b - a : a - b).normalized();
  FaceIdx f = m.face(h);
  if (!f.valid()) f = m.face(twin(h));
  side = Vec3d::Zero();
  if (!f.valid()) return;
  Vec3d c = Vec3d::Zero();
  int k = 0;
  m.for_each_face_halfedge(f, [&](HalfedgeIdx g) { c += m.position(m.tail(g)), ++k; });
  c /= k;
  side = c - 0.5 * (a + b);
  side -= side.dot(dir) * dir;
  if (side.norm() > 0) side.normalize();
}

/// `add` joins joint j, placed among its members clockwise by the right-hand
/// rule about the joint direction (seed 000 Fig. 4): the members stay in
/// their order, starting from the first; the new one goes where its side's
/// angle, measured clockwise (looking against the joint direction) from the
/// first member's side, belongs.
void join_member(Model& m, JointIdx j, JointMember add) {
  const auto row = m.joints.members.row(j.value);
  std::vector<JointMember> mem(row.begin(), row.end());
  Vec3d s0, d;
  member_side(m, mem[0], s0, d);
  auto clockwise = [&](const JointMember& jm) {
    Vec3d s, dd;
    member_side(m, jm, s, dd);
    const double ccw = std::atan2(d.cross(s0).dot(s), s0.dot(s));  // about d, in (-pi, pi]
    const double cw = -ccw;
    return cw < 0 ? cw + 2 * M_PI : cw;  // [0, 2 pi)
  };
  const double a = clockwise(add);
  std::size_t at = mem.size();
  for (std::size_t k = 1; k < mem.size(); ++k)
    if (a < clockwise(mem[k])) {
      at = k;
      break;
    }
  mem.insert(mem.begin() + static_cast<std::ptrdiff_t>(at), add);
  m.joints.members.assign(j.value, mem);
  m.mesh_edges.joint[add.mesh_edge.value] = j;
  ++m.topology_version;
}

}  // namespace

Status split_off(Model& m, const std::vector<NodeIdx>& B, bool ring, ExtrudeReport& rep, const ExecContext& ctx) {
  const std::size_t n = B.size(), segs = ring ? n : n - 1;
  const SurfaceIdx s = m.nodes.surface[B[0].value];
  // B's halfedges on the part's side: B[i] -> B[i+1] (the side that had no
  // face before sewing), the base's face on their twins.
  std::vector<HalfedgeIdx> hb(segs);
  std::vector<char> on_b(m.edges.slots.capacity(), 0);
  for (std::size_t i = 0; i < segs; ++i) {
    hb[i] = m.find_halfedge(B[i], B[(i + 1) % n]);
    if (!hb[i].valid() || !m.face(hb[i]).valid() || !m.face(twin(hb[i])).valid())
      return fail(ErrorCode::kInternal,
                  "as a surface: edge " + std::to_string(i) + " of B does not lie between the part and the base");
    on_b[edge_of(hb[i]).value] = 1;
  }
  // The part: the faces reached from B's part side without crossing B.
  std::vector<char> in_part(m.faces.slots.capacity(), 0);
  std::vector<FaceIdx> part, stack{m.face(hb[0])};
  in_part[stack[0].value] = 1;
  while (!stack.empty()) {
    const FaceIdx f = stack.back();
    stack.pop_back();
    part.push_back(f);
    m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
      if (on_b[edge_of(h).value]) return;
      const FaceIdx g = m.face(twin(h));
      if (g.valid() && !in_part[g.value]) in_part[g.value] = 1, stack.push_back(g);
    });
  }
  std::sort(part.begin(), part.end());
  for (std::size_t i = 0; i < segs; ++i)
    if (!in_part[m.face(hb[i]).value] || in_part[m.face(twin(hb[i])).value])
      return fail(ErrorCode::kInternal,
                  "as a surface: B does not separate the part from the base at its edge " + std::to_string(i));
  // The part's own elements: no mesh edge off B, no attribute node (the
  // part is new; the painted base curve lies on B's nodes and edges, which
  // stay with the base).
  std::vector<char> part_node(m.nodes.slots.capacity(), 0);
  std::vector<EdgeIdx> part_edges;
  std::vector<NodeIdx> fn;
  for (FaceIdx f : part) {
    m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
      part_node[m.tail(h).value] = 1;
      if (!on_b[edge_of(h).value]) part_edges.push_back(edge_of(h));
    });
  }
  std::sort(part_edges.begin(), part_edges.end());
  part_edges.erase(std::unique(part_edges.begin(), part_edges.end()), part_edges.end());
  for (EdgeIdx e : part_edges)
    if (m.edges.mesh_edge[e.value].valid())
      return fail(ErrorCode::kUnsupported, "as a surface: edge " + std::to_string(e.value) +
                                               " of the part is on mesh edge " +
                                               std::to_string(m.edges.mesh_edge[e.value].value));
  for (std::uint32_t a = 0; a < m.attrib_nodes.slots.capacity(); ++a) {
    if (!m.alive(AttribNodeIdx{a})) continue;
    const std::uint32_t el = m.attrib_nodes.element[a];
    const AttribNodeKind k = m.attrib_nodes.kind[a];
    const bool on_part = k == AttribNodeKind::kFace ? el < in_part.size() && in_part[el]
                         : k == AttribNodeKind::kEdge
                             ? std::binary_search(part_edges.begin(), part_edges.end(), edge_of(HalfedgeIdx{el}))
                             : false;
    if (on_part)
      return fail(ErrorCode::kUnsupported, "as a surface: attribute node " + std::to_string(a) + " lies on the part");
  }
  if (ctx.cancelled()) return fail(ErrorCode::kCancelled, "cancelled");

  // Mesh edges already on B (a seam to another surface, or a boundary mesh
  // edge): the base's side of each stretch of B along one of them must be
  // a mesh edge of its own, so the one it lies on is cut at the stretch's
  // ends (with its joint's partners, cut_mesh_edge).
  {
    std::set<MeshEdgeIdx> along;
    for (std::size_t i = 0; i < segs; ++i)
      if (const MeshEdgeIdx me = m.edges.mesh_edge[edge_of(hb[i]).value]; me.valid()) along.insert(me);
    for (MeshEdgeIdx me : along) {
      if (!m.alive(me)) continue;  // cut with a partner on B before
      const auto chain = m.mesh_edges.halfedges.row(me.value);
      std::vector<std::size_t> pos;
      for (std::size_t k = 0; k < chain.size(); ++k)
        if (on_b[edge_of(chain[k]).value]) pos.push_back(k);
      if (pos.back() - pos.front() + 1 != pos.size())
        return fail(ErrorCode::kJointRefused,
                    "as a surface: B runs along mesh edge " + std::to_string(me.value) + " in several stretches");
      std::vector<std::size_t> cuts;
      if (pos.front() > 0) cuts.push_back(pos.front());
      if (pos.back() + 1 < chain.size()) cuts.push_back(pos.back() + 1);
      cut_mesh_edge(m, me, cuts);
    }
  }

  // The part's surface, named as partition_along_curves names its pieces.
  std::set<std::string> used;
  for (std::uint32_t k = 0; k < m.surfaces.slots.capacity(); ++k)
    if (m.alive(SurfaceIdx{k})) used.insert(m.surfaces.name[k]);
  std::string name;
  for (int k = 1; name.empty() || used.count(name); ++k) name = m.surfaces.name[s.value] + "." + std::to_string(k);
  const Surface ns = m.add_surface(name);
  m.surfaces.flags[ns.idx.value] = m.surfaces.flags[s.value];

  // Move the part: its faces are made again in the new surface on the same
  // node cycles; the nodes only the part uses change surface (keeping their
  // index), the others (B's) are duplicated there.
  struct OldFace {
    std::vector<NodeIdx> nodes;
    std::vector<std::uint8_t> edge_flags;
    std::uint8_t flags;
  };
  std::vector<OldFace> old;
  for (FaceIdx f : part) {
    OldFace o{{}, {}, m.faces.flags[f.value]};
    m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
      o.nodes.push_back(m.tail(h));
      o.edge_flags.push_back(m.edges.flags[edge_of(h).value]);
    });
    old.push_back(std::move(o));
  }
  for (FaceIdx f : part) m.delete_face(f);
  for (EdgeIdx e : part_edges)
    if (m.is_wire(e)) m.delete_edge(e);
  std::vector<NodeIdx> to(m.nodes.slots.capacity());
  for (std::uint32_t v = 0; v < part_node.size(); ++v) {
    if (!part_node[v]) continue;
    if (m.is_isolated(NodeIdx{v})) {
      m.nodes.surface[v] = ns.idx;  // isolated: no edge or face refers to its surface
      to[v] = NodeIdx{v};
    } else {
      to[v] = m.new_node(ns.idx, m.position(NodeIdx{v}));
      m.nodes.uv[to[v].value] = m.nodes.uv[v];
      m.nodes.position_backup[to[v].value] = m.nodes.position_backup[v];
    }
  }
  std::vector<HalfedgeIdx> cyc;
  for (const OldFace& o : old) {
    cyc.clear();
    for (std::size_t k = 0; k < o.nodes.size(); ++k) {
      const NodeIdx a = to[o.nodes[k].value], b = to[o.nodes[(k + 1) % o.nodes.size()].value];
      HalfedgeIdx h = m.find_halfedge(a, b);
      if (!h.valid()) {
        const EdgeIdx e = m.new_edge(a, b);
        m.edges.flags[e.value] = o.edge_flags[k];
        h = halfedge_of(e, 0);
      }
      cyc.push_back(h);
    }
    const FaceIdx nf = m.new_face(ns.idx, cyc);
    m.faces.flags[nf.value] = o.flags;
  }

  // Joints along B, one per stretch of B on one mesh edge of the base (or
  // on none): the part's mesh edge runs along B (B'[i] -> B'[i+1], its
  // faces' side); a new joint holds it (positive) and the base's (its
  // faces' side, against B: negative), as partition_along_curves joins its
  // pieces; on a mesh edge already in a joint it joins that joint.
  auto me_of = [&](std::size_t i) { return m.edges.mesh_edge[edge_of(hb[i]).value]; };
  std::size_t start = 0;
  if (ring)
    for (std::size_t i = 0; i < segs; ++i)
      if (me_of(i) != me_of((i + segs - 1) % segs)) {
        start = i;
        break;
      }
  rep.joints.clear();
  for (std::size_t done = 0; done < segs;) {
    const std::size_t i0 = (start + done) % segs;
    const MeshEdgeIdx me = me_of(i0);
    std::size_t len = 1;
    while (done + len < segs && me_of((i0 + len) % segs) == me) ++len;
    std::vector<HalfedgeIdx> pc, bc;
    for (std::size_t k = 0; k < len; ++k) {
      const std::size_t i = (i0 + k) % segs;
      pc.push_back(m.find_halfedge(to[B[i].value], to[B[(i + 1) % n].value]));
      bc.push_back(twin(hb[(i0 + len - 1 - k) % segs]));
    }
    const MeshEdgeIdx pm = m.new_mesh_edge(ns.idx, pc);
    if (!me.valid()) {
      const MeshEdgeIdx bm = m.new_mesh_edge(s, bc);
      const JointMember mem[2] = {{pm, true}, {bm, false}};
      rep.joints.push_back(m.handle(m.new_joint(mem)));
    } else {
      // The base's mesh edge is this stretch now (cut above); its chain runs
      // along B or against it.
      const auto chain = m.mesh_edges.halfedges.row(me.value);
      if (chain.size() != len)
        return fail(ErrorCode::kInternal,
                    "as a surface: mesh edge " + std::to_string(me.value) + " is not B's stretch after the cut");
      const bool along_b = m.tail(chain[0]) == B[i0];
      const JointIdx j = m.mesh_edges.joint[me.value];
      if (!j.valid()) {
        const JointMember mem[2] = {{pm, true}, {me, !along_b}};
        rep.joints.push_back(m.handle(m.new_joint(mem)));
      } else {
        bool flag = true;
        for (const JointMember& jm : m.joints.members.row(j.value))
          if (jm.mesh_edge == me) flag = jm.positive;
        join_member(m, j, {pm, flag == along_b});
        rep.joints.push_back(m.handle(j));
      }
    }
    done += len;
  }
  rep.part_surface = ns.idx;
  m.complex_holes = count_topology(m).implied_holes();
  return {};
}

}  // namespace atelier::extrude_detail
