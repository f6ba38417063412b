// Collision pass: a regenerated garment never enters the body and keeps the
// clearance it had on the source body (issue 7). Shared by detail and profile
// regeneration; seed 001 section 6 decodes without any collision step, seed
// 000 section 4.2 (Fig. 16) avoids collisions during fairing by sub-steps.
//
//  1. Encoding (once per garment): each garment vertex stores its signed
//     distance to the source body (its clearance) and its closest source
//     triangle (a hint: on a body of the same topology the distance to that
//     triangle bounds the distance to the whole surface from above).
//  2. Per body: a CollisionBody over the body triangles: an Embree scene
//     built once per topology and worker, refit to the body, searched by
//     rtcPointQuery within the hint's distance. Queries are exact: closest
//     point by point-triangle distances within the hint's bound, sign by the
//     angle-weighted pseudo-normal of the closest feature (Baerentzen &
//     Aanaes 2005), computed on demand.
//  3. Pass: every vertex inside the body or closer than its target clearance
//     c_v = clamp(encoded, min_clearance, max_clearance) moves to x + c_v n
//     (x its closest body point, n the outward normal there: the distance
//     gradient, or the pseudo-normal on the surface); repeated a few rounds
//     where concave parts of the body make one push fall short. Then the
//     moved region (grown by `fair_rings` rings; none by default: spreading
//     a push over unmoved neighbours strains more edges, 0.2-0.7 points of
//     excess strain p95 on MakeHuman garments) is smoothed by umbrella
//     fairing (seed 000 section 4.2, Kobbelt's U2 Jacobi iteration, half
//     steps, along the body normal only) with all other vertices fixed.
//     What is faired is the pass's displacement (position minus position on
//     entry), not the garment: the bump a push leaves is spread over its
//     neighbours while the garment's own shape (its folds, and the skin
//     stretch the edge transfer gave it) is kept; fairing positions would
//     flatten it and add strain. Every move is applied in sub-steps and cut
//     at the last one that keeps the vertex at or above its target clearance.
//     Sub-steps are tested on the tangent plane at the closest body point
//     (first-order signed distance, no query); the end state is verified by
//     one exact query per vertex that moved by more than its margin over
//     its target (the distance is 1-Lipschitz, so the others cannot have
//     crossed it), and a vertex found deeper than both its target and its
//     pre-fairing distance returns to its pushed position.
//  4. Layers: garments are resolved in z_depth order (inner first); each
//     resolved layer leaves a clearance floor on the body vertices under it
//     and outer layers keep at least that floor plus `layer_gap` (their
//     target is floor + layer_gap + tolerance, so that the pass's tolerance
//     cannot leave them on the inner layer).
//
// Reads: body positions and triangles, garment positions and adjacency.
// Writes: garment positions (in place) and the report.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/systems/spatial/collision_body.h>
#include <atelier/systems/smooth/fairing.h>

namespace atelier {


/// Clearance encoding of a garment on its source body.
struct ClearanceEncoding {
  std::vector<float> clearance;         // signed distance to the source body per vertex
  std::vector<std::uint32_t> triangle;  // closest source triangle per vertex (hint on other bodies)
};

/// Signed distances of the garment vertices to the source body. Errors:
/// empty garment, non-finite vertex (naming it).
[[nodiscard]] Expected<ClearanceEncoding> encode_clearance(std::span<const Vec3d> garment, const CollisionBody& source,
                                                           const ExecContext& ctx = {});

struct CollisionParams {
  double min_clearance = 0.0005;  // floor of every target clearance (m)
  double max_clearance = 0.05;    // cap: a loose garment's far parts are never pushed farther
  /// Vertices within this much below their target are left alone (the pass
  /// does not chase rounding).
  double tolerance = 0.001;
  int push_rounds = 3;       // push, re-query, push again where concavities make it fall short
  int fair_rings = 0;        // rings of unmoved neighbours freed around the moved region (0: the moved region alone)
  int fair_iterations = 10;  // umbrella iterations (0: no smoothing)
  int substeps = 4;          // sub-steps of a fairing move (tested on the tangent plane)
  double layer_gap = 0.001;  // resolve_layers: outer layer at least this far outside the inner one
};

struct CollisionReport {
  std::size_t vertices = 0;
  std::size_t inside_before = 0;  // signed distance < 0 on entry
  std::size_t below_before = 0;   // below target clearance - tolerance on entry
  std::size_t pushed = 0;         // vertices moved by the push
  std::size_t faired = 0;         // free vertices of the smoothing
  std::size_t inside_after = 0;   // signed distance < 0 on exit
  std::size_t below_after = 0;    // below min(target, floor) - tolerance on exit
  double max_depth_before = 0;    // deepest penetration on entry (>= 0)
  double max_depth_after = 0;
  std::uint64_t queries = 0;        // exact body queries
  std::uint64_t refused_moves = 0;  // fairing sub-steps cut by the collision test
};

/// The pass, in place on `garment`. `encoding` gives the target clearances
/// and hints (its triangles must index the body's topology; an empty
/// `triangle` array means no hints). Errors: empty garment, sizes that do
/// not match, empty body, bad parameters, non-finite vertex.
[[nodiscard]] Expected<CollisionReport> resolve_collisions(std::span<Vec3d> garment, const NodeAdjacency& adjacency,
                                                           const ClearanceEncoding& encoding, const CollisionBody& body,
                                                           const CollisionParams& params, const ExecContext& ctx = {});
/// The same, also giving each vertex's exact distance to the body at its
/// final position (the pass's own last query of it), so that a caller
/// reporting clearance does not query every vertex again.
[[nodiscard]] Expected<CollisionReport> resolve_collisions(std::span<Vec3d> garment, const NodeAdjacency& adjacency,
                                                           const ClearanceEncoding& encoding, const CollisionBody& body,
                                                           const CollisionParams& params,
                                                           std::vector<BodyDistance>& final_distance,
                                                           const ExecContext& ctx = {});

/// One garment of a layered outfit.
struct GarmentLayer {
  std::span<Vec3d> positions;
  const NodeAdjacency* adjacency = nullptr;
  const ClearanceEncoding* encoding = nullptr;
  int z_depth = 0;  // MakeHuman's layer order: smaller is nearer the skin
  /// When set, each vertex's exact distance to the body at its final
  /// position (as resolve_collisions' final_distance).
  std::vector<BodyDistance>* final_distance = nullptr;
};

/// Resolves the layers inner first (stable by z_depth); each outer layer's
/// target clearance is at least the clearance of the inner layers under it
/// (interpolated on the body triangle under the vertex) plus layer_gap.
/// Reports in the order given.
[[nodiscard]] Expected<std::vector<CollisionReport>> resolve_layers(std::span<GarmentLayer> layers,
                                                                    const CollisionBody& body,
                                                                    const CollisionParams& params,
                                                                    const ExecContext& ctx = {});

}  // namespace atelier
