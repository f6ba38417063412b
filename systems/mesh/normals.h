// Normals of a Model's faces and nodes from a position column, and the
// local frame of a triangle.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>

#include <atelier/engine/math.h>
#include <atelier/storage/model.h>

namespace atelier {

/// Newell normal of a face: unnormalised, its length twice the area for a
/// planar face.
[[nodiscard]] inline Vec3d face_normal(const Model& m, FaceIdx f, std::span<const Vec3d> pos) {
  Vec3d n = Vec3d::Zero();
  m.for_each_face_halfedge(f, [&](HalfedgeIdx h) { n += pos[m.tail(h).value].cross(pos[m.head(h).value]); });
  return n;
}

/// Angle-weighted node normal (Thurmer & Wuthrich), unnormalised: robust to
/// the uneven face sizes of ring meshes, unlike the plain average.
[[nodiscard]] inline Vec3d vertex_normal(const Model& m, NodeIdx v, std::span<const Vec3d> pos) {
  Vec3d n = Vec3d::Zero();
  m.for_each_outgoing(v, [&](HalfedgeIdx h) {
    const FaceIdx f = m.face(h);
    if (!f.valid()) return;
    const Vec3d e1 = pos[m.head(h).value] - pos[v.value];
    const Vec3d e0 = pos[m.tail(m.prev(h)).value] - pos[v.value];
    const double den = e0.norm() * e1.norm();
    if (den <= 0) return;
    const double ang = std::acos(std::clamp(e0.dot(e1) / den, -1.0, 1.0));
    const Vec3d fn = face_normal(m, f, pos);
    const double l = fn.norm();
    if (l > 0) n += ang * fn / l;
  });
  return n;
}

/// Columns: a triangle's two edges from corner 0 and its unit normal (zero
/// for a zero-area triangle). The affine map of a body triangle from one
/// shape to another is B_new B_source^-1, the normal kept at unit length:
/// an offset from the skin is carried, not scaled.
[[nodiscard]] inline Mat3d triangle_basis(std::span<const Vec3d> p, const std::array<std::uint32_t, 3>& t) {
  Mat3d m;
  const Vec3d e1 = p[t[1]] - p[t[0]], e2 = p[t[2]] - p[t[0]];
  m << e1, e2, e1.cross(e2).normalized();
  return m;
}

}  // namespace atelier
