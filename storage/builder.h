// Bulk construction of surfaces from flat arrays (the fast path used by the
// readers and by generators): O(n), no per-face operator calls.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

namespace atelier {

/// Polygon soup in CSR form: face f has nodes face_nodes[face_offsets[f] ..
/// face_offsets[f+1]), counter-clockwise seen from outside.
struct PolygonArrays {
  std::span<const Vec3d> positions;
  std::span<const std::uint32_t> face_offsets;  // size F+1, starts at 0
  std::span<const std::uint32_t> face_nodes;
};

/// Adds one surface holding the given polygons. Errors (naming the face or
/// node): out-of-range index, face with fewer than 3 nodes or a repeated node,
/// non-finite position, an edge used by more than two faces (non-manifold
/// within a surface: split the faces into surfaces joined by a joint), or two
/// faces traversing an edge in the same direction (inconsistent orientation).
/// Nodes referenced by no face are kept as isolated nodes. The model's
/// complex-hole count is updated so the Euler-Poincare formula holds.
[[nodiscard]] Expected<Surface> add_polygon_surface(Model& m, std::string name, const PolygonArrays& arrays,
                                                    const ExecContext& ctx = {});

}  // namespace atelier
