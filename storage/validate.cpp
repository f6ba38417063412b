#include <atelier/storage/validate.h>

#include <sstream>
#include <vector>

#include <atelier/storage/topology.h>

namespace atelier {

namespace {

class Checker {
 public:
  explicit Checker(const Model& m) : m_(m) {}
  template <class... A>
  Status fail(const A&... parts) {
    std::ostringstream s;
    (s << ... << parts);
    return {ErrorCode::kTopology, s.str()};
  }
  const Model& m_;
};

#define CHECK_OR(cond, ...) \
  do {                      \
    if (!(cond)) return c.fail(__VA_ARGS__); \
  } while (0)

Status check_sizes(const Model& m, Checker& c) {
  const std::size_t nn = m.nodes.slots.capacity(), ne = m.edges.slots.capacity(), nf = m.faces.slots.capacity();
  CHECK_OR(m.nodes.position.size() == nn && m.nodes.out.size() == nn && m.nodes.surface.size() == nn &&
               m.nodes.in_face.size() == nn && m.nodes.uv.size() == nn && m.nodes.position_backup.size() == nn,
           "node columns do not match the node table capacity ", nn);
  CHECK_OR(m.halfedges.tail.size() == 2 * ne && m.halfedges.face.size() == 2 * ne && m.halfedges.next.size() == 2 * ne &&
               m.halfedges.prev.size() == 2 * ne && m.halfedges.vnext.size() == 2 * ne &&
               m.halfedges.vprev.size() == 2 * ne && m.edges.flags.size() == ne && m.edges.mesh_edge.size() == ne,
           "edge/halfedge columns do not match the edge table capacity ", ne);
  CHECK_OR(m.faces.halfedge.size() == nf && m.faces.surface.size() == nf, "face columns do not match capacity ", nf);
  return {};
}

Status check_nodes_and_edges(const Model& m, Checker& c) {
  const std::size_t nn = m.nodes.slots.capacity(), ne = m.edges.slots.capacity();
  std::vector<std::uint32_t> out_count(nn, 0);
  for (std::uint32_t e = 0; e < ne; ++e) {
    const EdgeIdx ei{e};
    if (!m.alive(ei)) continue;
    const HalfedgeIdx h0 = halfedge_of(ei, 0), h1 = halfedge_of(ei, 1);
    const NodeIdx a = m.tail(h0), b = m.tail(h1);
    CHECK_OR(m.alive(a) && m.alive(b), "edge ", e, " has a dead end node");
    CHECK_OR(a != b, "edge ", e, " is a loop on node ", a.value);
    CHECK_OR(m.nodes.surface[a.value] == m.nodes.surface[b.value], "edge ", e, " joins nodes ", a.value, " and ",
             b.value, " of different surfaces");
    ++out_count[a.value];
    ++out_count[b.value];
    for (HalfedgeIdx h : {h0, h1}) {
      const FaceIdx f = m.face(h);
      if (!f.valid()) {
        CHECK_OR(!m.next(h).valid() && !m.prev(h).valid(), "faceless halfedge ", h.value, " has next/prev set");
        continue;
      }
      CHECK_OR(m.alive(f), "halfedge ", h.value, " refers to dead face ", f.value);
      CHECK_OR(m.faces.surface[f.value] == m.nodes.surface[a.value], "halfedge ", h.value, " and its face ", f.value,
               " are in different surfaces");
      const HalfedgeIdx n = m.next(h), p = m.prev(h);
      CHECK_OR(n.valid() && m.alive(n) && p.valid() && m.alive(p), "halfedge ", h.value,
               " of face ", f.value, " has a dead or missing next/prev");
      CHECK_OR(m.prev(n) == h && m.next(p) == h, "next/prev of halfedge ", h.value, " are not inverse");
      CHECK_OR(m.face(n) == f, "next of halfedge ", h.value, " leaves face ", f.value);
      CHECK_OR(m.tail(n) == m.head(h), "face ", f.value, " is not a closed chain at halfedge ", h.value);
    }
    const MeshEdgeIdx me = m.edges.mesh_edge[e];
    if (me.valid()) {
      CHECK_OR(m.alive(me), "edge ", e, " refers to dead mesh edge ", me.value);
      bool listed = false;
      for (HalfedgeIdx h : m.mesh_edges.halfedges.row(me.value)) listed |= edge_of(h) == ei;
      CHECK_OR(listed, "edge ", e, " names mesh edge ", me.value, " which does not list it");
    }
  }
  for (std::uint32_t v = 0; v < nn; ++v) {
    const NodeIdx vi{v};
    if (!m.alive(vi)) continue;
    const SurfaceIdx s = m.nodes.surface[v];
    CHECK_OR(s.valid() && m.alive(s), "node ", v, " is in a dead surface");
    CHECK_OR(m.nodes.position[v].allFinite(), "node ", v, " has a non-finite position");
    const HalfedgeIdx start = m.nodes.out[v];
    if (!start.valid()) {
      CHECK_OR(out_count[v] == 0, "node ", v, " has no outgoing halfedge but ", out_count[v], " incident edges");
    } else {
      std::uint32_t n = 0;
      HalfedgeIdx h = start, prev = start;
      do {
        CHECK_OR(m.alive(h), "ring of node ", v, " holds dead halfedge ", h.value);
        CHECK_OR(m.tail(h) == vi, "ring of node ", v, " holds halfedge ", h.value, " with tail ", m.tail(h).value);
        CHECK_OR(m.halfedges.vprev[m.halfedges.vnext[h.value].value] == h, "ring of node ", v,
                 " has a broken vprev at ", h.value);
        if (n > 0) CHECK_OR(prev < h, "ring of node ", v, " is not sorted at halfedge ", h.value);
        prev = h;
        h = m.halfedges.vnext[h.value];
        ++n;
        CHECK_OR(n <= out_count[v], "ring of node ", v, " does not close after ", n, " halfedges");
      } while (h != start);
      CHECK_OR(n == out_count[v], "ring of node ", v, " has ", n, " halfedges but the node has ", out_count[v],
               " incident edges");
      // No parallel edges: the heads around a node are distinct.
      std::vector<NodeIdx> heads;
      m.for_each_outgoing(vi, [&](HalfedgeIdx x) { heads.push_back(m.head(x)); });
      std::sort(heads.begin(), heads.end());
      CHECK_OR(std::adjacent_find(heads.begin(), heads.end()) == heads.end(), "node ", v,
               " has two edges to the same node");
    }
    const FaceIdx rf = m.nodes.in_face[v];
    if (rf.valid()) {
      CHECK_OR(m.alive(rf), "ring node ", v, " lies in dead face ", rf.value);
      CHECK_OR(m.faces.surface[rf.value] == s, "ring node ", v, " lies in a face of another surface");
      bool ok = true;
      m.for_each_outgoing(vi, [&](HalfedgeIdx x) {
        ok &= m.nodes.in_face[m.head(x).value] == rf && m.is_wire(edge_of(x));
      });
      CHECK_OR(ok, "ring node ", v, " is joined to a node outside its face ", rf.value);
    }
  }
  return {};
}

Status check_faces(const Model& m, Checker& c) {
  const std::size_t nf = m.faces.slots.capacity();
  const std::size_t nh = m.halfedges.tail.size();
  for (std::uint32_t f = 0; f < nf; ++f) {
    const FaceIdx fi{f};
    if (!m.alive(fi)) continue;
    const SurfaceIdx s = m.faces.surface[f];
    CHECK_OR(s.valid() && m.alive(s), "face ", f, " is in a dead surface");
    const HalfedgeIdx start = m.faces.halfedge[f];
    CHECK_OR(start.valid() && m.alive(start), "face ", f, " has a dead first halfedge");
    CHECK_OR(m.face(start) == fi, "first halfedge of face ", f, " belongs to face ", m.face(start).value);
    std::size_t n = 0;
    HalfedgeIdx h = start;
    std::vector<NodeIdx> corners;
    do {
      CHECK_OR(m.face(h) == fi, "cycle of face ", f, " runs into halfedge ", h.value, " of another face");
      corners.push_back(m.tail(h));
      h = m.next(h);
      ++n;
      CHECK_OR(n <= nh, "cycle of face ", f, " does not close");
    } while (h != start);
    CHECK_OR(n >= 3, "face ", f, " has ", n, " sides");
    std::sort(corners.begin(), corners.end());
    CHECK_OR(std::adjacent_find(corners.begin(), corners.end()) == corners.end(), "face ", f,
             " visits a node twice");
  }
  return {};
}

Status check_mesh_edges_loops_joints(const Model& m, Checker& c, const ValidateOptions& opt) {
  const std::size_t nm = m.mesh_edges.slots.capacity();
  for (std::uint32_t i = 0; i < nm; ++i) {
    const MeshEdgeIdx mi{i};
    if (!m.alive(mi)) continue;
    const SurfaceIdx s = m.mesh_edges.surface[i];
    CHECK_OR(s.valid() && m.alive(s), "mesh edge ", i, " is in a dead surface");
    auto chain = m.mesh_edges.halfedges.row(i);
    CHECK_OR(!chain.empty(), "mesh edge ", i, " has no edges");
    for (std::size_t k = 0; k < chain.size(); ++k) {
      const HalfedgeIdx h = chain[k];
      CHECK_OR(m.alive(h), "mesh edge ", i, " holds dead halfedge ", h.value);
      CHECK_OR(m.surface_of(edge_of(h)) == s, "mesh edge ", i, " holds an edge of another surface");
      CHECK_OR(m.edges.mesh_edge[edge_of(h).value] == mi, "edge ", edge_of(h).value, " of mesh edge ", i,
               " does not point back to it");
      if (k + 1 < chain.size())
        CHECK_OR(m.head(h) == m.tail(chain[k + 1]), "mesh edge ", i, " is not a chain at position ", k);
    }
    const MeshLoopIdx l = m.mesh_edges.loop[i];
    if (l.valid()) CHECK_OR(m.alive(l), "mesh edge ", i, " refers to dead loop ", l.value);
    const JointIdx j = m.mesh_edges.joint[i];
    if (j.valid()) CHECK_OR(m.alive(j), "mesh edge ", i, " refers to dead joint ", j.value);
  }
  for (std::uint32_t i = 0; i < m.mesh_loops.slots.capacity(); ++i) {
    if (!m.alive(MeshLoopIdx{i})) continue;
    auto list = m.mesh_loops.mesh_edges.row(i);
    CHECK_OR(!list.empty(), "mesh loop ", i, " is empty");
    for (std::size_t k = 0; k < list.size(); ++k) {
      const MeshEdgeIdx me = list[k];
      CHECK_OR(m.alive(me), "mesh loop ", i, " holds dead mesh edge ", me.value);
      CHECK_OR(m.mesh_edges.loop[me.value] == MeshLoopIdx{i}, "mesh edge ", me.value, " of loop ", i,
               " does not point back to it");
      CHECK_OR(m.mesh_edges.surface[me.value] == m.mesh_loops.surface[i], "mesh loop ", i,
               " holds a mesh edge of another surface");
      const MeshEdgeIdx nx = list[(k + 1) % list.size()];
      const auto a = m.mesh_edges.halfedges.row(me.value), b = m.mesh_edges.halfedges.row(nx.value);
      CHECK_OR(m.head(a.back()) == m.tail(b.front()), "mesh loop ", i, " is not closed between mesh edges ",
               me.value, " and ", nx.value);
    }
  }
  // Joint tolerance scales with the model.
  Box3d box;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v})) box.extend(m.nodes.position[v]);
  const double tol = opt.joint_tolerance * (1.0 + (box.empty() ? 0.0 : (box.hi - box.lo).norm()));
  for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
    if (!m.alive(JointIdx{j})) continue;
    auto members = m.joints.members.row(j);
    CHECK_OR(members.size() >= 2, "joint ", j, " has ", members.size(), " mesh edges (at least 2 needed)");
    std::size_t len = 0;
    for (std::size_t k = 0; k < members.size(); ++k) {
      const MeshEdgeIdx me = members[k].mesh_edge;
      CHECK_OR(m.alive(me), "joint ", j, " holds dead mesh edge ", me.value);
      CHECK_OR(m.mesh_edges.joint[me.value] == JointIdx{j}, "mesh edge ", me.value, " of joint ", j,
               " does not point back to it");
      const std::size_t n = m.mesh_edges.halfedges.size(me.value);
      if (k == 0) len = n;
      CHECK_OR(n == len, "joint ", j, ": mesh edge ", me.value, " has ", n, " edges, mesh edge ",
               members[0].mesh_edge.value, " has ", len);
    }
    // Corresponding nodes coincide: walk each member in joint direction.
    auto node_at = [&](const JointMember& mem, std::size_t t) {  // t in [0, len]
      auto chain = m.mesh_edges.halfedges.row(mem.mesh_edge.value);
      if (mem.positive) return t < len ? m.tail(chain[t]) : m.head(chain[len - 1]);
      return t < len ? m.head(chain[len - 1 - t]) : m.tail(chain[0]);
    };
    for (std::size_t t = 0; t <= len; ++t) {
      const Vec3d p0 = m.position(node_at(members[0], t));
      for (std::size_t k = 1; k < members.size(); ++k) {
        const double d = (m.position(node_at(members[k], t)) - p0).norm();
        CHECK_OR(d <= tol, "joint ", j, ": node ", t, " of mesh edge ", members[k].mesh_edge.value,
                 " is ", d, " away from its partner on mesh edge ", members[0].mesh_edge.value);
      }
    }
  }
  return {};
}

