// Fan triangulation of a Model's faces into a triangle array over the node
// indices, for the spatial structures (BVHs, collision bodies, grids) and
// rendering, which take triangles and a position column.
//
// Reads: faces and halfedges of the given surfaces (or a soup's faces).
// Writes: nothing.
#pragma once

#include <span>
#include <vector>

#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>

namespace atelier {

/// Fan triangulation of faces of a Model: face corners c0..c(k-1) give
/// triangles (c0, c_{j+1}, c_{j+2}) (the attribute-node corner convention),
/// indices into model.nodes.position (dead slots are never referenced), so
/// the position column is used directly:
/// `bvh.build(StridedPoints::of(std::span<const Vec3d>(model.nodes.position)), tri.triangles)`.
struct SurfaceTriangles {
  std::vector<Triangle> triangles;
  std::vector<FaceIdx> face;  // source face of each triangle
};
/// Faces of the given surfaces (all live surfaces when empty). Errors on a
/// dead surface index.
[[nodiscard]] Expected<SurfaceTriangles> fan_triangulate(const Model& model,
                                                         std::span<const SurfaceIdx> surfaces = {});

/// The same convention for a polygon soup (a decoded garment, a MakeHuman
/// proxy): triangles in face order, indices into the soup's positions.
/// Precondition: soup.check() passes.
[[nodiscard]] std::vector<Triangle> fan_triangulate(const PolygonSoup& soup);

}  // namespace atelier
