#include <atelier/engine/math.h>
#include <atelier/engine/status_format.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/edge_flags.h>
#include <atelier/storage/union_find.h>
#include <atelier/systems/pattern/seams.h>

#include <algorithm>
#include <deque>
#include <limits>
#include <set>
#include <utility>

namespace atelier {

namespace {


bool interior(const Model& m, EdgeIdx e) {
  return m.face(halfedge_of(e, 0)).valid() && m.face(halfedge_of(e, 1)).valid();
}

/// Boundary loops of surface s: per node, its loop's id (the smallest
/// boundary node of the loop), kNone off the boundary.
std::vector<std::uint32_t> boundary_loops(const Model& m, SurfaceIdx s, std::vector<std::uint32_t>& loop_ids) {
  const std::uint32_t nn = m.nodes.slots.capacity();
  UnionFind uf(nn);
  std::vector<std::uint8_t> on(nn, 0);
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e}) || m.surface_of(EdgeIdx{e}) != s || !m.is_boundary(EdgeIdx{e})) continue;
    const HalfedgeIdx h = halfedge_of(EdgeIdx{e}, 0);
    uf.unite(m.tail(h).value, m.head(h).value);
    on[m.tail(h).value] = on[m.head(h).value] = 1;
  }
  std::vector<std::uint32_t> loop(nn, kNone);
  std::set<std::uint32_t> ids;
  for (std::uint32_t v = 0; v < nn; ++v)
    if (on[v]) ids.insert(loop[v] = uf.find(v));
  loop_ids.assign(ids.begin(), ids.end());
  return loop;
}

/// Automatic seams of surface s (see seams.h): appended to `paths`, their
/// edges and nodes marked.
Status automatic_seams(const Model& m, SurfaceIdx s, std::vector<std::uint8_t>& seam_edge,
                       std::vector<std::uint8_t>& seam_node, const std::vector<std::uint8_t>& on_mesh_edge,
                       std::vector<std::vector<NodeIdx>>& paths) {
  std::vector<std::uint32_t> ids;
  std::vector<std::uint32_t> loop = boundary_loops(m, s, ids);
  bool has_face = false;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity() && !has_face; ++f)
    has_face = m.alive(FaceIdx{f}) && m.faces.surface[f] == s;
  if (!has_face) return Status::ok();
  if (ids.empty())
    return status_of(ErrorCode::kTopology, "surface '", m.surfaces.name[s.value],
                     "' is closed: a seam needs a boundary to start from (cut or partition it first)");
  // Loops already joined to the first one by paths (given or marked, also
  // through each other: two marked runs meeting inside) count as reached.
  const std::uint32_t nn = m.nodes.slots.capacity();
  UnionFind joined(nn);
  for (std::uint32_t v = 0; v < nn; ++v)
    if (loop[v] != kNone) joined.unite(v, loop[v]);
  for (const auto& p : paths) {
    if (p.empty() || m.nodes.surface[p.front().value] != s) continue;
    for (std::size_t i = 1; i < p.size(); ++i) joined.unite(p[i - 1].value, p[i].value);
  }
  std::vector<NodeIdx> outgoing_nodes;
  std::vector<HalfedgeIdx> out;
  while (true) {
    const std::uint32_t root = joined.find(ids.front());
    bool all = true;
    for (std::uint32_t id : ids) all = all && joined.find(id) == root;
    if (all) return Status::ok();
    // Breadth-first from the reached loops' nodes (in node order), strict
    // (no mesh edges or their nodes inside the path), then relaxed.
    bool found = false;
    for (int strict = 1; strict >= 0 && !found; --strict) {
      std::vector<std::uint32_t> from(nn, kNone);
      std::vector<std::uint8_t> seen(nn, 0);
      std::deque<std::uint32_t> queue;
      for (std::uint32_t v = 0; v < nn; ++v)
        if (loop[v] != kNone && joined.find(loop[v]) == root) {
          seen[v] = 1;
          queue.push_back(v);
        }
      std::uint32_t hit = kNone;
      while (!queue.empty() && hit == kNone) {
        const std::uint32_t u = queue.front();
        queue.pop_front();
        m.outgoing(NodeIdx{u}, out);
        for (HalfedgeIdx h : out) {
          const EdgeIdx e = edge_of(h);
          const std::uint32_t w = m.head(h).value;
          if (seen[w] || !interior(m, e) || seam_edge[e.value]) continue;
          if (strict && m.edges.mesh_edge[e.value].valid()) continue;
          if (loop[w] != kNone) {  // a boundary node: a target, or a loop already reached
            if (joined.find(loop[w]) == root) continue;
            from[w] = u;
            hit = w;
            break;
          }
          if (seam_node[w] || (strict && on_mesh_edge[w])) continue;
          seen[w] = 1;
          from[w] = u;
          queue.push_back(w);
        }
      }
      if (hit == kNone) continue;
      std::vector<NodeIdx> path;
      for (std::uint32_t v = hit; v != kNone; v = from[v]) path.push_back(NodeIdx{v});
      std::reverse(path.begin(), path.end());
      for (std::size_t i = 0; i + 1 < path.size(); ++i)
        seam_edge[edge_of(m.find_halfedge(path[i], path[i + 1])).value] = 1;
      for (NodeIdx v : path) seam_node[v.value] = 1;
      joined.unite(root, loop[hit]);
      paths.push_back(std::move(path));
      found = true;
    }
    if (!found)
      return status_of(ErrorCode::kTopology, "surface '", m.surfaces.name[s.value],
                       "': no seam path reaches boundary loop at node ", ids.back());
  }
}

