// Mesh optimisation of a region (seed 002 step 5, Fig. 9; the paper's [1],
// the remeshing of Botsch and Kobbelt 2004): the triangles of a region are
// split, collapsed and swapped with the existing edit operators
// (systems/mesh/edit.h) towards a target edge length L, and its inner nodes
// relaxed tangentially and projected back onto the region as it was on
// entry, so the surface stays where it was. Used by extrude() on the swept
// region (L = B's mean edge length, B fixed); callable on any region.
//
//  1. Rounds (options.passes, Botsch-Kobbelt): split every edge longer than
//     high L at its midpoint, collapse every edge shorter than low L (when no
//     edge of the result would be longer than high L, 2 low L in the first
//     round, in every round but the last on a region with a fold, and no
//     triangle turns over), swap edges towards valence 6 (4 on
//     a border), relax (after the first round only the nodes whose ring
//     changed). Projection: from each node's last closest triangle, a walk
//     over the region on entry; a BVH query where the walk ends farther than
//     0.02 L, and for every projection when the region on entry has a fold
//     (neighbouring triangles turned by more than 60 degrees).
//  2. Repair (beyond the paper, which states no bound): a local queue of the
//     edges still outside [low L, high L]; each is swapped, split or
//     collapsed, or its free ends relaxed, and the edges an operator touched
//     re-enter the queue (each edge at most once in it). Never a pass over
//     the whole model; budget options.repair_budget operations per region
//     edge. A stalled repair (edges left out, nothing applies) is followed
//     by a relaxation of the region and the repair again, up to three times;
//     edges still out then get two more rounds (the first with the wide
//     collapses) and the repair again.
//
// Region: the faces given (triangles), and every face an operator creates
// from them. An edge is editable when every face on it is a region face.
// Fixed nodes: `fixed` and every node of a face outside the region; they
// keep their index and position bit for bit (`fixed_chain`, a chain of
// halfedges through fixed nodes, is held by a temporary mesh edge so that
// edge_collapse keeps them; removed before returning). Nodes on an open
// border (no face beyond) move only along their border.
//
// Reads: the model. Writes: nodes, edges, faces of the region (appended,
// removed, moved), topology_version. Faces outside the region never change.
// Transactional: on error the model is unchanged (diff_tables == "").
// Errors: kInvalidArgument (target not positive and finite, low/high not
// 0 < low < 1 < high, a dead or non-triangle region
// face, a fixed node that is dead), kCancelled; an operator failing where
// its checks should have prevented it is kInternal. Single-threaded: every
// pass runs in a fixed order, so ExecContext threads change nothing.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

#include <cstddef>
#include <span>

namespace atelier {

/// Edge-length statistics of a region's editable edges.
struct EdgeLengthStats {
  std::size_t edges = 0;
  double mean = 0, min = 0, max = 0;
  double within = 0;        // fraction within [low, high] of the target length
  std::size_t outside = 0;  // edges outside [low, high] of the target length
};

struct RegionOptimiseOptions {
  double target = 0;       // L (required)
  double low = 4.0 / 5.0;  // bounds, fractions of L (Botsch-Kobbelt's)
  double high = 4.0 / 3.0;
  int passes = 4;         // rounds of step 1
  int repair_budget = 8;  // step 2 operations per region edge, at most
  bool relax = true;      // tangential relaxation + projection
};

struct RegionOptimiseReport {
  std::size_t splits = 0, collapses = 0, swaps = 0, relaxed = 0;
  EdgeLengthStats before, after;
  // Largest distance of a region node to the region on entry (an upper
  // bound of it where the walk projects: its local minimum).
  double max_deviation = 0;
  std::size_t region_faces = 0;  // after
};

[[nodiscard]] Expected<RegionOptimiseReport> optimise_region(Model& model, std::span<const FaceIdx> region,
                                                             std::span<const NodeIdx> fixed,
                                                             std::span<const HalfedgeIdx> fixed_chain,
                                                             const RegionOptimiseOptions& options,
                                                             const ExecContext& ctx = {});

}  // namespace atelier
