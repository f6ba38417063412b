// Private to systems/sketch/extrude*.cpp: the mesh optimisation of step 5
// (seed 002 Fig. 9), kept apart from the sweep so each file stays short.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/sketch/extrude.h>

#include <cstddef>
#include <vector>

namespace atelier::extrude_detail {

/// Which faces and nodes existed before the sweep (by slot): a face is "new"
/// when its slot was dead or beyond the table then.
struct Region {
  std::vector<bool> old_face;
  std::vector<bool> fixed_node;  // B's nodes
  [[nodiscard]] bool is_new(const Model& m, FaceIdx f) const noexcept {
    return f.valid() && m.alive(f) && (f.value >= old_face.size() || !old_face[f.value]);
  }
  [[nodiscard]] bool fixed(NodeIdx v) const noexcept { return v.value < fixed_node.size() && fixed_node[v.value]; }
  /// An edge of the new region: a new face on one side, nothing but new
  /// faces or no face on the other (so never an edge of B).
  [[nodiscard]] bool editable(const Model& m, EdgeIdx e) const noexcept;
};

[[nodiscard]] EdgeLengthStats region_stats(const Model& m, const Region& r, double target);

struct OptimiseCounts {
  std::size_t splits = 0, collapses = 0, swaps = 0;
};

/// Split / collapse / swap passes over the new region towards `target`
/// (B held by a temporary mesh edge along `base_chain` so collapses keep
/// its nodes; removed again before returning). Errors: kCancelled, or an
/// operator failing in a way its checks should have prevented (kInternal).
[[nodiscard]] Expected<OptimiseCounts> optimise_region(Model& m, const Region& r,
                                                       std::span<const HalfedgeIdx> base_chain, double target,
                                                       int passes, const ExecContext& ctx);

}  // namespace atelier::extrude_detail
