#include <atelier/engine/status_format.h>
#include <atelier/systems/sketch/transfer.h>

#include <map>

namespace atelier {

Status check_same_topology(const Model& a, const Model& b) {
  auto differ = [](const char* what, std::size_t i) {
    return status_of(ErrorCode::kMismatch, "the models differ in topology: ", what, " ", i);
  };
  if (a.nodes.slots.capacity() != b.nodes.slots.capacity() || a.edges.slots.capacity() != b.edges.slots.capacity() ||
      a.faces.slots.capacity() != b.faces.slots.capacity() ||
      a.surfaces.slots.capacity() != b.surfaces.slots.capacity())
    return status_of(ErrorCode::kMismatch, "the models differ in topology: ", a.num_nodes(), " nodes, ", a.num_edges(),
                     " edges, ", a.num_faces(), " faces against ", b.num_nodes(), ", ", b.num_edges(), ", ",
                     b.num_faces(), " (another template, level or garment?)");
  for (std::uint32_t s = 0; s < a.surfaces.slots.capacity(); ++s)
    if (a.alive(SurfaceIdx{s}) != b.alive(SurfaceIdx{s})) return differ("surface", s);
  for (std::uint32_t v = 0; v < a.nodes.slots.capacity(); ++v) {
    const NodeIdx n{v};
    if (a.alive(n) != b.alive(n)) return differ("node", v);
    if (a.alive(n) && a.nodes.surface[v] != b.nodes.surface[v]) return differ("surface of node", v);
  }
  for (std::uint32_t e = 0; e < a.edges.slots.capacity(); ++e) {
    const EdgeIdx x{e};
    if (a.alive(x) != b.alive(x)) return differ("edge", e);
    if (!a.alive(x)) continue;
    for (unsigned s = 0; s < 2; ++s) {
      const HalfedgeIdx h = halfedge_of(x, s);
      if (a.tail(h) != b.tail(h) || a.face(h) != b.face(h) || a.next(h) != b.next(h))
        return differ("halfedge", h.value);
    }
  }
  for (std::uint32_t f = 0; f < a.faces.slots.capacity(); ++f) {
    const FaceIdx x{f};
    if (a.alive(x) != b.alive(x)) return differ("face", f);
    if (a.alive(x) && (a.faces.halfedge[f] != b.faces.halfedge[f] || a.faces.surface[f] != b.faces.surface[f]))
      return differ("face", f);
  }
  return {};
}

Expected<std::vector<AttribEdge>> transfer_curves(const Model& from, std::span<const AttribEdge> curves, Model& to) {
  std::vector<AttribEdgeIdx> idx;
  for (const AttribEdge& c : curves) {
    auto r = from.resolve(c);
    if (!r) return r.status();
    idx.push_back(*r);
  }
  if (Status s = check_same_topology(from, to); !s) return s;
  std::vector<AttribEdge> out;
  const auto& an = from.attrib_nodes;
  for (AttribEdgeIdx e : idx) {
    std::map<AttribNodeIdx, AttribNodeIdx> made;  // a closed curve repeats a node
    std::vector<AttribNodeIdx> row;
    for (AttribNodeIdx a : from.attrib_edges.nodes.row(e.value)) {
      auto it = made.find(a);
      if (it == made.end()) {
        const AttribNodeIdx n = to.new_attrib_node(an.surface[a.value], an.kind[a.value], an.element[a.value],
                                                   an.param[a.value], Vec3d::Zero(), an.corner[a.value]);
        to.attrib_nodes.position[n.value] = to.attrib_position_on_surface(n);
        it = made.emplace(a, n).first;
      }
      row.push_back(it->second);
    }
    const AttribEdgeIdx ne =
        to.new_attrib_edge(from.attrib_edges.surface[e.value], from.attrib_edges.feature_id[e.value], row);
    out.push_back(to.handle(ne));
  }
  return out;
}

}  // namespace atelier
