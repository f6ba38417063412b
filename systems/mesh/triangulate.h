// Face triangulation, the 5th high-level operator of seed 000 section 3
// (Table 3, Fig. 5c): ATTRIB_FACENODEs in the face become nodes, the face's
// edges are split at their ATTRIB_EDGENODEs, ATTRIB_EDGE segments through the
// face become constraint edges, and the face is replaced by a constrained
// Delaunay triangulation (CGAL, exact predicates) of its boundary polygon in
// its least-squares plane. New triangles keep the face's orientation.
//
// Reads: the face, its edges, its neighbours across split edges, attribute
// nodes/edges. Writes: nodes (new ones for attribute nodes), edges (split
// edges, diagonals), faces (the face is replaced; neighbours across a split
// edge gain corners), mesh edge chains through split edges, attribute nodes
// (converted ones become kVertex nodes on the new mesh node, so attribute
// edges keep their order; face nodes of grown neighbours are re-located in
// their fan), topology_version. model.complex_holes is unchanged: each split
// adds one node and one edge, and a polygon with B boundary and I interior
// points gets B-3+3I diagonals and B-2+2I triangles, so V - E + F is kept.
//
// Neighbours: when a split edge has a face on its other side, that face gains
// the new corners and stays a valid (planar, collinear-cornered) polygon; it
// is listed in TriangulationResult::grown_faces and, with
// TriangulateOptions::triangulate_grown, triangulated as well.
//
// Joints: when a split edge lies on a mesh edge of a MESHJOINT, the
// corresponding edge of every other member is split at the same points
// (new nodes at the same positions), so the joint stays crack-free; the
// partners' faces gain corners like neighbours do.
//
// Errors leave the model untouched: kStaleHandle, kJointRefused (a joint
// partner edge to split carries attribute edge-nodes of its own),
// kUnsupported (ring nodes lie in the face),
// kDegenerate (no plane, points outside the polygon or projecting onto one
// another, crossing constraints, a triangle flipped against the face normal).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

namespace atelier {

struct TriangulateOptions {
  /// Also triangulate the neighbours that gained corners from edge splits
  /// (repeatedly, with their own attributes converted too).
  bool triangulate_grown = false;
  /// Points closer than this fraction of the face's diameter are merged.
  double merge_tolerance = 1e-9;
};

struct TriangulationResult {
  std::vector<FaceIdx> faces;        // the new triangles
  std::vector<NodeIdx> new_nodes;    // nodes made from attribute nodes
  std::vector<FaceIdx> grown_faces;  // neighbours that gained corners and are still polygons
};

/// Triangulates one face with its attributes (see above). Cost: one scan of
/// the node and attribute tables (ring nodes, attributes touching the face)
/// plus the CDT of the face's points.
[[nodiscard]] Expected<TriangulationResult> triangulate_face(Model& model, Face face,
                                                             const TriangulateOptions& opt = {});
/// Triangulates each face in turn (stops at the first error; faces done
/// before it stay done). Faces made stale by earlier ones are an error.
[[nodiscard]] Expected<TriangulationResult> triangulate_faces(Model& model, std::span<const Face> faces,
                                                              const TriangulateOptions& opt = {});
/// Whole model: every face with more than 3 sides becomes triangles of its
/// boundary polygon (no edge is split, no node is added). Attribute nodes stay
/// attributes: face nodes move into the triangle holding them. Returns the
/// number of polygons triangulated. Stops at the first error (kUnsupported
/// for ring nodes, kDegenerate...); polygons done before it stay done.
[[nodiscard]] Expected<std::size_t> triangulate_polygons(Model& model, const ExecContext& ctx = {});

}  // namespace atelier