Status check_attributes(const Model& m, Checker& c) {
  const auto& an = m.attrib_nodes;
  constexpr double eps = 1e-9;
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i) {
    if (!m.alive(AttribNodeIdx{i})) continue;
    const std::uint32_t el = an.element[i];
    SurfaceIdx s;
    switch (an.kind[i]) {
      case AttribNodeKind::kVertex:
        CHECK_OR(m.alive(NodeIdx{el}), "attribute node ", i, " sits on dead node ", el);
        s = m.nodes.surface[el];
        break;
      case AttribNodeKind::kEdge: {
        CHECK_OR(el < m.halfedges.tail.size() && m.alive(HalfedgeIdx{el}), "attribute edge-node ", i,
                 " lies on dead halfedge ", el);
        const double u = an.param[i].x();
        CHECK_OR(u >= -eps && u <= 1 + eps, "attribute edge-node ", i, " has parameter ", u, " outside [0,1]");
        s = m.surface_of(edge_of(HalfedgeIdx{el}));
        break;
      }
      case AttribNodeKind::kFace: {
        CHECK_OR(m.alive(FaceIdx{el}), "attribute face-node ", i, " lies in dead face ", el);
        const Vec3d& b = an.param[i];
        CHECK_OR(std::abs(b.sum() - 1.0) <= 1e-6 && b.minCoeff() >= -1e-6, "attribute face-node ", i,
                 " has areal coordinates (", b.x(), ",", b.y(), ",", b.z(), ") that are not a convex combination");
        CHECK_OR(an.corner[i] + 3u <= m.face_degree(FaceIdx{el}), "attribute face-node ", i,
                 " names fan triangle ", int(an.corner[i]), " beyond its face");
        s = m.faces.surface[el];
        break;
      }
    }
    CHECK_OR(an.surface[i] == s, "attribute node ", i, " is not in the surface of its element");
    const AttribEdgeIdx o = an.owner[i];
    if (o.valid()) CHECK_OR(m.alive(o), "attribute node ", i, " belongs to dead attribute edge ", o.value);
  }
  const auto& ae = m.attrib_edges;
  for (std::uint32_t i = 0; i < ae.slots.capacity(); ++i) {
    if (!m.alive(AttribEdgeIdx{i})) continue;
    for (AttribNodeIdx a : ae.nodes.row(i)) {
      CHECK_OR(m.alive(a), "attribute edge ", i, " holds dead attribute node ", a.value);
      CHECK_OR(an.owner[a.value] == AttribEdgeIdx{i}, "attribute node ", a.value, " of attribute edge ", i,
               " does not point back to it");
      CHECK_OR(an.surface[a.value] == ae.surface[i], "attribute edge ", i, " crosses into another surface");
    }
  }
  return {};
}

}  // namespace

Status validate(const Model& m, const ValidateOptions& opt) {
  Checker c(m);
  if (Status s = check_sizes(m, c); !s) return s;
  if (Status s = check_nodes_and_edges(m, c); !s) return s;
  if (Status s = check_faces(m, c); !s) return s;
  if (Status s = check_mesh_edges_loops_joints(m, c, opt); !s) return s;
  if (Status s = check_attributes(m, c); !s) return s;
  if (opt.check_euler) {
    const TopologyCounts t = count_topology(m);
    CHECK_OR(m.complex_holes >= 0, "complex hole count is negative (", m.complex_holes, ")");
    CHECK_OR(t.euler() == t.components - m.complex_holes + t.shells, "Euler-Poincare formula fails: V-E+F-R = ",
             t.nodes, "-", t.edges, "+", t.faces, "-", t.rings, " = ", t.euler(), " but C-H+S = ", t.components, "-",
             m.complex_holes, "+", t.shells);
  }
  return {};
}

}  // namespace atelier
