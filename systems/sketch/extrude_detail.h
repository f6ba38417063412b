// Private to systems/sketch/extrude*.cpp: the single extrusion run shared by
// extrude() and the mirrored pair (extrude_mirror.cpp).
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/spatial/collision_body.h>

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
[[nodiscard]] double signed_volume(const Model& m);
[[nodiscard]] std::vector<NodeIdx> new_nodes(const Model& m, const std::vector<char>& old);
void push_out(Model& m, const std::vector<char>& old, const CollisionBody& body, double c, int rounds,
              std::vector<char>& pushed);
[[nodiscard]] Status split_off(Model& m, const std::vector<NodeIdx>& B, bool ring, ExtrudeReport& rep,
                               const ExecContext& ctx);
[[nodiscard]] Expected<HalfedgeIdx> halfedge_for(Model& m, NodeIdx a, NodeIdx b);

/// The mirrored pair (extrude_mirror.cpp), options.mirror set.
[[nodiscard]] Expected<ExtrudeReport> run_mirrored(Model& m, const ExtrudeStrokes& in, const ExtrudeOptions& opt,
                                                   const ExecContext& ctx);

}  // namespace atelier::extrude_detail
