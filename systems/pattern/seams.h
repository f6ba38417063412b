// Seams that make closed tubes flattenable (issue 22): a sleeve, a skirt, a
// trouser leg or a collar is a tube (two boundary loops), a top's body has
// four (hip, neck, two armholes); flattening needs a topological disk, so
// these pieces are opened along seams first.
//
// Where seams come from:
//  * a sketch partition curve (systems/sketch/cut.h partition_along_curves)
//    that separates the tube already makes pieces joined by MESHJOINTs:
//    those pieces flatten as they are (this file is not needed for them);
//  * a seam path: a chain of the model's edges from boundary to boundary
//    (`SeamOptions::paths`), e.g. a profile edge the template marks as a
//    seam, or a single generator of a tube, which no partition curve can
//    express (one curve on a tube separates nothing);
//  * marked seams (`SeamOptions::marked`): edges carrying the kEdgeSeam
//    flag (storage/edge_flags.h), which a profile template sets on the
//    edges it marks as seams (TemplateBuilder::seam) and which every edge
//    split copies, so a regenerated garment carries them on every body.
//    Interior marked edges are chained between end nodes (a boundary node
//    or a node with other than two marked edges; a closed loop starts at
//    its smallest node), in node order. A marked run off joints opens like
//    a given path; a marked run along an inner joint member (a collar
//    sewn on an inner line) opens too, and the member's other side joins
//    that joint as one more member (a three-layer seam), so the piece sewn
//    on the inner line is sewn onto the boundaries of the pieces it
//    separates. Marked seams that close off a region split the surface:
//  * pieces: after opening, the faces of a surface joined across non-seam
//    edges form its pieces; a surface the seams separate becomes several
//    surfaces, named "<name>", "<name>.1", "<name>.2", ... in the order of
//    their first faces (so the same on every body of one template);
//  * automatic seams (`SeamOptions::automatic`): for every piece with more
//    than one boundary loop, paths from its first loop to each other loop,
//    each the path of fewest edges (breadth-first, ties to the smaller node
//    index), avoiding mesh edges (joints, profiles) and their nodes where it
//    can. The choice depends only on the topology: a garment regenerated on
//    any body gets the same seams, so its patterns are comparable body to
//    body (the same pieces, notches and named lines).
//
// Opening a seam: the faces around a node on a seam path fall into wedges
// separated by seam edges (corners of a node joined across the non-seam
// edges they share); each wedge gets its own copy of the node, so the seam
// becomes two boundary chains, joined by a MESHJOINT (both members in the
// path's direction, positive) whose sewability make_pattern checks. Nodes on
// no seam keep one copy. The input's joints are carried over (their mesh
// edges mapped to the new halfedges; a joint chain that a seam crosses is
// cut there into several joints, all members at the same place).
//
// The result is a new model (the input is not modified): surfaces in the
// input's order with their names, nodes with their positions, faces in the
// input's order (a polygon whose fan from its first corner would have a
// degenerate triangle, as one with collinear corners at a T-junction of a
// refined neighbour has, starts at the corner whose fan's smallest triangle
// is largest: flattening fans polygons from their first corner), joints, no attribute nodes or edges (marks do not
// carry over: notches come from the seam ends). `source_node` maps each node back.
//
// Reads: the surfaces' faces, nodes.position, edges.flags (kEdgeSeam), mesh
// edges and joints.
// Errors: kStaleHandle (a dead surface), kInvalidArgument (a path node not
// alive, two path nodes not joined by an edge, a path edge on a boundary or
// in no face pair, a path of fewer than two nodes), kTopology (a closed
// surface without any seam: no boundary to start one from; a loop the
// automatic seams cannot reach), and those of add_polygon_surface.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

#include <span>
#include <vector>

namespace atelier {

struct SeamOptions {
  /// Surfaces to open (empty: every live surface with faces). Other
  /// surfaces are copied as they are.
  std::vector<SurfaceIdx> surfaces;
  /// Seam paths: node chains along edges of one surface, boundary to
  /// boundary (or boundary to inside: a dart).
  std::vector<std::vector<NodeIdx>> paths;
  /// Marked seams (edges with kEdgeSeam) are cut.
  bool marked = true;
  /// Automatic seams for pieces that still have several boundary loops.
  bool automatic = true;
};

struct OpenedSeams {
  Model model;
  std::vector<NodeIdx> source_node;         // per node slot of `model`: its node in the input
  std::vector<SurfaceIdx> surfaces;         // per input surface slot: its (first) surface in `model` (or invalid)
  std::vector<SurfaceIdx> part_of;          // per surface slot of `model`: the input surface it is part of
  std::vector<std::vector<NodeIdx>> paths;  // every seam opened (input nodes), given ones first
  std::vector<JointIdx> seam_joints;        // per path: its joint in `model`
  std::size_t marked_along_joints = 0;      // marked runs along joint members (no path: their joints grew)
};

/// Opens the seams (see above) on a copy of `m`.
[[nodiscard]] Expected<OpenedSeams> open_seams(const Model& m, const SeamOptions& opt = {},
                                               const ExecContext& ctx = {});

}  // namespace atelier
