// Uniform 1-to-4 split of a whole model (seed 000 section 3 "face split",
// Fig. 5b, and the topological step of the modified variational subdivision,
// section 4.2, Fig. 15a).
//
// Every live face of every surface is split at once:
//   - a triangle becomes 4 triangles (3 corner triangles + the centre one),
//   - a quad becomes 4 quads and, in general, an n-gon (n >= 4) becomes n
//     quads around a new face-centre node (the centroid of its corners),
//   - every edge (face edges, boundary edges and wire edges) gets one new node
//     at its midpoint; old nodes keep their indices.
// Callers that want another position for a new node (the profile point
// C(1/2) of section 4.2) overwrite it through the returned SubdivisionMap.
//
// Reads: every table. Writes: every topology table (appends nodes, edges and
// faces; old edge e keeps its index as the half at its tail side), mesh edge
// chains (each halfedge becomes two, in order, direction kept), the elements
// and parameters of ATTRIB_EDGENODEs / ATTRIB_FACENODEs, topology_version.
// Mesh loops, joints, attribute edges and model.complex_holes are unchanged
// (the split keeps V - E + F - R, C, S and R, so H stays the same).
// Property columns of new elements get their fill value.
#pragma once

#include <cstdint>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

namespace atelier {

/// Where the new elements of a uniform split are, in the model after the
/// split. All indices of "old" elements refer to the model as it was right
/// before the split (after compaction when `compacted` is set).
struct SubdivisionMap {
  /// The model had tombstones and was compacted before the split; `compaction`
  /// maps the caller's pre-split indices to the ones used below.
  bool compacted = false;
  CompactRemap compaction;

  std::uint32_t old_nodes = 0;  // nodes [0, old_nodes) are the old ones
  std::uint32_t old_edges = 0;
  std::uint32_t old_faces = 0;
  /// Old edge e -> its midpoint node (= old_nodes + e).
  std::vector<NodeIdx> edge_midpoint;
  /// Old face f -> its centre node; invalid for triangles (no centre node).
  std::vector<NodeIdx> face_centre;
  /// Old face f has children f (the corner-0 child) and
  /// [face_child_begin[f], face_child_begin[f+1]) (size old_faces + 1).
  /// Triangles: children are corner 0, corner 1, corner 2, centre, where
  /// corner k is (v_k, m_k, m_{k-1}) and the centre is (m0, m1, m2), v_0 being
  /// the tail of the face's first halfedge and m_k the midpoint of side k.
  /// n-gons: child k is the quad (v_k, m_k, c, m_{k-1}).
  std::vector<FaceIdx> face_child_begin;

  [[nodiscard]] bool is_old(NodeIdx v) const noexcept { return v.value < old_nodes; }
  /// The half of old halfedge h that starts at tail(h) (ends at the midpoint).
  [[nodiscard]] HalfedgeIdx first_half(HalfedgeIdx h) const noexcept {
    return (h.value & 1u) ? HalfedgeIdx{2u * (old_edges + (h.value >> 1)) + 1u} : h;
  }
  /// The half of old halfedge h that ends at head(h) (starts at the midpoint).
  [[nodiscard]] HalfedgeIdx second_half(HalfedgeIdx h) const noexcept {
    return (h.value & 1u) ? h : HalfedgeIdx{2u * (old_edges + (h.value >> 1))};
  }
};

/// The fast split: compacts the model first when any table has tombstones,
/// sizes everything with prefix sums and fills the columns by index
/// arithmetic in parallel (through engine/parallel.h). The output tables are
/// a pure function of the input: identical for any ctx.threads.
/// ATTRIB_FACENODEs in triangles are remapped exactly; those in polygons
/// (whose fan parameters have no exact image in the quads) are re-located by
/// position into the child quad fan triangle holding them (exact up to
/// rounding for planar faces). Errors (model untouched): kCancelled when ctx
/// is cancelled on entry.
/// Ring nodes (nodes.in_face) stay attached to child 0 of their face.
[[nodiscard]] Expected<SubdivisionMap> subdivide_uniform(Model& model, const ExecContext& ctx = {});

/// The same split written naively, face by face through the Model primitives
/// (new_node / set_tail / new_edge / new_face / find_halfedge), for the
/// benchmark and as a cross-check. Produces the same tables as
/// subdivide_uniform (same indices), only much slower.
[[nodiscard]] Expected<SubdivisionMap> subdivide_uniform_naive(Model& model);

/// Re-parametrisation of an ATTRIB_FACENODE with areal coordinates `b` in the
/// parent triangle (v0, v1, v2) into the child triangle containing it
/// (children numbered as in SubdivisionMap::face_child_begin). Exact up to
/// one rounding: coordinates are 2b - 1, 2b or 1 - 2b.
struct ChildBarycentric {
  unsigned child = 0;  // 0, 1, 2: corner triangles; 3: centre
  Vec3d param;
};
[[nodiscard]] ChildBarycentric split_triangle_barycentric(const Vec3d& b) noexcept;

}  // namespace atelier