/// The marked seams of the chosen surfaces (see seams.h): chains of
/// interior kEdgeSeam edges between end nodes (a boundary node, or a node
/// with other than two marked edges; closed loops start at their smallest
/// node), in node order, cut into runs along joints and runs off them.
void marked_seams(const Model& m, const std::vector<std::uint8_t>& chosen, std::vector<std::vector<NodeIdx>>& off_joint,
                  std::vector<std::vector<NodeIdx>>& on_joint) {
  const std::uint32_t nn = m.nodes.slots.capacity(), ne = m.edges.slots.capacity();
  std::vector<std::uint8_t> marked(ne, 0), visited(ne, 0);
  std::vector<std::uint32_t> degree(nn, 0);
  std::vector<std::uint8_t> on_boundary(nn, 0);
  bool any = false;
  for (std::uint32_t e = 0; e < ne; ++e) {
    const EdgeIdx E{e};
    if (!m.alive(E)) continue;
    const HalfedgeIdx h = halfedge_of(E, 0);
    if (m.is_boundary(E)) on_boundary[m.tail(h).value] = on_boundary[m.head(h).value] = 1;
    const SurfaceIdx s = m.surface_of(E);
    if (!(m.edges.flags[e] & kEdgeSeam) || !interior(m, E) || !s.valid() || !chosen[s.value]) continue;
    marked[e] = 1;
    any = true;
    ++degree[m.tail(h).value];
    ++degree[m.head(h).value];
  }
  if (!any) return;
  auto on_a_joint = [&](EdgeIdx e) {
    const MeshEdgeIdx me = m.edges.mesh_edge[e.value];
    return me.valid() && m.mesh_edges.joint[me.value].valid();
  };
  auto emit = [&](const std::vector<NodeIdx>& chain) {
    std::size_t start = 0;
    for (std::size_t i = 1; i < chain.size(); ++i) {
      const bool here = on_a_joint(edge_of(m.find_halfedge(chain[i - 1], chain[i])));
      const bool next =
          i + 1 < chain.size() && on_a_joint(edge_of(m.find_halfedge(chain[i], chain[i + 1])));
      if (i + 1 == chain.size() || here != next) {
        std::vector<NodeIdx> run(chain.begin() + static_cast<std::ptrdiff_t>(start),
                                 chain.begin() + static_cast<std::ptrdiff_t>(i) + 1);
        (here ? on_joint : off_joint).push_back(std::move(run));
        start = i;
      }
    }
  };
  std::vector<HalfedgeIdx> out;
  auto walk = [&](NodeIdx v, HalfedgeIdx h, bool stop_at_ends) {
    std::vector<NodeIdx> chain{v};
    while (true) {
      visited[edge_of(h).value] = 1;
      const NodeIdx w = m.head(h);
      chain.push_back(w);
      if ((stop_at_ends && (on_boundary[w.value] || degree[w.value] != 2)) || w == chain.front()) break;
      HalfedgeIdx nxt{};
      m.outgoing(w, out);
      for (HalfedgeIdx g : out)
        if (marked[edge_of(g).value] && !visited[edge_of(g).value]) {
          nxt = g;
          break;
        }
      if (!nxt.valid()) break;
      h = nxt;
    }
    emit(chain);
  };
  for (int pass = 0; pass < 2; ++pass)  // chains between end nodes, then closed loops
    for (std::uint32_t v = 0; v < nn; ++v) {
      if (!degree[v] || (pass == 0 && !on_boundary[v] && degree[v] == 2)) continue;
      m.outgoing(NodeIdx{v}, out);
      const std::vector<HalfedgeIdx> starts = out;
      for (HalfedgeIdx h : starts)
        if (marked[edge_of(h).value] && !visited[edge_of(h).value]) walk(NodeIdx{v}, h, pass == 0);
    }
}

