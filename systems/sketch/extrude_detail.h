// Private to systems/sketch/extrude*.cpp: the single extrusion run shared by
// extrude() and the mirrored pair (extrude_mirror.cpp).
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/sketch/optimise_region.h>
#include <atelier/systems/spatial/collision_body.h>

#include <span>
#include <string>
#include <vector>

namespace atelier::extrude_detail {

[[nodiscard]] Status fail(ErrorCode c, const std::string& what);

enum class Stop { kNever, kAfterBase };

/// What run() saw just before sewing: the live nodes and faces then (the
/// part is every live element not among them afterwards) and B's kind.
struct RunOut {
  std::vector<char> old_node, old_face;
  bool ring = false;
};

/// An open base selects only boundary nodes with sign * (p - point) . normal
/// > 0 (the mirror base: the boundary behind it on screen is its twin).
struct BaseSide {
  Vec3d point, normal;
  double sign = 1;
};

/// One extrusion (steps 1-5 and the additions), not transactional (the
/// caller restores the model). Stop::kAfterBase returns after step 1 with
/// rep.base, rep.base_ring and rep.faces_removed set.
[[nodiscard]] Expected<ExtrudeReport> run(Model& m, const ExtrudeStrokes& in, const ExtrudeOptions& opt,
                                          const ExecContext& ctx, Stop stop, RunOut* out,
                                          const BaseSide* only = nullptr);
/// Steps 4-5 and the additions (sewing, body push, optimisation, the part
/// as a surface, validation) for copies of B = rep.base already placed
/// (rep.base_mean_edge set): shared by run() and the recipe replay.
[[nodiscard]] Expected<ExtrudeReport> finish(Model& m, ExtrudeReport rep, bool ring,
                                             const std::vector<std::vector<Vec3d>>& copies, const ExtrudeOptions& opt,
                                             const ExecContext& ctx, RunOut* out, double volume_before);
/// The recipe's local similarities (and n_p's sign) from rep's world ones,
/// in B's frame on m (extrude_recipe.cpp).
[[nodiscard]] Status localise(const Model& m, ExtrusionRecipe& rc, const ExtrudeReport& rep);
/// The copies of B from the recipe, through B's frame on m; sets rep's
/// similarities, P_i*, n_p, L and copies (extrude_recipe.cpp). run() places
/// its copies this way too, so a replay on the same B repeats them bit for bit.
[[nodiscard]] Status place_copies(const Model& m, const ExtrusionRecipe& rc, ExtrudeReport& rep,
                                  std::vector<std::vector<Vec3d>>& copies);
[[nodiscard]] double signed_volume(const Model& m);
[[nodiscard]] std::vector<NodeIdx> new_nodes(const Model& m, const std::vector<char>& old);
/// Per node slot, the centre and unit normal of the copy of a ring B the
/// node was placed in (the sweep's axis there); a zero normal: none.
struct CopyAxes {
  std::vector<Vec3d> centre, normal;
};
/// The body push of one point, shared by every push of the extrusion: a
/// point whose body distance d is below the clearance c (by a hair, so that
/// a point already pushed is not pushed again by rounding) moves to the
/// closest body point + c n.
[[nodiscard]] inline bool within_clearance(const BodyDistance& d, double c) noexcept {
  return d.triangle != kNoTriangle && d.distance < c * (1 - 1e-9);
}
[[nodiscard]] inline Vec3d pushed_place(const BodyDistance& d, double c) noexcept {
  return d.closest + c * d.normal;
}
/// The push of the collision pass on the new nodes (closest body point +
/// c n). With axes, a node inside the body whose closest point lies towards
/// its copy's axis goes out away from the axis instead (extrude.cpp).
void push_out(Model& m, const std::vector<char>& old, const CollisionBody& body, double c, int rounds,
              std::vector<char>& pushed, const CopyAxes* axes = nullptr);
/// Before the optimisation: umbrella steps on the pushed nodes and two
/// rings around them, each followed by the push, `rounds` times
/// (extrude_body.cpp).
void smooth_pushed(Model& m, const std::vector<char>& old, const std::vector<char>& pushed, const CollisionBody& body,
                   double c, int push_rounds, int rounds);
/// After the first push: every new edge at least min_length long whose
/// midpoint lies in the body split there, the new node pushed out, up to
/// `rounds` times (extrude_body.cpp). Returns the splits.
[[nodiscard]] Expected<std::size_t> refine_outside(Model& m, const std::vector<char>& old, const CollisionBody& body,
                                                   double c, double min_length, int rounds, std::vector<char>& pushed);
/// After the last push: refine_outside (refine_shortest * target,
/// refine_rounds), optimise_region on the faces around edges with a new
/// node outside [low, high] target, then the push, up to `rounds` times
/// (extrude_body.cpp). Returns the operations applied.
[[nodiscard]] Expected<std::size_t> settle(Model& m, const std::vector<char>& old, const std::vector<char>& old_face,
                                           std::span<const NodeIdx> B, std::span<const HalfedgeIdx> chain,
                                           const RegionOptimiseOptions& oo, const CollisionBody& body, double c,
                                           int push_rounds, int rounds, double refine_shortest, int refine_rounds,
                                           std::vector<char>& pushed, const ExecContext& ctx);
/// optimise_region keeping every place it makes c outside the body: split
/// and collapse points pushed out (closest body point + c n), a relaxed
/// node projected onto the region where the region runs outside the body,
/// else its tangential place pushed out (optimise_region.cpp).
[[nodiscard]] Expected<RegionOptimiseReport> optimise_outside(
    Model& m, std::span<const FaceIdx> region, std::span<const NodeIdx> fixed, std::span<const HalfedgeIdx> fixed_chain,
    const RegionOptimiseOptions& options, const CollisionBody& body, double c, const ExecContext& ctx);
/// Lengths of the edges with a new node against [low, high] L.
[[nodiscard]] EdgeLengthStats new_edge_stats(const Model& m, const std::vector<char>& old, double L, double low,
                                             double high);
/// The part (the faces on B's side that had none) as its own surface,
/// joined along B (extrude_surface.cpp).
[[nodiscard]] Status split_off(Model& m, const std::vector<NodeIdx>& B, bool ring, ExtrudeReport& rep,
                               const ExecContext& ctx);
[[nodiscard]] Expected<HalfedgeIdx> halfedge_for(Model& m, NodeIdx a, NodeIdx b);

/// The mirrored pair (extrude_mirror.cpp), options.mirror set.
[[nodiscard]] Expected<ExtrudeReport> run_mirrored(Model& m, const ExtrudeStrokes& in, const ExtrudeOptions& opt,
                                                   const ExecContext& ctx);

}  // namespace atelier::extrude_detail
