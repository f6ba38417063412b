// Internals shared by the sources of the Euler operators
// (systems/mesh/euler.h):
//
//   euler.cpp        the make/kill operators and the connectivity queries
//   euler_split.cpp  split_edge / merge_edge and the raw split edit.cpp uses
#pragma once

#include <cstdint>

#include <atelier/storage/model.h>
#include <atelier/systems/mesh/euler.h>

namespace atelier::euler_detail {

/// The columns of node v (what make needs to put it back).
inline NodeRecord node_record(const Model& m, NodeIdx v) {
  NodeRecord r;
  r.surface = m.nodes.surface[v.value];
  r.position = m.nodes.position[v.value];
  r.position_backup = m.nodes.position_backup[v.value];
  r.uv = m.nodes.uv[v.value];
  r.in_face = m.nodes.in_face[v.value];
  return r;
}

// Attribute references: O(number of attribute nodes), which is small next to
// the mesh (profiles and feature points).
inline bool node_has_attrib(const Model& m, NodeIdx v) {
  const auto& an = m.attrib_nodes;
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
    if (an.slots.alive(AttribNodeIdx{i}) && an.kind[i] == AttribNodeKind::kVertex && an.element[i] == v.value)
      return true;
  return false;
}

}  // namespace atelier::euler_detail
