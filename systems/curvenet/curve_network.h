// Curve treatment (seed 003, Li & Lou 2014, section 4 "Construction of
// polygons"): a designer's curves become a graph whose nodes are the points
// where curves meet and whose segments are the curve pieces between them.
//
//   1. split (4.1): every curve is cut at every curve-curve intersection
//      (closest approach within `intersection_tolerance` x the network's
//      bounding-box diagonal, reported); the pieces meeting there end on one
//      node position, bit for bit;
//   2. prune (not in the paper): pieces with a free end (the parts of curves
//      that run past their last crossing, "dangling ends") are removed
//      repeatedly, with a warning naming their curves;
//   3. merge (4.2): two pieces meeting at a node of degree 2 become one
//      curve (knot removal) when their ends are close (`merge_distance`,
//      relative; free ends that close are joined first), their tangents
//      continue each other (`merge_angle_degrees`) and their curvatures agree
//      (`merge_curvature`, relative difference). These are the paper's three
//      thresholds; docs/glossary.md records the values.
//
// The control-point density of eq. (1) is applied later, per segment, by
// systems/curvenet/control_mesh.h (it needs the face cycles for parity).
//
// Reads: the polylines. Writes: nothing outside the returned graph.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/io/curve_network.h>

namespace atelier {

inline constexpr std::uint32_t kNoCurveNode = 0xffffffffu;

/// The treated network: nodes where curves meet, segments between them.
/// Segment s runs from node segment_nodes[s][0] to segment_nodes[s][1]
/// along points[offsets[s] .. offsets[s+1]), whose first and last points are
/// the two node positions bit for bit. A segment may start and end on the
/// same node (a closed curve with a single junction).
struct CurveGraph {
  std::vector<Vec3d> nodes;
  std::vector<std::array<std::uint32_t, 2>> segment_nodes;
  std::vector<std::uint32_t> offsets{0};
  std::vector<Vec3d> points;
  /// The input curve (index into the PolylineSet) each segment comes from;
  /// a merged segment keeps the curve of its first piece.
  std::vector<std::uint32_t> segment_curve;

  [[nodiscard]] std::size_t node_count() const noexcept { return nodes.size(); }
  [[nodiscard]] std::size_t segment_count() const noexcept { return segment_nodes.size(); }
  [[nodiscard]] std::span<const Vec3d> polyline(std::size_t s) const noexcept {
    return {points.data() + offsets[s], offsets[s + 1] - offsets[s]};
  }
  [[nodiscard]] double length(std::size_t s) const noexcept;
  /// Appends a segment; the polyline's ends must be the node positions.
  void add_segment(std::uint32_t from, std::uint32_t to, std::span<const Vec3d> polyline, std::uint32_t curve);
  /// Number of segment ends at each node (a closed segment counts twice).
  [[nodiscard]] std::vector<std::uint32_t> degrees() const;
};

struct CurveTreatmentOptions {
  /// Curves closer than this (x the bounding-box diagonal) intersect.
  double intersection_tolerance = 1e-6;
  /// Merge threshold 1: free curve ends closer than this (x the diagonal)
  /// are joined into one node; a degree-2 node qualifies for merging only
  /// when its two pieces' ends lie within it (always, after splitting).
  double merge_distance = 1e-3;
  /// Merge threshold 2: the largest angle between one piece's tangent and
  /// the other's continued tangent at the node.
  double merge_angle_degrees = 20.0;
  /// Merge threshold 3: the largest relative curvature difference
  /// |k1 - k2| / max(k1, k2, 1 / diagonal).
  double merge_curvature = 0.75;
  bool merge = true;
  bool prune_dangling = true;
  /// Intersections closer than this along one curve (x the diagonal) are
  /// one intersection; a run of close approaches longer than 100 times it
  /// is two curves running on top of each other (refused as duplicates).
  double cluster_length = 1e-4;
};

struct CurveTreatmentReport {
  std::size_t input_curves = 0;
  std::size_t input_points = 0;
  double diagonal = 0;              // bounding-box diagonal of the input
  double tolerance = 0;             // absolute intersection tolerance used
  std::size_t intersections = 0;    // crossing points found (after clustering)
  double max_intersection_gap = 0;  // largest closest-approach distance snapped into a node
  std::size_t splits = 0;           // pieces created beyond one per curve
  std::size_t joined_ends = 0;      // free ends joined by merge threshold 1
  std::size_t merges = 0;           // degree-2 nodes removed (knot removals)
  std::size_t kinks = 0;            // degree-2 nodes kept: tangent or curvature threshold refused
  std::size_t pruned_segments = 0;
  double pruned_length = 0;
  std::vector<std::int64_t> pruned_curve_ids;  // sorted, unique
  std::vector<std::string> warnings;
};

struct TreatedCurves {
  CurveGraph graph;
  CurveTreatmentReport report;
};

/// Split, prune and merge (see the file comment). Errors (kInvalidArgument
/// naming the curve): fewer than 2 distinct points, a non-finite point, two
/// curves running on top of each other (duplicates), a degenerate network
/// (all points equal); kTopology when nothing but dangling ends remains
/// (the network has no cycle). Deterministic: the graph does not depend on
/// ctx.threads.
[[nodiscard]] Expected<TreatedCurves> treat_curves(const PolylineSet& curves, const CurveTreatmentOptions& opt = {},
                                                   const ExecContext& ctx = {});

}  // namespace atelier
