#include <atelier/storage/bulk_remove.h>

#include <cassert>
#include <vector>

namespace atelier {

// The rows are cleared in memory order (one pass over the halfedge columns
// for the faces, passes over byte marks for edges and nodes) rather than in
// the order of the lists: a piece's edges and nodes are scattered over the
// columns, and clearing them in list order was mostly cache misses (a third
// of the sketch cut's removal). Slots are still released in list order, so
// the free lists and generations are those of the primitives; the rings are
// the same whatever the order in which halfedges leave them (each stays
// sorted, `out` its smallest).
void remove_faces_bulk(Model& m, std::span<const FaceIdx> faces, std::span<const EdgeIdx> edges,
                       std::span<const NodeIdx> nodes) {
  auto& he = m.halfedges;
  const std::size_t nh = 2 * m.edges.slots.capacity();
  // Faces. A small set is walked face by face; a large one (half a mesh)
  // costs one pass over the halfedge columns.
  if (faces.size() * 16 < m.faces.slots.capacity()) {
    for (FaceIdx f : faces) {
      assert(m.alive(f));
      const HalfedgeIdx start = m.faces.halfedge[f.value];
      HalfedgeIdx h = start;
      do {
        const HalfedgeIdx n = he.next[h.value];
        he.face[h.value] = {};
        he.next[h.value] = he.prev[h.value] = {};
        h = n;
      } while (h != start);
    }
  } else if (!faces.empty()) {
    std::vector<std::uint8_t> gone(m.faces.slots.capacity(), 0);
    for (FaceIdx f : faces) {
      assert(m.alive(f));
      gone[f.value] = 1;
    }
    for (std::size_t h = 0; h < nh; ++h)
      if (const FaceIdx f = he.face[h]; f.valid() && gone[f.value]) {
        he.face[h] = {};
        he.next[h] = he.prev[h] = {};
      }
  }
  for (FaceIdx f : faces) {
    m.faces.halfedge[f.value] = {};
    m.faces.surface[f.value] = {};
    m.faces.flags[f.value] = 0;
    m.faces.props.reset(f);
    m.faces.slots.release(f);
  }
  // Edges, in index order.
  const std::size_t nn = m.nodes.slots.capacity();
  std::vector<std::uint8_t> dies(nodes.empty() ? 0 : nn, 0);
  for (NodeIdx v : nodes) dies[v.value] = 1;
  std::vector<std::uint8_t> edie(edges.empty() ? 0 : m.edges.slots.capacity(), 0);
  for (EdgeIdx e : edges) {
    assert(m.alive(e) && m.is_wire(e) && !m.edges.mesh_edge[e.value].valid());
    edie[e.value] = 1;
  }
  for (std::uint32_t e = 0; e < edie.size(); ++e) {
    if (!edie[e]) continue;
    for (unsigned s = 0; s < 2; ++s) {
      const HalfedgeIdx h = halfedge_of(EdgeIdx{e}, s);
      const NodeIdx v = he.tail[h.value];
      // A dying node's ring goes as a whole (delete_node clears its out);
      // a survivor's ring is unlinked as Model::unlink_out does.
      if (dies.empty() || !dies[v.value]) {
        if (he.vnext[h.value] == h) {
          m.nodes.out[v.value] = {};
        } else {
          const HalfedgeIdx p = he.vprev[h.value], n = he.vnext[h.value];
          he.vnext[p.value] = n;
          he.vprev[n.value] = p;
          if (m.nodes.out[v.value] == h) m.nodes.out[v.value] = n;
        }
      }
      he.vnext[h.value] = he.vprev[h.value] = {};
      he.tail[h.value] = {};
      he.face[h.value] = {};
      he.next[h.value] = he.prev[h.value] = {};
    }
    m.edges.flags[e] = 0;
    m.edges.mesh_edge[e] = {};
  }
  for (EdgeIdx e : edges) {
    m.edges.props.reset(e);
    he.props.reset(halfedge_of(e, 0));
    he.props.reset(halfedge_of(e, 1));
    m.edges.slots.release(e);
  }
  // Nodes, in index order.
  for (std::uint32_t v = 0; v < dies.size(); ++v) {
    if (!dies[v]) continue;
    assert(m.alive(NodeIdx{v}) && !m.nodes.in_face[v].valid());
    m.nodes.position[v] = Vec3d::Zero();
    m.nodes.position_backup[v] = Vec3d::Zero();
    m.nodes.uv[v] = Vec2d::Zero();
    m.nodes.out[v] = {};
    m.nodes.surface[v] = {};
    m.nodes.in_face[v] = {};
  }
  for (NodeIdx v : nodes) {
    m.nodes.props.reset(v);
    m.nodes.slots.release(v);
  }
  ++m.topology_version;
}

}  // namespace atelier
