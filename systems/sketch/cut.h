// Mesh cutting and mesh partitioning by painted curves (seed 001 section 5,
// Figs. 12-13 and 15). Both re-triangulate the curves into mesh edges
// (systems/sketch/retriangulate.h), then split the faces of the surfaces the
// curves run on into pieces: sets of faces connected across edges that are
// not on a curve.
//
//  - Cutting removes the faces on one side: the piece holding a picked
//    surface point (the "second stroke" of Fig. 12; only that piece is
//    grown, so the cost is the removed side's, plus one pass for the
//    areas), or, without a pick, every piece of a crossed component but its
//    largest (by area). A curve that separates nothing is refused and
//    nothing changes.
//  - Partitioning makes every piece its own MESHSURFACE (the first piece of
//    each surface keeps it; the others get "<name>.<k>"), seam nodes and
//    edges are duplicated, and neighbouring pieces are joined by MESHJOINTs
//    along the curves: one mesh edge per side, opposite directions, so the
//    pieces stay one non-manifold model with equal edge counts and
//    coincident nodes on every joint (seed 001 section 3, Fig. 4).
//
// Reads and writes: every table of the surfaces involved. Removed or moved
// faces take their ATTRIB_FACENODEs with them (removed: deleted; moved: to
// the piece's new surface); attribute edges whose nodes end up in several
// surfaces are split into one attribute edge per run (the first keeps the
// original index). The curves stay as attribute edges (cutting: on the
// boundary left; partitioning: on the piece to the left of the curve).
// model.complex_holes is recounted (count_topology): removing faces and
// unzipping seams change C and S as well as V - E + F.
//
// Transactional: on any error the tables are unchanged (diff_tables == "").
// Errors: those of retriangulate_curves; kInvalidArgument (the curves do not
// separate the surface, a pick outside the model or on the curve);
// kJointRefused (the cut would remove part of a joint's mesh edge, a piece
// boundary would cut a joint's mesh edge, a curve runs along an existing
// mesh edge); kUnsupported (ring nodes in faces to remove or move).
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/surface_location.h>
#include <atelier/systems/sketch/retriangulate.h>

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace atelier {

/// One piece: faces of one surface connected across non-curve edges.
struct Piece {
  Surface surface;  // after the operation (partitioning: its own surface)
  std::size_t faces = 0;
  double area = 0;       // sum of fan-triangle areas
  bool removed = false;  // cutting: the piece removed
};

struct CutOptions {
  /// The side to remove: the piece holding this surface location of the
  /// model as it is before the cut. Without it, every piece of each crossed
  /// component but the largest is removed.
  std::optional<SurfaceLocation> pick;
  /// With a pick: also sum the area and face count of the side kept (one
  /// pass over every face of the surfaces the curves cross). Off, the result
  /// holds only the removed piece and kept_area is 0; the removed piece's
  /// area costs nothing extra (it is summed while the piece is grown).
  /// Without a pick every piece is measured anyway and this is ignored.
  bool kept_totals = true;
  RetriangulateOptions retriangulate;
};

struct CutResult {
  /// With a pick: the removed piece, then the rest of the surfaces the
  /// curves cross (one entry: the picked side is grown, the rest is not
  /// split into pieces; left out when options.kept_totals is false). Without: every piece of the crossed components,
  /// removed ones included.
  std::vector<Piece> pieces;
  double removed_area = 0, kept_area = 0;
  std::size_t faces_removed = 0, nodes_removed = 0;
  std::size_t faces_added = 0, nodes_added = 0, crossings = 0;  // by the re-triangulation
};

/// Cuts the model along the curves (see above).
[[nodiscard]] Expected<CutResult> cut_along_curves(Model& model, std::span<const AttribEdge> curves,
                                                   const CutOptions& options = {}, const ExecContext& ctx = {});

struct PartitionOptions {
  RetriangulateOptions retriangulate;
};

struct PartitionResult {
  std::vector<Piece> pieces;                                    // every piece of the surfaces the curves run on
  std::vector<Surface> new_surfaces;                            // surfaces made for pieces
  std::vector<Joint> joints;                                    // seams between pieces
  std::size_t faces_added = 0, nodes_added = 0, crossings = 0;  // by the re-triangulation
  std::size_t seam_nodes = 0;                                   // nodes duplicated along seams
};

/// Partitions the surfaces along the curves (see above).
[[nodiscard]] Expected<PartitionResult> partition_along_curves(Model& model, std::span<const AttribEdge> curves,
                                                               const PartitionOptions& options = {},
                                                               const ExecContext& ctx = {});

}  // namespace atelier
