// The MESHEDGE bookkeeping of an edge split, shared by the Euler split
// (systems/mesh/euler_split.cpp), the face triangulation and the sketch
// re-triangulation, which split edges with their own face links.
#pragma once

#include <atelier/storage/model.h>

namespace atelier {

/// After edge_of(h) was split at a new node into h then g (their twins
/// twin(g) then twin(h)): the new edge joins the MESHEDGE of edge_of(h), next
/// to it in chain order (g after h, or twin(g) before twin(h), whichever the
/// chain lists), and records that membership. Nothing happens when
/// edge_of(h) is on no MESHEDGE.
inline void chain_split_edge(Model& m, HalfedgeIdx h, HalfedgeIdx g) {
  const MeshEdgeIdx me = m.edges.mesh_edge[edge_of(h).value];
  if (!me.valid()) return;
  const HalfedgeIdx t = twin(h);
  auto row = m.mesh_edges.halfedges.row(me.value);
  for (std::size_t i = 0; i < row.size(); ++i) {
    if (row[i] == h) {
      m.mesh_edges.halfedges.insert(me.value, i + 1, g);
      break;
    }
    if (row[i] == t) {
      m.mesh_edges.halfedges.insert(me.value, i, twin(g));
      break;
    }
  }
  m.edges.mesh_edge[edge_of(g).value] = me;
}

}  // namespace atelier
