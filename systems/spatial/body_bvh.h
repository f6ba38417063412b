// BodyBvh: an Embree BVH over a triangulated body for closest-point queries,
// first-hit rays and an exact inside test (seed 000 section 4.2: collision
// avoidance needs "inside the body?" and "where is the surface?" for every
// new garment vertex).
//
// Reads: caller's point and triangle arrays (never a Model directly; see
// fan_triangulate below). Writes: nothing outside itself.
//
// Derived data is committed explicitly (Embree style): build() takes the
// topology, commit() re-reads the positions and rebuilds (or refits) the BVH
// and the pseudo-normals. Queries see the geometry as of the last commit.
//
// Embree headers stay inside body_bvh.cpp (they dominate compile time); this
// header is plain C++ over a pimpl.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/spatial/triangle_query.h>

namespace atelier {

/// Non-owning strided view of 3D points: a column of Vec3f, Vec3d, or xyz
/// floats inside a larger record. The caller keeps the memory alive (and
/// unchanged between commit() calls) as long as the BVH uses it.
struct StridedPoints {
  enum class Scalar : std::uint8_t { kFloat, kDouble };
  const void* data = nullptr;
  std::size_t stride = 0;  // bytes between consecutive points
  std::size_t count = 0;
  Scalar scalar = Scalar::kFloat;
  /// Float views only: the caller guarantees that 4 more bytes are readable
  /// after the last point's z. Embree reads its vertices as 16-byte vectors,
  /// so a float view is shared zero-copy with Embree only when it is padded
  /// (or its stride is at least 16 bytes); otherwise it is copied.
  bool padded = false;

  [[nodiscard]] static StridedPoints of(std::span<const Vec3f> p) noexcept {
    return {p.data(), sizeof(Vec3f), p.size(), Scalar::kFloat, false};
  }
  [[nodiscard]] static StridedPoints of(std::span<const Vec3d> p) noexcept {
    return {p.data(), sizeof(Vec3d), p.size(), Scalar::kDouble, false};
  }
  [[nodiscard]] static StridedPoints floats(const float* xyz, std::size_t stride_bytes, std::size_t n,
                                            bool padded = false) noexcept {
    return {xyz, stride_bytes, n, Scalar::kFloat, padded};
  }
  [[nodiscard]] Vec3d operator[](std::size_t i) const noexcept {
    const auto* base = static_cast<const unsigned char*>(data) + i * stride;
    if (scalar == Scalar::kFloat) {
      const auto* f = reinterpret_cast<const float*>(base);
      return {f[0], f[1], f[2]};
    }
    const auto* d = reinterpret_cast<const double*>(base);
    return {d[0], d[1], d[2]};
  }
};

struct ClosestHit {
  Vec3d point = Vec3d::Zero();
  Vec3d barycentric = Vec3d::Zero();
  double distance = std::numeric_limits<double>::infinity();
  std::uint32_t triangle = kNoTriangle;  // kNoTriangle when the BVH is empty
  TriFeature feature = TriFeature::kFace;
};

/// Signed distance with the angle-weighted pseudo-normal of the closest
/// feature (Baerentzen & Aanaes 2005): negative inside.
struct SignedHit {
  double distance = std::numeric_limits<double>::infinity();  // signed
  ClosestHit closest;
  Vec3d normal = Vec3d::Zero();  // unit pseudo-normal at the closest feature (push-out direction)
};

struct RayHit {
  bool hit = false;
  double t = std::numeric_limits<double>::infinity();
  std::uint32_t triangle = kNoTriangle;
  Vec3d barycentric = Vec3d::Zero();
  Vec3d point = Vec3d::Zero();
  Vec3d normal = Vec3d::Zero();  // unit geometric normal of the hit triangle
};

struct BvhParams {
  /// When positions change but not the topology, commit() refits the BVH
  /// (RTC_BUILD_QUALITY_REFIT) instead of rebuilding it: faster, looser boxes.
  bool refit_on_commit = true;
  /// Build quality of the initial build: 0 low, 1 medium, 2 high.
  int build_quality = 1;
};

class BodyBvh {
 public:
  BodyBvh();
  ~BodyBvh();
  BodyBvh(BodyBvh&&) noexcept;
  BodyBvh& operator=(BodyBvh&&) noexcept;
  BodyBvh(const BodyBvh&) = delete;
  BodyBvh& operator=(const BodyBvh&) = delete;

