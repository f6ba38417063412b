// Partial re-triangulation by painted curves (seed 002 section 3.1, Figs. 2-3;
// seed 001 section 5, the step shared by cutting and partitioning): the
// curves (ATTRIB_EDGEs) become chains of mesh edges.
//
//  1. Intersections of the curves (with each other and themselves) are
//     computed in the fan triangle holding both segments, in its areal
//     coordinates (so they do not depend on where the nodes are: the same
//     curve on a regenerated garment crosses at the same place), and
//     inserted into both curves as one shared node.
//  2. Curve points become nodes: edge points split their edges (on a joint
//     edge, every member's corresponding edge is split at the same
//     parameters, so the joint stays crack-free), face points become nodes.
//  3. Every face holding a new node, on its sides or inside, is replaced by
//     the constrained Delaunay triangulation (exact predicates; CGAL's CDT
//     where a fan holds two or more stroke points, else built directly) of each
//     of its fan triangles (c0, c_k+1, c_k+2) in that triangle's plane, with
//     the curve segments as constraints: new nodes lie exactly on the surface
//     the attribute nodes were defined on, existing nodes never move, and
//     the area is kept (exactly for triangles and planar polygons; a
//     non-planar polygon keeps the area of its fan triangles).
//  4. The curves' attribute nodes become ATTRIB_NODEs (kVertex) on their
//     mesh nodes; other attribute nodes in the replaced faces or on split
//     edges are re-attached where they were (same 3D point).
//
// Reads: the curves, the faces, edges, joints and attribute nodes they
// touch, the node table (ring nodes). Writes: nodes (appended), edges
// (split, new), faces (replaced), mesh edge chains through split edges,
// attribute nodes and the curves' rows, topology_version. The
// Euler-Poincare terms C, S, R and H are unchanged (each split adds one node
// and one edge; a polygon with B boundary and I inner points gets B-2+2I
// triangles and B-3+3I inner edges).
//
// Transactional: everything is planned and checked before the first write;
// on error the model is unchanged. Errors: kStaleHandle, kInvalidArgument
// (two consecutive curve nodes in no common face, a dead curve), kDegenerate
// (overlapping curves, points closer than the snap tolerance in a plane, a
// degenerate fan triangle holding points), kUnsupported (ring nodes in a
// face to replace), kTopology (a new edge would duplicate an existing one).
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/surface_location.h>

#include <cstddef>
#include <span>
#include <vector>

namespace atelier {

struct RetriangulateOptions {
  /// Curve points closer than this in edge parameter or areal coordinates
  /// are one point; points this close to a corner are the corner.
  double snap = 1e-9;
  /// Surface locations (in the model before the call) to follow through
  /// the re-triangulation, e.g. the pick of a cut; see probes below.
  std::vector<SurfaceLocation> probes;
  /// A fan triangle holding at most one stroke point (with its spokes) or
  /// only chords between points on its sides is triangulated directly (a
  /// fan or ear clipping, then Lawson's flips by exact predicates: the
  /// constrained Delaunay triangulation) instead of building CGAL's CDT.
  /// False sends every fan through the CDT (the tests show both give the
  /// same tables).
  bool chords_without_cdt = true;
};

struct RetriangulationResult {
  /// Per input curve, the mesh halfedges along it in curve order (a closed
  /// curve's chain ends where it starts).
  std::vector<std::vector<HalfedgeIdx>> chains;
  /// Per input curve, its mesh nodes in order (crossings included).
  std::vector<std::vector<NodeIdx>> nodes;
  /// The probes located in the new faces (kFace with corner 0, or kVertex
  /// on a node), and the smallest areal coordinate of each in its face
  /// (0 on an edge).
  std::vector<SurfaceLocation> probes;
  std::vector<double> probe_margin;
  std::size_t crossings = 0;      // curve-curve intersections inserted
  std::size_t nodes_added = 0;    // joint partner splits included
  std::size_t edges_split = 0;    // edges cut into pieces
  std::size_t faces_removed = 0;  // faces replaced
  std::size_t faces_added = 0;
  std::size_t fans_without_cdt = 0;  // fan triangles split directly (see chords_without_cdt)
};

/// Makes the curves mesh edges (see above).
[[nodiscard]] Expected<RetriangulationResult> retriangulate_curves(Model& model, std::span<const AttribEdge> curves,
                                                                   const RetriangulateOptions& options = {},
                                                                   const ExecContext& ctx = {});

}  // namespace atelier
