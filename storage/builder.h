// Bulk construction of surfaces from flat arrays (the fast path used by the
// readers and by generators): O(n), no per-face operator calls.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>

namespace atelier {

/// Adds one surface holding the given polygons. Errors (naming the face or
/// node): out-of-range index, face with fewer than 3 nodes or a repeated node,
/// non-finite position, an edge used by more than two faces (non-manifold
/// within a surface: split the faces into surfaces joined by a joint), or two
/// faces traversing an edge in the same direction (inconsistent orientation).
/// Nodes referenced by no face are kept as isolated nodes. The model's
/// complex-hole count is updated so the Euler-Poincare formula holds.
[[nodiscard]] Expected<Surface> add_polygon_surface(Model& m, std::string name, const PolygonSoupView& arrays,
                                                    const ExecContext& ctx = {});

/// The inverse: the model's live faces (of one surface, or all) in index
/// order as a polygon soup over node indices, with every node slot's
/// position (dead slots included, so indices stay the model's), and the
/// per-corner texture coordinates when the model has the halfedge property
/// "corner_uv".
[[nodiscard]] PolygonSoup polygon_soup(const Model& m, SurfaceIdx only = {});

}  // namespace atelier
