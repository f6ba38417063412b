// Plane sections of a surface: the chains where a plane cuts the faces, as
// surface locations (a point on an edge, by its parameter) so they move with
// the mesh. Used for centre and side feature lines and for tape-measure girths.
//
// Reads: halfedge/face connectivity of one surface and a position array.
#pragma once

#include <span>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/storage/model.h>
#include <atelier/storage/surface_location.h>

namespace atelier {

struct SectionPoint {
  SurfaceLocation where;  // kEdge: element = halfedge, param.x = u from its tail
  Vec3d p = Vec3d::Zero();
};

struct SectionChain {
  std::vector<SectionPoint> points;
  bool closed = false;
};

/// Chains of the intersection of surface `s` with the plane {x : n.x = d}.
/// Nodes exactly on the plane count as on the positive side (simulation of
/// simplicity), so every crossing lies on an edge with one node strictly
/// below the plane, and each crossed face contributes segments between its
/// crossings in cycle order. Chains are ordered; closed chains do not repeat
/// their first point. Output is deterministic (chains start at their
/// smallest halfedge). `positions` is indexed by node index.
[[nodiscard]] std::vector<SectionChain> plane_section(const Model& m, SurfaceIdx s, const Vec3d& n, double d,
                                                      std::span<const Vec3d> positions);

}  // namespace atelier
