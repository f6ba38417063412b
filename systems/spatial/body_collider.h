// The body collider of profile regeneration: an Embree BVH of the body
// (closest points, exact signed distance through the sign rule of
// systems/spatial/triangle_query.h) and, optionally, an OpenVDB
// signed-distance grid over a region of interest for the distance far from
// the surface; near the surface the BVH answers exactly.
//
// Reads: a body Model's faces of one surface and a position array. Writes:
// nothing outside itself (it keeps its own copy of the positions).
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/spatial/body_bvh.h>

namespace atelier {

struct ColliderParams {
  /// Build an OpenVDB grid for the inside tests (else the BVH answers all).
  bool use_grid = true;
  double voxel_size = 0.01;  // m
  /// The grid covers the region of interest grown by this much (m).
  double margin = 0.05;
  /// Exact queries first search this far (m); beyond it they fall back to an
  /// unbounded search (same answer, slower). Garment nodes are within it.
  double query_radius = 0.03;
};

/// Per-body collision set-up: BVH + region-of-interest SDF grid.
class BodyCollider {
 public:
  BodyCollider();
  ~BodyCollider();
  BodyCollider(BodyCollider&&) noexcept;
  BodyCollider& operator=(BodyCollider&&) noexcept;

  /// `positions` indexed by the body model's node index; `roi` the region
  /// the queries will come from (empty: the whole body). The body surface
  /// must be closed.
  [[nodiscard]] Status build(const Model& body, SurfaceIdx skin, std::span<const Vec3d> positions, const Box3d& roi,
                             const ColliderParams& params = {}, const ExecContext& ctx = {});
  /// Moves a built collider to another body of the same topology: copies
  /// the positions and refits the BVH (BvhParams::refit_on_commit), keeping
  /// the Embree device, the triangulation, the adjacency and the closedness
  /// check; rebuilds the grid when it has one. Every query answer is the
  /// same as after build() (they are exact; only the BVH boxes differ).
  /// Errors: not built, another number of positions, non-finite position.
  [[nodiscard]] Status update(std::span<const Vec3d> positions, const ExecContext& ctx = {});
  [[nodiscard]] bool built() const noexcept;
  /// Built on this body model (the same object, which must not have changed
  /// since) and skin with the same region and parameters, so update() may
  /// replace build().
  [[nodiscard]] bool reusable_for(const Model& body, SurfaceIdx skin, const Box3d& roi,
                                  const ColliderParams& params) const noexcept;
  /// Signed distance (negative inside): the grid's value where it is
  /// reliable (farther than its exact band), exact (BVH) elsewhere.
  [[nodiscard]] double signed_distance(const Vec3d& p) const;
  /// Exact signed distance, closest point and push-out normal.
  [[nodiscard]] SignedHit exact(const Vec3d& p) const noexcept;
  [[nodiscard]] const BodyBvh& bvh() const noexcept;
  [[nodiscard]] bool has_grid() const noexcept;
  [[nodiscard]] double grid_build_ms() const noexcept;

 private:
  [[nodiscard]] Status build_grid(const ExecContext& ctx);

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Colliders kept across the bodies of a batch, so that each body costs a
/// refit instead of a build (device, triangulation, adjacency). A worker
/// takes one, uses it for one body and gives it back; thread-safe.
class ColliderPool {
 public:
  [[nodiscard]] std::unique_ptr<BodyCollider> acquire();
  void release(std::unique_ptr<BodyCollider> c);

 private:
  std::mutex mutex_;
  std::vector<std::unique_ptr<BodyCollider>> free_;
};

}  // namespace atelier
