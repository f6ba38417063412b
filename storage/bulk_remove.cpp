#include <atelier/storage/bulk_remove.h>

#include <cassert>
#include <vector>

namespace atelier {

void remove_faces_bulk(Model& m, std::span<const FaceIdx> faces, std::span<const EdgeIdx> edges,
                       std::span<const NodeIdx> nodes) {
  auto& he = m.halfedges;
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
    m.faces.halfedge[f.value] = {};
    m.faces.surface[f.value] = {};
    m.faces.flags[f.value] = 0;
    m.faces.props.reset(f);
    m.faces.slots.release(f);
  }
  std::vector<std::uint8_t> dies(nodes.empty() ? 0 : m.nodes.slots.capacity(), 0);
  for (NodeIdx v : nodes) dies[v.value] = 1;
  for (EdgeIdx e : edges) {
    assert(m.alive(e) && m.is_wire(e) && !m.edges.mesh_edge[e.value].valid());
    for (unsigned s = 0; s < 2; ++s) {
      const HalfedgeIdx h = halfedge_of(e, s);
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
    m.edges.flags[e.value] = 0;
    m.edges.mesh_edge[e.value] = {};
    m.edges.props.reset(e);
    he.props.reset(halfedge_of(e, 0));
    he.props.reset(halfedge_of(e, 1));
    m.edges.slots.release(e);
  }
  for (NodeIdx v : nodes) {
    assert(m.alive(v) && !m.nodes.in_face[v.value].valid());
    m.nodes.position[v.value] = Vec3d::Zero();
    m.nodes.position_backup[v.value] = Vec3d::Zero();
    m.nodes.uv[v.value] = Vec2d::Zero();
    m.nodes.out[v.value] = {};
    m.nodes.surface[v.value] = {};
    m.nodes.in_face[v.value] = {};
    m.nodes.props.reset(v);
    m.nodes.slots.release(v);
  }
  ++m.topology_version;
}

}  // namespace atelier
