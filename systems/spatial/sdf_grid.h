// SdfGrid: an OpenVDB narrow-band signed distance grid of a body for fast
// inside tests (seed 000 section 4.2, collision avoidance), with an exact
// fallback near the surface through the body's BodyBvh.
//
// Reads: a committed BodyBvh (its positions, triangles and pseudo-normals).
// Writes: nothing outside itself. The grid does not follow later commits of
// the BVH: rebuild it (explicit commit of derived data).
//
// Accuracy contract of inside(p) (h = voxel size, w = half width in voxels,
// e = exact band in voxels, mesh closed and consistently oriented):
//  * whenever the trilinear value d satisfies |d| < e h, or p is outside the
//    grid's region of interest, or (ROI grids) a corner of p's voxel is
//    outside the narrow band, and no exact corner decides (below), the
//    answer is BodyBvh::signed_distance(p) < 0:
//    exact up to rounding (Baerentzen & Aanaes pseudo-normal);
//  * otherwise the answer is the sign of d. Voxel values are distances to a
//    triangle (OpenVDB voxelises each triangle near it and widens the band
//    from the neighbours' closest triangles, so off the first layers a value
//    may overestimate the distance: up to 0.2 h (full) and 0.4 h (ROI)
//    measured by the tests; DISABLE_RENORMALIZATION keeps them unsmoothed).
//    A trilinear value is a convex combination of corner values; the sign of
//    d can only be wrong when the corners' signs differ, i.e. the surface
//    crosses p's cell, every corner is within sqrt(3) h of it and
//    |d| <= sqrt(3) h + (error of those near values): the default e = 2
//    covers it (zero wrong answers over 150k test points, half within a
//    voxel of the surface). Far from the surface (outside the band) full
//    grids take the sign from OpenVDB's signed flood fill of the interior.
//  * exact corners: at build every band voxel whose value is below e h is
//    replaced by BodyBvh::signed_distance of its centre (so a stored |value|
//    below e h is exact), and before asking the BVH, inside() looks for a
//    band corner c of p's cell with such an exact value and
//    |D(c)| > |p - c|: a signed distance is 1-Lipschitz, so p is strictly on
//    c's side of the surface and the sign of D(c) is the exact answer. This
//    leaves to the BVH only points within a fraction of a voxel of the
//    surface (about 1/5 of the former fallbacks on the benchmark sphere).
// sample(p) is the raw trilinear value (negative inside, +-w h outside the
// band) and carries no such guarantee near the surface.
//
// Region of interest: with params.roi, only the triangles whose bounding box
// meets a ROI box grown by (w + 3) h are voxelised (unsigned distance), and
// each band voxel gets its sign from the pseudo-normal of its closest
// triangle, which is exact where the voxel's distance ball stays inside the
// grown box (everywhere a query in the ROI looks); other voxels are dropped.
// The sub-mesh is open, so there is no flood fill: a query in the ROI whose
// voxel touches the outside of the band takes the sign of the first band
// voxel met walking along a grid line (exact: the band is complete there, so
// an inactive run of voxels cannot cross the surface), or the BVH's answer
// when the walk leaves the ROI. The walk is made once per leafless 8^3 block
// at build (all its voxels in the walk box are on one side) and looked up.
//
// Queries read voxels through a flat table of the 8^3 blocks over the
// band's bounding box (leaf values or tile value per block), not a tree
// walk: scattered queries are bound by cache misses on the tree's nodes.
//
// OpenVDB headers stay in sdf_grid.cpp (MeshToVolume.h alone costs ~11 s of
// compile time); this header is plain C++ over a pimpl.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/systems/spatial/body_bvh.h>

namespace atelier {

struct SdfParams {
  double voxel_size = 0.01;  // world units
  double half_width = 3.0;   // narrow band half width, in voxels (each side of the surface)
  double exact_band = 2.0;   // inside(): |d| < exact_band voxels is decided by the BVH
  /// Boxes where queries will be made (for example where a garment lies);
  /// empty = the whole body.
  std::vector<Box3d> roi;
};

struct SdfStats {
  std::size_t source_triangles = 0;  // triangles voxelised
  std::size_t active_voxels = 0;
  std::size_t memory_bytes = 0;
};

/// Counters of how inside() calls were decided (for benchmarks and tuning).
struct InsideStats {
  std::size_t from_grid = 0;
  std::size_t exact = 0;
};

class SdfGrid {
 public:
  SdfGrid();
  ~SdfGrid();
  SdfGrid(SdfGrid&&) noexcept;
  SdfGrid& operator=(SdfGrid&&) noexcept;
  SdfGrid(const SdfGrid&) = delete;
  SdfGrid& operator=(const SdfGrid&) = delete;

  /// Builds the grid of `body` (which must stay alive and unchanged while the
  /// grid is used: inside() falls back on it). Errors: body not built or not
  /// closed, bad parameters (voxel size <= 0, half width < 2, exact band < 0,
  /// empty ROI box), a grid that would need more than 2^30 voxels per axis,
  /// cancellation (kCancelled, through an OpenVDB interrupter). Threads come
  /// from ctx (a tbb arena around OpenVDB's parallel loops).
  [[nodiscard]] Status build(const BodyBvh& body, const SdfParams& params, const ExecContext& ctx = {});

  [[nodiscard]] bool empty() const noexcept;
  [[nodiscard]] const SdfParams& params() const noexcept;
  [[nodiscard]] const SdfStats& stats() const noexcept;
  /// True when p lies in the region where the grid answers (always for a
  /// full grid; inside one of the ROI boxes otherwise).
  [[nodiscard]] bool covers(const Vec3d& p) const noexcept;

  /// Trilinear signed distance (negative inside). Each call makes a fresh
  /// accessor: for many queries use a Sampler or the batched calls.
  [[nodiscard]] double sample(const Vec3d& p) const;
  [[nodiscard]] bool inside(const Vec3d& p) const;

  /// A cached (per-thread, not thread-safe) accessor: keep one per thread.
  /// Valid while the grid lives and is not rebuilt. From an unbuilt grid it
  /// samples NaN and answers "not inside".
  class Sampler {
   public:
    Sampler(Sampler&&) noexcept;
    Sampler& operator=(Sampler&&) noexcept;
    ~Sampler();
    [[nodiscard]] double sample(const Vec3d& p);
    [[nodiscard]] bool inside(const Vec3d& p);
    [[nodiscard]] const InsideStats& stats() const noexcept;
    struct Impl;

   private:
    friend class SdfGrid;
    explicit Sampler(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
  };
  [[nodiscard]] Sampler sampler() const;

  /// Batched, one accessor per block; identical results for any thread count.
  [[nodiscard]] Status sample_many(std::span<const Vec3d> in, std::span<double> out,
                                   const ExecContext& ctx = {}) const;
  [[nodiscard]] Status inside_many(std::span<const Vec3d> in, std::span<std::uint8_t> out,
                                   const ExecContext& ctx = {}, InsideStats* stats = nullptr) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace atelier
