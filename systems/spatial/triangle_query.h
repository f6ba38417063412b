// Point-triangle queries and the signed-distance sign rule: the one place
// where "where is the surface" and "which side of it" are answered. The
// Embree BVH (body_bvh.h), the collision body (collision_body.h) and the
// body collider (body_collider.h) find the closest triangle each their own
// way, and all of them answer through these functions, so their distances
// and signs agree bit for bit.
//
//  * closest_point_on_triangle: exact closest point in double (Ericson,
//    Real-Time Collision Detection 5.1.5), with the feature (vertex, edge,
//    face) whose Voronoi region holds the point;
//  * TriangleTopology: a triangle mesh's edges (the triangle across each
//    edge) and the triangles around each point, and whether the mesh is
//    closed and consistently oriented (a sign means nothing otherwise);
//  * the angle-weighted pseudo-normal of a feature and the sign rule of
//    Baerentzen & Aanaes ("Signed distance computation using the angle
//    weighted pseudonormal", 2005, theorem 1): p is outside when
//    (p - c) . n_pseudo >= 0, c its closest point.
//
// Reads: caller's triangle and position arrays. Writes: nothing outside itself.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>

namespace atelier {

inline constexpr std::uint32_t kNoTriangle = std::numeric_limits<std::uint32_t>::max();

/// Which feature of a triangle holds the closest point: vertex k, edge k
/// (from corner k to corner k+1 mod 3), or the face interior.
enum class TriFeature : std::uint8_t { kVertex0, kVertex1, kVertex2, kEdge01, kEdge12, kEdge20, kFace };

/// Exact closest point on one triangle (double precision, Voronoi regions;
/// degenerate triangles fall back to their edges). barycentric = weights of
/// corners a, b, c.
struct TrianglePoint {
  Vec3d point;
  Vec3d barycentric;
  TriFeature feature = TriFeature::kFace;
};
[[nodiscard]] TrianglePoint closest_point_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b,
                                                      const Vec3d& c) noexcept;

/// Edges and point rings of a triangle mesh, built once per topology (every
/// body of a family shares it).
class TriangleTopology {
 public:
  /// Errors: an index at or beyond `point_count` (naming the triangle).
  /// Open, non-manifold or inconsistently oriented meshes are accepted:
  /// closed() says, and open_message() names the first offending edge.
  [[nodiscard]] static Expected<TriangleTopology> build(std::span<const Triangle> triangles, std::uint32_t point_count,
                                                        const ExecContext& ctx = {});

  [[nodiscard]] std::span<const Triangle> triangles() const noexcept { return triangles_; }
  [[nodiscard]] std::uint32_t point_count() const noexcept { return point_count_; }
  [[nodiscard]] std::size_t size() const noexcept { return triangles_.size(); }
  /// The triangle across edge k (corner k -> k+1) of t; kNoTriangle when
  /// that edge is not shared by exactly two oppositely oriented triangles.
  [[nodiscard]] std::uint32_t across(std::uint32_t t, int k) const noexcept { return across_[t][k]; }
  /// The triangles using point v, increasing.
  [[nodiscard]] std::span<const std::uint32_t> triangles_around(std::uint32_t v) const noexcept {
    return {ring_.data() + ring_offset_[v], ring_offset_[v + 1] - ring_offset_[v]};
  }
  /// Every edge is used by exactly two triangles in opposite directions.
  [[nodiscard]] bool closed() const noexcept { return closed_; }
  /// "edge (a, b) of triangle t is ..." for the first offending edge.
  [[nodiscard]] const std::string& open_message() const noexcept { return open_message_; }

 private:
  std::vector<Triangle> triangles_;
  std::uint32_t point_count_ = 0;
  std::vector<std::array<std::uint32_t, 3>> across_;
  std::vector<std::uint32_t> ring_offset_, ring_;
  bool closed_ = false;
  std::string open_message_;
};

/// Unit normal of triangle t (counter-clockwise), zero when degenerate.
[[nodiscard]] inline Vec3d unit_face_normal(const Triangle& t, std::span<const Vec3d> pos) noexcept {
  const Vec3d cr = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
  const double len = cr.norm();
  return len > 0.0 ? Vec3d(cr / len) : Vec3d::Zero();
}

/// Angle-weighted pseudo-normal of point v: its triangles' unit normals
/// weighted by their angles at v, summed in triangle order (not unit).
[[nodiscard]] Vec3d vertex_pseudo_normal(const TriangleTopology& topo, std::span<const Vec3d> pos,
                                         std::uint32_t v) noexcept;
/// Pseudo-normal of edge k of t: the sum of its two unit face normals (the
/// face normal alone on an edge with no partner).
[[nodiscard]] inline Vec3d edge_pseudo_normal(const TriangleTopology& topo, std::span<const Vec3d> pos,
                                              std::uint32_t t, int k) noexcept {
  const std::uint32_t o = topo.across(t, k);
  const Vec3d n = unit_face_normal(topo.triangles()[t], pos);
  return o == kNoTriangle ? n : Vec3d(n + unit_face_normal(topo.triangles()[o], pos));
}
/// Pseudo-normal of the feature of t holding a closest point.
[[nodiscard]] Vec3d pseudo_normal(const TriangleTopology& topo, std::span<const Vec3d> pos, std::uint32_t t,
                                  TriFeature feature) noexcept;

/// The sign rule (Baerentzen & Aanaes, theorem 1): +1 when p is outside
/// (or on) the surface at its closest point c with pseudo-normal n, -1
/// inside. Exact up to rounding for a closed, consistently oriented mesh.
[[nodiscard]] inline double pseudo_normal_sign(const Vec3d& p, const Vec3d& c, const Vec3d& n) noexcept {
  return (p - c).dot(n) < 0.0 ? -1.0 : 1.0;
}

}  // namespace atelier
