// Regeneration of a profile template on a body: the decoding process of
// seed 001 section 4 and the shape construction of seed 000 section 4.2.
//
//  1. Relocate the feature nodes (systems/feature_encoding.h) and rebuild the
//     profiles: seed 001 eq. (7) for Bezier curves, seed 000 eq. (3) for
//     attached point lists. Profiles follow joints: a curve on one member's
//     edge applies to the corresponding edge of every member.
//  2. Modified variational subdivision, `levels` times:
//     - uniform 1-to-4 split (systems/subdivide.h); a new node on a profile
//       edge goes to C(1/2) and the curve is halved onto the two new edges
//       (de Casteljau for Bezier curves); on a boundary or joint edge without
//       a profile, the 4-point rule of interpolatory curve subdivision,
//       9/16 (a + b) - 1/16 (a' + b'), with a', b' the neighbours along the
//       boundary or joint chain (so hems and seams stay smooth); a joint
//       edge's new node is computed once and written to every member, so
//       surfaces never crack apart;
//     - a new node inside the body or closer than the clearance is pushed
//       out along the body normal at its closest point (seed 000 Fig. 16);
//     - Kobbelt's 2nd-order umbrella fairing of the new interior nodes, with
//       old nodes, profile, boundary and joint nodes fixed; moves are applied
//       in sub-steps and refused when they would come closer to the body than
//       the clearance (systems/fairing.h).
//  3. Quality: penetration, clearance at the feature nodes against the
//     encoded one, profile interpolation error, umbrella norm, cracks.
//
// Collision queries go through a BodyCollider (systems/spatial/body_collider.h).
//
// Reads: the template, the reference body's topology and features, a body's
// node positions. Writes: a new Model.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/spatial/body_collider.h>
#include <atelier/systems/profile/profile_template.h>
#include <atelier/systems/body/reference_body.h>

namespace atelier {

struct RegenParams {
  int levels = -1;           // refinement levels; < 0: the template's
  double clearance = -1;     // distance kept from the body (m); < 0: the template's
  int fair_iterations = 12;  // Jacobi iterations of umbrella fairing per level
  double fair_tolerance = 1e-5;  // stop a level's fairing once no node moves farther (m)
  int substeps = 4;          // sub-steps of a fairing move near the body
  bool collision = true;     // push-out and collision-checked fairing
  bool smooth_chains = true; // 4-point rule on boundary / joint edges (else midpoints)
};

struct RegenQuality {
  std::size_t nodes = 0, faces = 0;
  std::size_t inside = 0;         // nodes with signed distance < 0
  double max_depth = 0;           // deepest of them (m, >= 0)
  double min_distance = 0;        // smallest signed distance over all nodes (exact below 3x the clearance)
  double node_clearance_error = 0;  // max |d(node) - encoded d(node)| over feature nodes
  double profile_error = 0;       // max distance of refined profile nodes to their curve
  double umbrella = 0;            // max |U2| over the free nodes of the last level
  double crack = 0;               // max distance between corresponding joint nodes
  std::size_t pushed = 0;         // push-outs applied
  std::uint64_t refused_moves = 0;
  double ms = 0;                  // wall time of regenerate()
  // Where that time went (ms): node and profile decoding plus the splits,
  // push-outs, fairing, and the final distance pass with the quality measures.
  double split_ms = 0, push_ms = 0, fair_ms = 0, quality_ms = 0;
  std::uint64_t fair_queries = 0;  // body queries made by the fairing's collision test
};

struct RegenResult {
  Model model;
  RegenQuality quality;
  /// Per node of `model`: 0 free, 1 feature node, 2 profile, 3 boundary or joint chain, 4 old node of a later level.
  std::vector<std::uint8_t> role;
};

/// Regenerates `t` on the body with `body_positions` (reference topology).
/// `collider` may be null when params.collision is false (or for bodies
/// without a closed surface: no collision avoidance, penetration unmeasured).
[[nodiscard]] Expected<RegenResult> regenerate(const ProfileTemplate& t, const ReferenceBody& reference,
                                               std::span<const Vec3d> body_positions, const BodyCollider* collider,
                                               const RegenParams& params = {}, const ExecContext& ctx = {});

/// Several templates on one body, sharing one collider built over `roi`
/// (the batch path: ColliderParams::use_grid is off unless given). Errors
/// name the template.
[[nodiscard]] Expected<std::vector<RegenResult>> regenerate_on_body(std::span<const ProfileTemplate> templates,
                                                                    const ReferenceBody& reference,
                                                                    std::span<const Vec3d> body_positions,
                                                                    const Box3d& roi, const RegenParams& params = {},
                                                                    const ColliderParams& collider = {.use_grid = false},
                                                                    const ExecContext& ctx = {});

/// The same, with the collider taken from `pool` (updated when it was built
/// on this reference's topology, built otherwise) and given back after.
[[nodiscard]] Expected<std::vector<RegenResult>> regenerate_on_body(std::span<const ProfileTemplate> templates,
                                                                    const ReferenceBody& reference,
                                                                    std::span<const Vec3d> body_positions,
                                                                    const Box3d& roi, const RegenParams& params,
                                                                    const ColliderParams& collider,
                                                                    const ExecContext& ctx, ColliderPool& pool);

/// Largest distance between corresponding nodes of the model's joints.
[[nodiscard]] double joint_crack(const Model& m) noexcept;

}  // namespace atelier
