// The fit of a garment on a body, as `atelier measure` reports it and as the
// batch report's quality columns define it (issues 6 and 7): penetration,
// clearance, and, given the same garment on a source body, the clearance
// change and the excess edge strain.
//
// Definitions (every figure is independent of the pass that produced the
// garment: distances come from the exact BVH signed distance):
//  * penetration: vertices with signed distance < 0, and < -tolerance;
//    the largest depth;
//  * clearance: the signed distance of each vertex (min, mean, p50, p95);
//  * clearance change: RMS over vertices of (signed distance on the body -
//    signed distance of the source garment on the source body);
//  * edge strain: |l / l_source - 1| per garment edge;
//  * excess edge strain: |garment strain - body strain| per edge, where the
//    body strain is that of the source edge vector carried by the affine
//    map of the body triangle under the edge's midpoint (its two edges and
//    unit normal on the source body to the same on the new body): the stretch
//    of an edge that followed the skin exactly. Needs the source body with
//    the same topology as the body.
//
// Reads: body positions and triangles, garment positions and edges (and the
// source pair). Writes: nothing but the result.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/spatial/collision_body.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace atelier {

struct FitMeasureParams {
  double inside_tolerance = 0.001;  // "more than 1 mm inside"
};

struct FitMeasure {
  std::size_t vertices = 0;
  std::size_t edges = 0;
  std::size_t inside = 0;            // signed distance < 0
  std::size_t inside_tolerance = 0;  // signed distance < -tolerance
  double max_depth = 0;              // largest -distance (0 when none inside)
  double clearance_min = 0, clearance_mean = 0, clearance_p50 = 0, clearance_p95 = 0;
  bool has_source = false;       // a source garment was given: edge_strain_p95 is set
  bool has_source_body = false;  // and its body: clearance_change_rms, excess_strain_p95 are set
  double edge_strain_p95 = 0;
  double clearance_change_rms = 0;
  double excess_strain_p95 = 0;
};

/// A garment on a body. `source_*` are optional (empty spans): the garment
/// as designed (same vertex count and edges) and the body it was designed
/// on (same topology as `body_points`).
struct FitInput {
  std::span<const Vec3d> body_points;
  std::span<const Triangle> body_triangles;
  std::span<const Vec3d> garment;
  std::span<const std::array<std::uint32_t, 2>> garment_edges;
  std::span<const Vec3d> source_garment;
  std::span<const Vec3d> source_body_points;
};

/// Errors: open or empty body (naming the first bad edge), empty garment,
/// edge index out of range, non-finite vertex (naming it), source arrays of
/// the wrong size.
[[nodiscard]] Expected<FitMeasure> measure_fit(const FitInput& in, const FitMeasureParams& params = {},
                                               const ExecContext& ctx = {});

/// p-quantile by the nearest-rank rule used by every report (index
/// floor(q n), clamped); 0 for an empty array. Sorts its argument.
[[nodiscard]] double quantile_in_place(std::vector<double>& v, double q);

/// Inter-garment penetration (issue 26, outfits): an outer garment's vertex
/// p is "inside" an inner garment G when G passes above it: the ray from p's
/// closest body point x along the body's outward normal n there (the ray
/// through p, since p = x + d n for d > 0) meets G first at a distance t
/// with d + tolerance < t <= d + probe. A G met below p (t <= d) covers the spot under
/// p, so p is outside it; a G met more than `probe` above p is another part
/// of the outfit (the other leg, an arm), not the layer under p. Vertices
/// inside the body (d <= 0) are the body's penetration, not counted here.
/// The tolerance, like issue 7's "more than 1 mm inside" the body, keeps
/// the figure off the knife edge of a crease's medial axis (the crotch),
/// where the closest body point, and so the ray, jumps from one side to
/// the other.
struct LayerPenetrationParams {
  double probe = 0.01;       // m: how far above a vertex an inner layer still counts as the one over it
  double tolerance = 0.001;  // m: a lower layer less than this above the vertex is not counted
};

/// The number of vertices of `outer` inside the garment whose triangles
/// `inner` holds (a BodyBvh built over the inner garment: open meshes are
/// fine, only rays are cast), with `on_body` each outer vertex's exact
/// signed distance to the body (CollisionBody::query or the collision
/// pass's final_distance). Sequential (callers parallelise over bodies).
/// When `inside` is given it gets one flag per outer vertex. Errors: sizes
/// that differ, an empty inner BVH, a bad probe.
[[nodiscard]] Expected<std::size_t> count_inside_layer(std::span<const Vec3d> outer,
                                                       std::span<const BodyDistance> on_body, const BodyBvh& inner,
                                                       const LayerPenetrationParams& params = {},
                                                       std::vector<std::uint8_t>* inside = nullptr);

/// Collision step 8 (docs/collision.md), the counterpart of
/// count_inside_layer: after resolve_layers, each vertex of `outer` that one
/// of the `lower` garments still covers (its ray from the closest body point
/// meets a lower garment above it within `probe`: a crease, or a coarse inner
/// face spanning body points that got no floor) is moved along the body
/// normal to `gap` above that garment, and its body distance in `on_body` is
/// queried again. A lift moves the closest body point (in a crease, to the
/// other side), so vertices are tested again, at most `rounds` times, until no
/// lower layer is over them. Reads `lower` (BVHs over the final positions of
/// every layer under `outer`), `body`; writes `outer`, `on_body`. Sequential
/// and in vertex order (callers parallelise over bodies), so the result does
/// not depend on the thread count. Returns the number of lifts; errors:
/// sizes that differ, an empty lower BVH, a non-positive probe or gap.
[[nodiscard]] Expected<std::size_t> lift_over_lower_layers(std::span<Vec3d> outer, std::span<BodyDistance> on_body,
                                                           std::span<const BodyBvh> lower, const CollisionBody& body,
                                                           double probe, double gap, int rounds = 8);

}  // namespace atelier