/// The corner a polygon's fan should start from: the first one unless its
/// fan has a (nearly) degenerate triangle, as a polygon with collinear
/// corners (a T-junction of a refined neighbour) has from some corners; then
/// the corner whose fan's smallest triangle is largest.
std::size_t fan_start(const std::vector<Vec3d>& p, const std::vector<std::uint32_t>& ids) {
  const std::size_t n = ids.size();
  if (n <= 3) return 0;
  auto smallest = [&](std::size_t k) {
    double a = std::numeric_limits<double>::infinity();
    const Vec3d& c = p[ids[k]];
    for (std::size_t i = 1; i + 1 < n; ++i)
      a = std::min(a, (p[ids[(k + i) % n]] - c).cross(p[ids[(k + i + 1) % n]] - c).norm());
    return a;
  };
  std::size_t best = 0;
  double best_a = smallest(0);
  const double first = best_a;
  for (std::size_t k = 1; k < n; ++k)
    if (const double a = smallest(k); a > best_a) best = k, best_a = a;
  return first >= 1e-3 * best_a ? 0 : best;
}

}  // namespace

Expected<OpenedSeams> open_seams(const Model& m, const SeamOptions& opt, const ExecContext& ctx) {
  (void)ctx;
  const std::uint32_t nn = m.nodes.slots.capacity(), ne = m.edges.slots.capacity();
  std::vector<std::uint8_t> chosen(m.surfaces.slots.capacity(), 0);
  if (opt.surfaces.empty()) {
    for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f)
      if (m.alive(FaceIdx{f})) chosen[m.faces.surface[f].value] = 1;
  } else {
    for (SurfaceIdx s : opt.surfaces) {
      if (s.value >= chosen.size() || !m.alive(s))
        return status_of(ErrorCode::kStaleHandle, "open_seams: surface ", s.value, " is not alive");
      chosen[s.value] = 1;
    }
  }
  OpenedSeams res;
  std::vector<std::uint8_t> seam_edge(ne, 0), seam_node(nn, 0), on_mesh_edge(nn, 0);
  for (std::uint32_t me = 0; me < m.mesh_edges.slots.capacity(); ++me)
    if (m.alive(MeshEdgeIdx{me}))
      for (HalfedgeIdx h : m.mesh_edges.halfedges.row(me))
        on_mesh_edge[m.tail(h).value] = on_mesh_edge[m.head(h).value] = 1;
  // Given paths.
  for (std::size_t p = 0; p < opt.paths.size(); ++p) {
    const auto& path = opt.paths[p];
    if (path.size() < 2) return status_of(ErrorCode::kInvalidArgument, "seam path ", p, " has fewer than two nodes");
    for (std::size_t i = 0; i < path.size(); ++i) {
      if (path[i].value >= nn || !m.alive(path[i]))
        return status_of(ErrorCode::kInvalidArgument, "seam path ", p, ": node ", path[i].value, " is not alive");
      if (i == 0) continue;
      const HalfedgeIdx h = m.find_halfedge(path[i - 1], path[i]);
      if (!h.valid())
        return status_of(ErrorCode::kInvalidArgument, "seam path ", p, ": nodes ", path[i - 1].value, " and ",
                         path[i].value, " are not joined by an edge");
      const EdgeIdx e = edge_of(h);
      if (!interior(m, e))
        return status_of(ErrorCode::kInvalidArgument, "seam path ", p, ": edge ", e.value,
                         " is not between two faces (a seam runs inside a piece)");
      if (const MeshEdgeIdx me = m.edges.mesh_edge[e.value]; me.valid() && m.mesh_edges.joint[me.value].valid())
        return status_of(ErrorCode::kInvalidArgument, "seam path ", p, ": edge ", e.value, " is on joint ",
                         m.mesh_edges.joint[me.value].value, " already");
      seam_edge[e.value] = 1;
    }
    for (NodeIdx v : path) seam_node[v.value] = 1;
    res.paths.push_back(path);
  }
  // Marked seams: runs off joints open like given paths; runs along a
  // joint's inner member add the member's other side to that joint.
  std::vector<std::vector<NodeIdx>> along_joints;
  if (opt.marked) {
    marked_seams(m, chosen, res.paths, along_joints);
    for (const auto* runs : {&res.paths, &along_joints})
      for (const auto& path : *runs) {
        for (std::size_t i = 0; i + 1 < path.size(); ++i)
          seam_edge[edge_of(m.find_halfedge(path[i], path[i + 1])).value] = 1;
        for (NodeIdx v : path) seam_node[v.value] = 1;
      }
  }
  res.marked_along_joints = along_joints.size();
  if (opt.automatic) {
    std::vector<std::vector<NodeIdx>> all = res.paths;  // every cut so far joins boundary loops
    all.insert(all.end(), along_joints.begin(), along_joints.end());
    const std::size_t known = all.size();
    for (std::uint32_t s = 0; s < chosen.size(); ++s)
      if (chosen[s] && m.alive(SurfaceIdx{s}))
        if (Status st = automatic_seams(m, SurfaceIdx{s}, seam_edge, seam_node, on_mesh_edge, all); !st) return st;
    res.paths.insert(res.paths.end(), all.begin() + static_cast<std::ptrdiff_t>(known), all.end());
  }

  // Corners (a face's halfedge = its tail's corner) joined across non-seam
  // edges: the wedges of the seam nodes.
  UnionFind uf(2 * static_cast<std::size_t>(ne));
  for (std::uint32_t e = 0; e < ne; ++e) {
    if (!m.alive(EdgeIdx{e}) || seam_edge[e] || !interior(m, EdgeIdx{e})) continue;
    const HalfedgeIdx h = halfedge_of(EdgeIdx{e}, 0), t = twin(h);
    uf.unite(h.value, m.next(t).value);
    uf.unite(t.value, m.next(h).value);
  }
  // Faces joined across non-seam edges: seams that separate a surface
  // make several pieces of it.
  const std::uint32_t nf = m.faces.slots.capacity();
  UnionFind parts(nf);
  for (std::uint32_t e = 0; e < ne; ++e)
    if (m.alive(EdgeIdx{e}) && !seam_edge[e] && interior(m, EdgeIdx{e}))
      parts.unite(m.face(halfedge_of(EdgeIdx{e}, 0)).value, m.face(halfedge_of(EdgeIdx{e}, 1)).value);
  Model& out = res.model;
  std::vector<std::uint32_t> corner_node(2 * static_cast<std::size_t>(ne), kNone);  // new node per corner
  res.surfaces.assign(m.surfaces.slots.capacity(), SurfaceIdx{});
  std::vector<NodeIdx> fn;
  for (std::uint32_t s = 0; s < m.surfaces.slots.capacity(); ++s) {
    if (!m.alive(SurfaceIdx{s})) continue;
    // Its pieces, in the order of their first faces.
    std::vector<std::uint32_t> roots;
    for (std::uint32_t f = 0; f < nf; ++f)
      if (m.alive(FaceIdx{f}) && m.faces.surface[f].value == s &&
          std::find(roots.begin(), roots.end(), parts.find(f)) == roots.end())
        roots.push_back(parts.find(f));
    if (roots.empty()) roots.push_back(kNone);  // a surface without faces is copied empty
    for (std::size_t part = 0; part < roots.size(); ++part) {
    // Node copies in node order, then wedge order.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> keys;
    auto key_of = [&](HalfedgeIdx h) {
      const std::uint32_t v = m.tail(h).value;
      return std::pair{v, seam_node[v] ? uf.find(h.value) : 0u};
    };
    std::vector<FaceIdx> faces;
    for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
      if (!m.alive(FaceIdx{f}) || m.faces.surface[f].value != s || parts.find(f) != roots[part]) continue;
      faces.push_back(FaceIdx{f});
      m.for_each_face_halfedge(FaceIdx{f}, [&](HalfedgeIdx h) { keys.push_back(key_of(h)); });
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    PolygonSoup soup;
    for (const auto& k : keys) soup.positions.push_back(m.nodes.position[k.first]);
    const std::uint32_t v0 = out.nodes.slots.capacity();
    for (FaceIdx f : faces) {
      std::vector<std::uint32_t> ids;
      m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
        const auto local =
            static_cast<std::uint32_t>(std::lower_bound(keys.begin(), keys.end(), key_of(h)) - keys.begin());
        ids.push_back(local);
        corner_node[h.value] = v0 + local;
      });
      const std::size_t k = fan_start(soup.positions, ids);
      std::rotate(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(k), ids.end());
      soup.add_face(ids);
    }
    const std::string name = part == 0 ? m.surfaces.name[s] : m.surfaces.name[s] + "." + std::to_string(part);
    auto made = add_polygon_surface(out, name, soup);
    if (!made) return made.status();
    if (part == 0) res.surfaces[s] = made->idx;
    res.part_of.resize(out.surfaces.slots.capacity());
    res.part_of[made->idx.value] = SurfaceIdx{s};
    res.source_node.resize(out.nodes.slots.capacity());
    for (std::size_t k = 0; k < keys.size(); ++k) res.source_node[v0 + k] = NodeIdx{keys[k].first};
    }
  }
  // The new halfedge of an old one (through the corner on its face side).
  auto mapped = [&](HalfedgeIdx h) -> HalfedgeIdx {
    std::uint32_t a = kNone, b = kNone;
    if (m.face(h).valid()) {
      a = corner_node[h.value];
      b = corner_node[m.next(h).value];
    } else if (m.face(twin(h)).valid()) {
      a = corner_node[m.next(twin(h)).value];
      b = corner_node[twin(h).value];
    }
    if (a == kNone || b == kNone) return HalfedgeIdx{};
    return out.find_halfedge(NodeIdx{a}, NodeIdx{b});
  };
  // The other side of an inner edge opened by a seam: the new halfedge
  // along old halfedge h (same direction) on its twin's face side.
  auto other_side = [&](HalfedgeIdx h) -> HalfedgeIdx {
    if (!m.face(h).valid() || !m.face(twin(h)).valid() || !seam_edge[edge_of(h).value]) return HalfedgeIdx{};
    const std::uint32_t a = corner_node[m.next(twin(h)).value], b = corner_node[twin(h).value];
    if (a == kNone || b == kNone) return HalfedgeIdx{};
    return out.find_halfedge(NodeIdx{a}, NodeIdx{b});
  };
  auto surface_of_chain = [&](const std::vector<HalfedgeIdx>& c) { return out.nodes.surface[out.tail(c.front()).value]; };
  // Joints carried over, cut where a seam breaks their chains; a member
  // along a marked seam gets its other side as a further member.
  for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
    if (!m.alive(JointIdx{j})) continue;
    const auto members = m.joints.members.row(j);
    struct Mapped {
      std::vector<HalfedgeIdx> chain;  // in joint order
      SurfaceIdx surface;
      bool positive;
      std::vector<HalfedgeIdx> other;  // in joint order: the opened other side, or invalid
    };
    std::vector<Mapped> mm;
    std::size_t n = 0;
    bool ok = true, closed = true;
    for (const JointMember& mem : members) {
      const auto row = m.mesh_edges.halfedges.row(mem.mesh_edge.value);
      Mapped x{{}, res.surfaces[m.mesh_edges.surface[mem.mesh_edge.value].value], mem.positive, {}};
      for (HalfedgeIdx h : row) {
        x.chain.push_back(mapped(h));
        x.other.push_back(other_side(h));
      }
      if (!mem.positive) {
        std::reverse(x.chain.begin(), x.chain.end());
        std::reverse(x.other.begin(), x.other.end());
      }
      for (HalfedgeIdx h : x.chain) ok = ok && h.valid();
      closed = closed && !row.empty() && m.tail(row.front()) == m.head(row.back());
      n = row.size();
      ok = ok && row.size() == n && x.surface.valid();
      mm.push_back(std::move(x));
    }
    if (!ok || mm.empty() || n == 0)
      return status_of(ErrorCode::kInternal, "open_seams: joint ", j, " could not be carried over");
    // A break after joint position t: some member's chain is not connected
    // there (in its own direction).
    auto broken = [&](std::size_t t, std::size_t u) {
      for (const Mapped& x : mm) {
        if (x.other[t].valid() != x.other[u].valid()) return true;  // a marked seam starts or ends along it
        for (const auto* side : {&x.chain, &x.other}) {
          if (!(*side)[t].valid()) continue;
          const HalfedgeIdx a = x.positive ? (*side)[t] : (*side)[u], b = x.positive ? (*side)[u] : (*side)[t];
          if (out.head(a) != out.tail(b)) return true;
        }
      }
      return false;
    };
    std::vector<std::size_t> breaks;
    for (std::size_t t = 0; t + 1 < n; ++t)
      if (broken(t, t + 1)) breaks.push_back(t);
    if (closed && broken(n - 1, 0)) breaks.push_back(n - 1);
    std::vector<std::vector<std::size_t>> runs;
    if (breaks.empty() || (!closed && breaks.empty())) {
      runs.emplace_back();
      for (std::size_t t = 0; t < n; ++t) runs.back().push_back(t);
    } else if (!closed) {
      std::size_t start = 0;
      breaks.push_back(n - 1);
      for (std::size_t b : breaks) {
        runs.emplace_back();
        for (std::size_t t = start; t <= b; ++t) runs.back().push_back(t);
        start = b + 1;
      }
    } else {
      for (std::size_t i = 0; i < breaks.size(); ++i) {
        const std::size_t from = (breaks[i] + 1) % n, to = breaks[(i + 1) % breaks.size()];
        runs.emplace_back();
        for (std::size_t t = from;; t = (t + 1) % n) {
          runs.back().push_back(t);
          if (t == to) break;
        }
      }
    }
    for (const auto& run : runs) {
      std::vector<JointMember> jm;
      for (const Mapped& x : mm)
        for (const auto* side : {&x.chain, &x.other}) {
          if (!(*side)[run.front()].valid()) continue;  // no other side here
          std::vector<HalfedgeIdx> c;
          for (std::size_t t : run) c.push_back((*side)[t]);
          if (!x.positive) std::reverse(c.begin(), c.end());
          jm.push_back({out.new_mesh_edge(surface_of_chain(c), c), x.positive});
        }
      (void)out.new_joint(jm);
    }
  }
  // Seam joints: the two sides of each path, both in the path's direction.
  for (const auto& path : res.paths) {
    std::vector<HalfedgeIdx> left, right;
    for (std::size_t i = 0; i + 1 < path.size(); ++i) {
      const HalfedgeIdx h = m.find_halfedge(path[i], path[i + 1]), t = twin(h);
      const NodeIdx la{corner_node[h.value]}, lb{corner_node[m.next(h).value]};
      const NodeIdx ra{corner_node[m.next(t).value]}, rb{corner_node[t.value]};
      left.push_back(out.find_halfedge(la, lb));
      right.push_back(out.find_halfedge(ra, rb));
      if (!left.back().valid() || !right.back().valid())
        return status_of(ErrorCode::kInternal, "open_seams: seam edge ", edge_of(h).value, " was not opened");
    }
    const JointMember jm[2] = {{out.new_mesh_edge(surface_of_chain(left), left), true},
                               {out.new_mesh_edge(surface_of_chain(right), right), true}};
    res.seam_joints.push_back(out.new_joint(jm));
  }
  return res;
}

}  // namespace atelier
