// Face cycles of a treated curve network (seed 003 section 5): the closed
// chains of segments that bound the surface patches.
//
// Default, kAngular (ours): at every node the segments are ordered by the
// angle of their tangents in the node's tangent plane (normal from the
// traced mesh when given, else from the curves: the plane of the tangents,
// oriented consistently across the network), and faces are traced with the
// face on the left of every segment (a rotation system). An open network
// gets one extra cycle running around its outer boundary clockwise about
// the normals; it is recognised by its orientation (the mean cosine between
// its vector area and its nodes' normals is negative) and reported once as
// `outer`, not as a face. (Holes of a traced mesh are not recognised: a
// cycle around one becomes a face, as in the paper, section 7.)
//
// kPaperSearch, the paper's method as printed (5.1-5.3) made deterministic:
// starting from the smallest free edge (used by fewer than two validated
// cycles), every simple cycle through it over free edges of at most
// `max_cycle_length` segments is enumerated by depth-first search, weighted
// by eq. (2) k = n + n(m - 1) (n: segments, m: connected components of the
// network without the cycle's edges, isolated nodes ignored), ties broken by
// the smaller bounding-box volume, then by the sorted segment list. It is
// kept for comparison: it picks non-faces (on roof_75 a 4-cycle around two
// triangles scores below a pentagon face) and on open networks its stop rule
// (every edge in two cycles) is never met (report: stop_rule_met = false).
//
// Reads: the graph (and the optional normals). Writes: nothing.
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/systems/curvenet/curve_network.h>

namespace atelier {

enum class FaceCycleMethod : std::uint8_t { kAngular, kPaperSearch };

struct FaceCycleOptions {
  FaceCycleMethod method = FaceCycleMethod::kAngular;
  /// One unit normal per node (e.g. from the traced mesh); empty: from the
  /// curves (curve_node_normals).
  std::span<const Vec3d> node_normals;
  /// kPaperSearch: longest cycle enumerated, in segments.
  std::size_t max_cycle_length = 8;
};

/// Dart d = 2 s + r runs along segment s forwards (r = 0, from
/// segment_nodes[s][0]) or backwards (r = 1).
[[nodiscard]] constexpr std::uint32_t dart_segment(std::uint32_t d) noexcept {
  return d >> 1;
}

struct FaceCycles {
  /// Face f: darts[offsets[f] .. offsets[f+1]), in order, the face on the
  /// left of each dart (counter-clockwise about the node normals).
  std::vector<std::uint32_t> offsets{0};
  std::vector<std::uint32_t> darts;
  /// Cycles set aside: the outer boundary of an open network, holes.
  std::vector<std::uint32_t> outer_offsets{0};
  std::vector<std::uint32_t> outer_darts;

  std::size_t nodes = 0, segments = 0;
  std::map<std::size_t, std::size_t> faces_by_size;  // segments per face -> count
  std::size_t segments_in_two_faces = 0;
  std::size_t segments_in_one_face = 0;
  std::size_t segments_in_no_face = 0;
  bool stop_rule_met = true;  // kPaperSearch: every segment ended in two cycles

  [[nodiscard]] std::size_t face_count() const noexcept { return offsets.size() - 1; }
  [[nodiscard]] std::size_t outer_count() const noexcept { return outer_offsets.size() - 1; }
  [[nodiscard]] std::span<const std::uint32_t> face(std::size_t f) const noexcept {
    return {darts.data() + offsets[f], offsets[f + 1] - offsets[f]};
  }
  [[nodiscard]] std::span<const std::uint32_t> outer(std::size_t f) const noexcept {
    return {outer_darts.data() + outer_offsets[f], outer_offsets[f + 1] - outer_offsets[f]};
  }
  /// V - E + F over nodes, segments and faces (outer cycles not counted).
  [[nodiscard]] std::int64_t euler() const noexcept {
    return static_cast<std::int64_t>(nodes) - static_cast<std::int64_t>(segments) +
           static_cast<std::int64_t>(face_count());
  }
};

/// Unit normals at the nodes from the curves alone: the normal of the plane
/// best fitting the tangents leaving the node (smallest eigenvector), or,
/// when they fit no plane (a cube's corner), the opposite of their mean; signs
/// made consistent along segments (breadth-first), the whole set turned so
/// that it points away from the network's centroid on average.
[[nodiscard]] std::vector<Vec3d> curve_node_normals(const CurveGraph& g);

/// Finds the face cycles (see the file comment). Errors: kInvalidArgument
/// for normals of the wrong count or non-finite; kTopology when no face is
/// found (the network has no cycle).
[[nodiscard]] Expected<FaceCycles> find_face_cycles(const CurveGraph& g, const FaceCycleOptions& opt = {},
                                                    const ExecContext& ctx = {});

}  // namespace atelier
