// The collision body: exact signed distances from points to a closed body
// mesh, for thousands of bodies of one topology (issue 7). Embree finds the
// candidate triangles: a scene per body whose hierarchy is built once per
// topology and worker and refit to every later body (RTC_BUILD_QUALITY_REFIT),
// searched by rtcPointQuery with a sphere that starts at a hint triangle's
// distance and shrinks as nearer triangles are found. Embree only culls: the
// distances are exact (closest_point_on_triangle, in double), ties go to the
// smaller triangle index, the sign is the pseudo-normal rule of
// systems/spatial/triangle_query.h, so answers equal BodyBvh's. (It replaced
// a hand-written 4-wide refit hierarchy: the same answers bit for bit at
// 1.0-1.16x its cost per body; docs/collision.md.)
//
// Reads: the body's triangles (once) and positions (per body, kept as a
// view). Writes: nothing outside itself.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/spatial/triangle_query.h>

namespace atelier {

/// Topology shared by every body of one family (built once): triangles,
/// the triangles around each vertex, the neighbour across each edge, and a
/// pool of Embree scenes over the triangles (made on demand: a scene is
/// built on the first body that needs one, then lent to one body at a time
/// and refit to it). Errors: empty mesh, index out of range, an edge not
/// shared by exactly two oppositely oriented triangles (the body must be
/// closed: inside and clearance mean nothing on an open mesh).
class CollisionTopology {
 public:
  [[nodiscard]] static Expected<std::shared_ptr<const CollisionTopology>> build(std::span<const Triangle> triangles,
                                                                                std::uint32_t point_count);
  [[nodiscard]] std::span<const Triangle> triangles() const noexcept { return topo_.triangles(); }
  [[nodiscard]] std::uint32_t point_count() const noexcept { return topo_.point_count(); }
  /// Edges and point rings (systems/spatial/triangle_query.h).
  [[nodiscard]] const TriangleTopology& triangle_topology() const noexcept { return topo_; }

 private:
  friend class CollisionBody;
  // Embree's device and the idle scenes (collision_body.cpp).
  struct EmbreePool;
  struct EmbreeScene;
  TriangleTopology topo_;
  mutable std::once_flag embree_once_;
  mutable std::shared_ptr<EmbreePool> embree_pool_;
};

/// Exact signed distance of a point to the body with its closest feature.
struct BodyDistance {
  double distance = 0;            // signed, negative inside
  Vec3d closest = Vec3d::Zero();  // closest body point
  Vec3d normal = Vec3d::Zero();   // unit outward direction at `closest`
  std::uint32_t triangle = kNoTriangle;
  Vec3d barycentric = Vec3d::Zero();
};

struct CollisionBodyParams {
  /// Where the garment lies. The scene covers the whole body whatever it
  /// is (a refit, 0.2 ms for the MakeHuman skin, costs less than cutting
  /// the body to a region), so answers and cost ignore it; callers that
  /// built the old region grid still pass it (apps/atelier/demo.cpp).
  Box3d roi;
};

/// Per-body query structure: an Embree scene of the topology, borrowed
/// from its pool, refit to these positions (in float). Keeps a view of the
/// positions: they must stay alive and unchanged while it is used. Copies
/// share the scene.
class CollisionBody {
 public:
  /// Errors: positions count differs from the topology, non-finite
  /// position, a coordinate beyond float range (Embree holds vertices in
  /// float), an Embree error.
  [[nodiscard]] Status build(std::shared_ptr<const CollisionTopology> topology, std::span<const Vec3d> positions,
                             const CollisionBodyParams& params = {}, const ExecContext& ctx = {});
  /// The body keeps a view of its positions: a temporary vector would be
  /// freed while it is read, so that is refused when compiling.
  Status build(std::shared_ptr<const CollisionTopology> topology, std::vector<Vec3d>&& positions,
               const CollisionBodyParams& params = {}, const ExecContext& ctx = {}) = delete;
  [[nodiscard]] bool empty() const noexcept { return topo_ == nullptr; }
  [[nodiscard]] const CollisionTopology& topology() const noexcept { return *topo_; }
  [[nodiscard]] std::span<const Vec3d> positions() const noexcept { return pos_; }

  /// Exact signed distance. `hint`: a triangle believed near (e.g. the
  /// closest one on the source body, or kNoTriangle); it only speeds the
  /// search up (its distance is the search's first radius), the result is
  /// exact either way. Thread-safe.
  [[nodiscard]] BodyDistance query(const Vec3d& p, std::uint32_t hint = kNoTriangle) const noexcept;
  /// The same answers for many points with hints (empty: none), in
  /// parallel. Errors: sizes that differ, an empty body.
  [[nodiscard]] Status query_many(std::span<const Vec3d> p, std::span<const std::uint32_t> hint,
                                  std::span<BodyDistance> out, const ExecContext& ctx = {}) const;
  /// Pseudo-normal signed distance to one given triangle (the triangle must
  /// hold the closest point for the sign to be meaningful).
  [[nodiscard]] BodyDistance query_triangle(const Vec3d& p, std::uint32_t t) const noexcept;

 private:
  struct Best;  // the best triangle so far of one query
  [[nodiscard]] Best start_from_hint(const Vec3d& p, std::uint32_t hint) const noexcept;
  /// Sign and outward direction of p's closest point r on triangle t.
  [[nodiscard]] BodyDistance signed_distance(const Vec3d& p, std::uint32_t t, const TrianglePoint& r) const noexcept;

  std::shared_ptr<const CollisionTopology> topo_;
  std::span<const Vec3d> pos_;
  double extent_ = 0;  // largest absolute coordinate (scales the culling margins)
  // The scene lent by the topology's pool (back to it when the last holder
  // lets go). Declared last: released before topo_.
  std::shared_ptr<CollisionTopology::EmbreeScene> scene_;
};

}  // namespace atelier