  /// Sets the topology and the position view, then commits. Errors: empty
  /// mesh, index out of range, non-finite referenced vertex, more than 2^32-2
  /// points or triangles. Points referenced by no triangle are ignored. The
  /// view (and the triangle array, which is copied) may be the caller's
  /// columns; positions are read again by every commit().
  [[nodiscard]] Status build(const StridedPoints& points, std::span<const Triangle> triangles,
                             const BvhParams& params = {}, const ExecContext& ctx = {});
  /// Convenience: build over a span of Vec3f or Vec3d.
  [[nodiscard]] Status build(std::span<const Vec3d> points, std::span<const Triangle> triangles,
                             const BvhParams& params = {}, const ExecContext& ctx = {}) {
    return build(StridedPoints::of(points), triangles, params, ctx);
  }
  /// Re-reads the positions through the view given to build() (the memory
  /// may have changed in place; its count must not) and refits or rebuilds
  /// the BVH, face, edge and vertex normals.
  [[nodiscard]] Status commit(const ExecContext& ctx = {});
  /// Same, with a new view of the same number of points (for example after
  /// the caller's column was reallocated).
  [[nodiscard]] Status commit(const StridedPoints& points, const ExecContext& ctx = {});

  [[nodiscard]] bool empty() const noexcept;
  [[nodiscard]] std::size_t num_triangles() const noexcept;
  [[nodiscard]] std::size_t num_points() const noexcept;
  /// Positions as of the last commit (double copy used by the exact queries).
  [[nodiscard]] std::span<const Vec3d> positions() const noexcept;
  [[nodiscard]] std::span<const Triangle> triangles() const noexcept;
  /// True when the Embree vertex buffer shares the caller's memory.
  [[nodiscard]] bool zero_copy() const noexcept;
  [[nodiscard]] Box3d bounds() const noexcept;

  /// Every undirected edge used by exactly two triangles in opposite
  /// directions: the mesh is closed and consistently oriented. The signed
  /// distance and the inside tests are only meaningful when it is.
  [[nodiscard]] bool closed() const noexcept;
  /// kTopology naming the first offending edge when !closed().
  [[nodiscard]] Status require_closed() const;

  // ------------------------------------------------------------ queries
  // All queries are const and thread-safe; batched versions run through
  // engine/parallel.h and give identical results for any thread count.

  /// Exact closest point (double precision point-triangle distance; the
  /// Embree traversal only culls). Ties go to the smallest triangle index.
  [[nodiscard]] ClosestHit closest_point(const Vec3d& p) const noexcept;
  /// The same result, faster when `bound` is an upper bound on the distance
  /// (the search starts with that radius; when nothing lies within it, an
  /// unbounded search follows, so a wrong bound costs time, never accuracy).
  [[nodiscard]] ClosestHit closest_point(const Vec3d& p, double bound) const noexcept;
  [[nodiscard]] Status closest_points(std::span<const Vec3d> in, std::span<ClosestHit> out,
                                      const ExecContext& ctx = {}) const;

  /// First hit along origin + t dir, t in [0, tmax]; dir need not be unit
  /// (t is in units of dir). Embree finds the triangle, t is refined in double.
  [[nodiscard]] RayHit ray_first_hit(const Vec3d& origin, const Vec3d& dir,
                                     double tmax = std::numeric_limits<double>::infinity()) const noexcept;
  [[nodiscard]] Status ray_first_hits(std::span<const Vec3d> origins, std::span<const Vec3d> dirs,
                                      std::span<RayHit> out, const ExecContext& ctx = {}) const;

  /// Exact signed distance (negative inside) by the angle-weighted
  /// pseudo-normal at the closest feature: vertex normals weighted by the
  /// incident angles, edge normals as the sum of the two face normals
  /// (Baerentzen & Aanaes, "Signed distance computation using the angle
  /// weighted pseudonormal", 2005). Requires closed() for a meaningful sign;
  /// the sign is exact up to rounding for points not on the surface.
  [[nodiscard]] SignedHit signed_distance(const Vec3d& p) const noexcept;
  /// With an upper bound on |distance| (see closest_point(p, bound)).
  [[nodiscard]] SignedHit signed_distance(const Vec3d& p, double bound) const noexcept;
  /// The same, given that `triangle` holds the closest point of p (used by
  /// the SDF grid, whose voxels know their closest triangle).
  [[nodiscard]] SignedHit signed_distance_to(const Vec3d& p, std::uint32_t triangle) const noexcept;
  [[nodiscard]] bool inside(const Vec3d& p) const noexcept { return signed_distance(p).distance < 0.0; }
  /// Batched; errors when the mesh is not closed (require_closed()).
  [[nodiscard]] Status signed_distances(std::span<const Vec3d> in, std::span<double> out,
                                        const ExecContext& ctx = {}) const;
  [[nodiscard]] Status inside_many(std::span<const Vec3d> in, std::span<std::uint8_t> out,
                                   const ExecContext& ctx = {}) const;

  /// Generalized winding number (Jacobson et al. 2013) by brute force over
  /// all triangles: the sum of signed solid angles / 4 pi (Van Oosterom &
  /// Strackee). ~1 inside, ~0 outside a closed mesh; O(triangles) per point,
  /// for tests and for robustness on open meshes.
  [[nodiscard]] double winding_number(const Vec3d& p) const noexcept;
  [[nodiscard]] Status winding_numbers(std::span<const Vec3d> in, std::span<double> out,
                                       const ExecContext& ctx = {}) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace atelier
