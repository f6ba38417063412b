// High-level editing operators (seed 000 section 3, Table 3 and Fig. 5; seed
// 001 section 3): edge split, edge collapse, edge swap and the single-face
// 1-to-4 split. Each is a fixed sequence of extended Euler operators whose
// net change of every Euler-Poincare term but V, E and F is zero, so they run
// on the unchecked primitives (no O(component) connectivity search) and leave
// model.complex_holes unchanged.
//
// Joint awareness (seed 000 section 3): when the edge lies on a mesh edge of
// a joint, split and collapse act on EVERY corresponding edge of the joint's
// mesh edges (same position along the joint direction, honouring each
// member's direction flag), so the members keep equal edge counts and
// coincident nodes; edge swap on a joint edge is refused (kJointRefused).
//
// Faces are general polygons (PFACE, seed 001) with triangles the common
// case. The polygon rules are stated at each operator.
//
// Attributes: ATTRIB_EDGENODEs of a split edge move to the half holding them;
// face-nodes of replaced faces are re-attached to the new face containing
// their 3D surface position; vertex-nodes of a removed node move to the kept
// node; edge-nodes of a removed edge move to the edge that replaces it (or
// become vertex-nodes of the kept node for the collapsed edge itself).
//
// Reads and writes: node, edge, halfedge and face tables, mesh edge chains,
// attribute nodes. Never model.complex_holes.
#pragma once

#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

#include <array>
#include <vector>

namespace atelier {

struct EditOptions {
  /// Refuse when a ring node (stand-alone vertex) lies in a face the operator
  /// replaces. The check scans the node table (O(V)); callers that know the
  /// model has no ring nodes (e.g. meshes from readers) may switch it off.
  bool check_ring_nodes = true;
};

struct EdgeSplitResult {
  /// New node on each split edge: first the given edge's, then those of the
  /// other joint members in joint order.
  std::vector<Node> nodes;
};

/// Inserts a node at `position` on edge e (Table 3: kill_face_make_Chole x2,
/// split_edge, make_edge_Chole x2, make_face_kill_Chole x4). Each triangle on
/// either side becomes two triangles through the new node and the opposite
/// corner; a face with more than three sides only gains the new corner (a
/// polygon stays a valid polygon, and there is no canonical opposite corner).
/// On a joint edge every corresponding member edge is split at the same
/// position.
[[nodiscard]] Expected<EdgeSplitResult> edge_split(Model& m, Edge e, const Vec3d& position,
                                                   const EditOptions& opt = {});

struct EdgeCollapseResult {
  /// The kept node of each collapsed edge (the given edge's first).
  std::vector<Node> kept;
};

/// Collapses edge e into one node placed at `position` (Table 3). The kept
/// node is the tail of halfedge 2e, except: when e is not on a mesh edge and
/// exactly one end lies on a mesh edge, that end is kept (mesh edges are
/// constraints), and if it lies on a joint it also keeps its position
/// (`position` is ignored: the partner nodes of the joint must stay
/// coincident). Triangles on either side disappear with one of their two
/// other edges; a face with more than three sides only loses the corner.
/// Refused with a clear status when: e is a wire edge; the link condition
/// fails (a common neighbour of the ends that is not opposite e: a parallel
/// edge would appear); both ends are on the boundary while e is interior; a
/// triangle would degenerate (both other edges boundary, or both backed by
/// the same face, or its opposite node would drop below valence 3); both ends
/// lie on mesh edges not holding e; e is the only edge of its mesh edge.
/// On a joint edge the corresponding edge of every member is collapsed,
/// keeping the corresponding node; all must pass the checks.
[[nodiscard]] Expected<EdgeCollapseResult> edge_collapse(Model& m, Edge e, const Vec3d& position,
                                                         const EditOptions& opt = {});

/// Replaces the two triangles sharing interior edge e by the two sharing the
/// other diagonal (Table 3); returns the new edge (it reuses e's slot).
/// Triangles only. Refused on a joint edge (kJointRefused), on a mesh edge
/// (it would break the chain), or when the new diagonal already exists.
[[nodiscard]] Expected<Edge> edge_swap(Model& m, Edge e, const EditOptions& opt = {});

struct FaceSplitResult {
  std::array<Face, 4> faces;      // corner faces at corners 0, 1, 2, then the centre face
  std::array<Node, 3> midpoints;  // on the sides starting at corners 0, 1, 2
};

/// Splits one triangle into four through its edge midpoints (Table 3:
/// kill_face_make_Chole, split_edge x3, make_edge_Chole x3,
/// make_face_kill_Chole x4). Neighbours across ordinary edges gain the
/// midpoint as an extra corner (they become polygons). Across a joint edge
/// the midpoint is inserted on every corresponding edge of the joint and the
/// faces of those edges (other than this one) are re-triangulated: each
/// triangle is cut in two through the new node, as the paper's face
/// triangulation step does.
[[nodiscard]] Expected<FaceSplitResult> face_split_1to4(Model& m, Face f, const EditOptions& opt = {});

namespace edit_detail {
/// One step of a collapse (Table 3): the face across rout, if any, takes kin
/// in rout's place in its cycle, and rout is left faceless. Returns that face.
FaceIdx hand_over_side(Model& m, HalfedgeIdx rout, HalfedgeIdx kin);
}  // namespace edit_detail

/// The halfedges corresponding to h on every mesh edge of its joint (h
/// first), oriented so that each one's tail corresponds to tail(h). Just {h}
/// when the edge of h is not on a joint.
[[nodiscard]] std::vector<HalfedgeIdx> joint_corresponding_halfedges(const Model& m, HalfedgeIdx h);

}  // namespace atelier
