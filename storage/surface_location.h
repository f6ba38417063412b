// A location on a surface of the Model: what an attribute node (ATTRIB_NODE,
// ATTRIB_EDGENODE, ATTRIB_FACENODE) stores, by element and parameters, never
// by position, so it moves with the mesh when node positions change (a
// feature curve on another body of the same topology, a painted curve on a
// regenerated garment).
#pragma once

#include <cstdint>

#include <atelier/engine/math.h>
#include <atelier/storage/model.h>

namespace atelier {

/// kVertex: element = node; kEdge: element = halfedge, param.x = u from its
/// tail; kFace: element = face, param = areal coordinates (u, v, w) in the
/// fan triangle (c0, c_{corner+1}, c_{corner+2}) of the face's corners.
struct SurfaceLocation {
  AttribNodeKind kind = AttribNodeKind::kVertex;
  std::uint32_t element = 0;
  Vec3d param = Vec3d::Zero();
  std::uint8_t corner = 0;
};

}  // namespace atelier
