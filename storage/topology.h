// Independent counts of the terms of the non-manifold Euler-Poincare formula
//   V - E + F - R = C - H + S
// (see docs/glossary.md). Everything but H is recounted from the tables; H,
// the complex holes, is the count the Euler operators keep in the model.
#pragma once

#include <cstdint>

#include <atelier/storage/model.h>

namespace atelier {

struct TopologyCounts {
  std::int64_t nodes = 0;       // V
  std::int64_t edges = 0;       // E
  std::int64_t faces = 0;       // F
  std::int64_t rings = 0;       // R: connected groups of ring nodes/edges lying inside faces
  std::int64_t components = 0;  // C: connected components (a ring counts with its face)
  std::int64_t shells = 0;      // S: face-connected groups with no boundary or wire edge (closed shells)

  [[nodiscard]] std::int64_t euler() const noexcept { return nodes - edges + faces - rings; }
  /// H implied by the formula: C - (V - E + F - R) + S.
  [[nodiscard]] std::int64_t implied_holes() const noexcept { return components - euler() + shells; }
};

/// Recounts V, E, F, R, C and S of the whole model (or one surface).
[[nodiscard]] TopologyCounts count_topology(const Model& m);
[[nodiscard]] TopologyCounts count_topology(const Model& m, SurfaceIdx s);

}  // namespace atelier
