// diff_tables (storage/model.h): the first differences between two models'
// live slots, bit for bit (how the tests show that a failed operator left
// the tables unchanged and that make(kill(x)) restores them).
#include <atelier/storage/model.h>

#include <algorithm>
#include <cstring>
#include <sstream>
#include <string>
#include <type_traits>

namespace atelier {

namespace {

struct Differ {
  std::ostringstream out;
  bool found = false;
  template <class A, class B>
  void note(const char* what, std::size_t i, const A&, const B&) {
    if (found) return;
    found = true;
    out << what << " differs at " << i;
  }
};

template <class Tag>
bool live_sets_equal(const SlotTable<Tag>& a, const SlotTable<Tag>& b, const char* kind, Differ& d) {
  const std::size_t n = std::max(a.capacity(), b.capacity());
  for (std::size_t i = 0; i < n; ++i) {
    const bool la = a.alive(Idx<Tag>{static_cast<std::uint32_t>(i)});
    const bool lb = b.alive(Idx<Tag>{static_cast<std::uint32_t>(i)});
    if (la != lb) {
      if (!d.found) {
        d.found = true;
        d.out << kind << " " << i << " is " << (la ? "alive" : "dead") << " in the first model and "
              << (lb ? "alive" : "dead") << " in the second";
      }
      return false;
    }
  }
  return true;
}

template <class T>
bool bits_equal(const T& a, const T& b) {
  if constexpr (std::is_same_v<T, Vec3d> || std::is_same_v<T, Vec2d>) {
    return std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
  } else {
    return a == b;
  }
}

template <class Tag, class T>
void cmp_col(const SlotTable<Tag>& slots, const std::vector<T>& a, const std::vector<T>& b, const char* what,
             Differ& d, std::size_t stride = 1) {
  if (d.found) return;
  for (std::size_t i = 0; i < slots.capacity(); ++i) {
    if (!slots.alive(Idx<Tag>{static_cast<std::uint32_t>(i)})) continue;
    for (std::size_t s = 0; s < stride; ++s)
      if (!bits_equal(a[stride * i + s], b[stride * i + s])) {
        d.found = true;
        d.out << what << " differs at " << stride * i + s;
        return;
      }
  }
}

template <class Tag, class T>
void cmp_ragged(const SlotTable<Tag>& slots, const RaggedColumn<T>& a, const RaggedColumn<T>& b, const char* what,
                Differ& d) {
  if (d.found) return;
  for (std::size_t i = 0; i < slots.capacity(); ++i) {
    if (!slots.alive(Idx<Tag>{static_cast<std::uint32_t>(i)})) continue;
    auto ra = a.row(i), rb = b.row(i);
    if (!std::equal(ra.begin(), ra.end(), rb.begin(), rb.end())) {
      d.found = true;
      d.out << what << " list differs at " << i;
      return;
    }
  }
}

}  // namespace

std::string diff_tables(const Model& a, const Model& b) {
  Differ d;
  if (a.complex_holes != b.complex_holes) {
    d.found = true;
    d.out << "complex hole count differs: " << a.complex_holes << " vs " << b.complex_holes;
    return d.out.str();
  }
  if (live_sets_equal(a.nodes.slots, b.nodes.slots, "node", d)) {
    const auto& s = a.nodes.slots;
    cmp_col(s, a.nodes.position, b.nodes.position, "node position", d);
    cmp_col(s, a.nodes.position_backup, b.nodes.position_backup, "node backup position", d);
    cmp_col(s, a.nodes.uv, b.nodes.uv, "node uv", d);
    cmp_col(s, a.nodes.out, b.nodes.out, "node outgoing halfedge", d);
    cmp_col(s, a.nodes.surface, b.nodes.surface, "node surface", d);
    cmp_col(s, a.nodes.in_face, b.nodes.in_face, "node in_face", d);
  }
  if (!d.found && live_sets_equal(a.edges.slots, b.edges.slots, "edge", d)) {
    const auto& s = a.edges.slots;
    cmp_col(s, a.edges.flags, b.edges.flags, "edge flags", d);
    cmp_col(s, a.edges.mesh_edge, b.edges.mesh_edge, "edge mesh edge", d);
    cmp_col(s, a.halfedges.tail, b.halfedges.tail, "halfedge tail", d, 2);
    cmp_col(s, a.halfedges.face, b.halfedges.face, "halfedge face", d, 2);
    cmp_col(s, a.halfedges.next, b.halfedges.next, "halfedge next", d, 2);
    cmp_col(s, a.halfedges.prev, b.halfedges.prev, "halfedge prev", d, 2);
    cmp_col(s, a.halfedges.vnext, b.halfedges.vnext, "halfedge vnext", d, 2);
    cmp_col(s, a.halfedges.vprev, b.halfedges.vprev, "halfedge vprev", d, 2);
  }
  if (!d.found && live_sets_equal(a.faces.slots, b.faces.slots, "face", d)) {
    const auto& s = a.faces.slots;
    cmp_col(s, a.faces.halfedge, b.faces.halfedge, "face halfedge", d);
    cmp_col(s, a.faces.surface, b.faces.surface, "face surface", d);
    cmp_col(s, a.faces.flags, b.faces.flags, "face flags", d);
  }
  if (!d.found && live_sets_equal(a.surfaces.slots, b.surfaces.slots, "surface", d))
    cmp_col(a.surfaces.slots, a.surfaces.name, b.surfaces.name, "surface name", d);
  if (!d.found && live_sets_equal(a.mesh_edges.slots, b.mesh_edges.slots, "mesh edge", d)) {
    const auto& s = a.mesh_edges.slots;
    cmp_col(s, a.mesh_edges.surface, b.mesh_edges.surface, "mesh edge surface", d);
    cmp_col(s, a.mesh_edges.loop, b.mesh_edges.loop, "mesh edge loop", d);
    cmp_col(s, a.mesh_edges.joint, b.mesh_edges.joint, "mesh edge joint", d);
    cmp_ragged(s, a.mesh_edges.halfedges, b.mesh_edges.halfedges, "mesh edge halfedge", d);
  }
  if (!d.found && live_sets_equal(a.mesh_loops.slots, b.mesh_loops.slots, "mesh loop", d)) {
    cmp_col(a.mesh_loops.slots, a.mesh_loops.surface, b.mesh_loops.surface, "mesh loop surface", d);
    cmp_ragged(a.mesh_loops.slots, a.mesh_loops.mesh_edges, b.mesh_loops.mesh_edges, "mesh loop", d);
  }
  if (!d.found && live_sets_equal(a.joints.slots, b.joints.slots, "joint", d))
    cmp_ragged(a.joints.slots, a.joints.members, b.joints.members, "joint member", d);
  if (!d.found && live_sets_equal(a.attrib_nodes.slots, b.attrib_nodes.slots, "attribute node", d)) {
    const auto& s = a.attrib_nodes.slots;
    cmp_col(s, a.attrib_nodes.kind, b.attrib_nodes.kind, "attribute node kind", d);
    cmp_col(s, a.attrib_nodes.element, b.attrib_nodes.element, "attribute node element", d);
    cmp_col(s, a.attrib_nodes.corner, b.attrib_nodes.corner, "attribute node corner", d);
    cmp_col(s, a.attrib_nodes.param, b.attrib_nodes.param, "attribute node param", d);
    cmp_col(s, a.attrib_nodes.position, b.attrib_nodes.position, "attribute node position", d);
    cmp_col(s, a.attrib_nodes.owner, b.attrib_nodes.owner, "attribute node owner", d);
  }
  if (!d.found && live_sets_equal(a.attrib_edges.slots, b.attrib_edges.slots, "attribute edge", d)) {
    const auto& s = a.attrib_edges.slots;
    cmp_col(s, a.attrib_edges.surface, b.attrib_edges.surface, "attribute edge surface", d);
    cmp_col(s, a.attrib_edges.feature_id, b.attrib_edges.feature_id, "attribute edge feature", d);
    cmp_ragged(s, a.attrib_edges.nodes, b.attrib_edges.nodes, "attribute edge node", d);
  }
  return d.out.str();
}

}  // namespace atelier
