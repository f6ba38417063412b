// MESHEDGE chains: the bookkeeping of an edge split, shared by the Euler
// split (systems/mesh/euler_split.cpp), the face triangulation and the
// sketch re-triangulation, which split edges with their own face links; and
// the walk along a MESHJOINT member's chain in the joint's direction, shared
// by the profile regeneration, the pattern pieces and the demo's outfit.
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

/// The halfedge of joint member `mem` from its node t to node t + 1, in the
/// joint's direction: the member's MESHEDGE chain read forwards when the
/// member is positive, backwards on the twins otherwise (t < chain length).
[[nodiscard]] inline HalfedgeIdx joint_member_halfedge(const Model& m, const JointMember& mem, std::size_t t) {
  auto chain = m.mesh_edges.halfedges.row(mem.mesh_edge.value);
  return mem.positive ? chain[t] : twin(chain[chain.size() - 1 - t]);
}

}  // namespace atelier
