#include <atelier/storage/topology.h>
#include <atelier/storage/union_find.h>

#include <numeric>
#include <vector>

namespace atelier {

namespace {


TopologyCounts count_impl(const Model& m, SurfaceIdx only) {
  TopologyCounts c;
  const std::size_t nn = m.nodes.slots.capacity();
  const std::size_t ne = m.edges.slots.capacity();
  const std::size_t nf = m.faces.slots.capacity();
  auto in_scope_node = [&](std::size_t v) {
    return m.alive(NodeIdx{static_cast<std::uint32_t>(v)}) && (!only.valid() || m.nodes.surface[v] == only);
  };
  auto in_scope_edge = [&](std::size_t e) {
    return m.alive(EdgeIdx{static_cast<std::uint32_t>(e)}) &&
           (!only.valid() || m.surface_of(EdgeIdx{static_cast<std::uint32_t>(e)}) == only);
  };
  auto in_scope_face = [&](std::size_t f) {
    return m.alive(FaceIdx{static_cast<std::uint32_t>(f)}) && (!only.valid() || m.faces.surface[f] == only);
  };

  // Components over nodes: edges join their ends, a ring node joins its face.
  UnionFind nodes_uf(nn);
  for (std::size_t e = 0; e < ne; ++e) {
    if (!in_scope_edge(e)) continue;
    ++c.edges;
    const EdgeIdx ei{static_cast<std::uint32_t>(e)};
    nodes_uf.unite(m.tail(halfedge_of(ei, 0)).value, m.tail(halfedge_of(ei, 1)).value);
  }
  // Rings: components of in-face nodes counted before joining them to their face.
  for (std::size_t v = 0; v < nn; ++v) {
    if (!in_scope_node(v)) continue;
    ++c.nodes;
  }
  std::vector<std::uint8_t> seen_root(nn, 0);
  for (std::size_t v = 0; v < nn; ++v) {
    if (!in_scope_node(v) || !m.nodes.in_face[v].valid()) continue;
    const auto r = nodes_uf.find(static_cast<std::uint32_t>(v));
    if (!seen_root[r]) {
      seen_root[r] = 1;
      ++c.rings;
    }
  }
  for (std::size_t v = 0; v < nn; ++v) {
    if (!in_scope_node(v) || !m.nodes.in_face[v].valid()) continue;
    const FaceIdx f = m.nodes.in_face[v];
    if (m.alive(f)) nodes_uf.unite(static_cast<std::uint32_t>(v), m.tail(m.faces.halfedge[f.value]).value);
  }
  for (std::size_t v = 0; v < nn; ++v)
    if (in_scope_node(v) && nodes_uf.find(static_cast<std::uint32_t>(v)) == v) ++c.components;

  // Shells: union faces across shared edges; a group is closed when none of
  // its halfedges has a faceless twin.
  UnionFind faces_uf(nf);
  std::vector<std::uint8_t> open(nf, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    if (!in_scope_face(f)) continue;
    ++c.faces;
    m.for_each_face_halfedge(FaceIdx{static_cast<std::uint32_t>(f)}, [&](HalfedgeIdx h) {
      const FaceIdx g = m.face(twin(h));
      if (g.valid())
        faces_uf.unite(static_cast<std::uint32_t>(f), g.value);
      else
        open[f] = 1;
    });
  }
  for (std::size_t f = 0; f < nf; ++f)
    if (in_scope_face(f) && open[f]) open[faces_uf.find(static_cast<std::uint32_t>(f))] = 1;
  for (std::size_t f = 0; f < nf; ++f)
    if (in_scope_face(f) && faces_uf.find(static_cast<std::uint32_t>(f)) == f && !open[f]) ++c.shells;
  return c;
}

}  // namespace

TopologyCounts count_topology(const Model& m) { return count_impl(m, SurfaceIdx{}); }
TopologyCounts count_topology(const Model& m, SurfaceIdx s) { return count_impl(m, s); }

}  // namespace atelier
