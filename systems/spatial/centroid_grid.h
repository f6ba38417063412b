// The voxel grid of polygon centroids behind the p-polygon search of detail
// templates (seed 001 section 6, determine_p-polygons, eqs. 8-10): the k
// polygons whose centroids are nearest to a garment vertex, exactly (equal
// to brute force, ties broken by index), in parallel over many queries.
//
// Reads: the caller's centroid array (copied at build). Writes: nothing
// outside itself.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>

namespace atelier {

/// Voxel grid of polygon centroids (seed 001 section 6, determine_p-polygons).
class CentroidGrid {
 public:
  /// `cell`: voxel edge length; 0 picks one from the point spacing and k.
  void build(std::span<const Vec3d> centroids, std::span<const std::uint8_t> skip, std::size_t k_hint,
             double cell = 0.0);
  /// The k nearest centroids to q, nearest first, ties broken by polygon
  /// index. Exact: rings of boxes are added until no unvisited box can hold a
  /// centroid nearer than the k-th found (the paper stops as soon as the heap
  /// holds N_q polygons, which can miss a nearer one in the next ring).
  void nearest(const Vec3d& q, std::size_t k, std::vector<std::uint32_t>& out,
               std::vector<std::pair<double, std::uint32_t>>& scratch) const;
  /// The same with an upper bound on the k-th distance (e.g. the previous,
  /// nearby query's k-th distance plus the distance between the queries, by
  /// the triangle inequality): boxes and centroids beyond it are skipped, so
  /// only about k candidates reach the heap. A bound that proves too small is
  /// detected and the search redone without it, so the result is always exact.
  /// Returns the k-th distance found.
  double nearest_bounded(const Vec3d& q, std::size_t k, double bound, std::vector<std::uint32_t>& out,
                         std::vector<std::pair<double, std::uint32_t>>& scratch) const;
  /// The k nearest centroids of every query (nearest first, as nearest()),
  /// k per query in `out` (size queries.size() * k), in parallel over blocks
  /// of consecutive queries. Each query is bounded by the previous query's
  /// result (the farthest of its k centroids from the new query bounds the
  /// new k-th distance), so garment vertices in mesh order cost little more
  /// than k distance evaluations each. Exact and independent of thread count.
  void nearest_many(std::span<const Vec3d> queries, std::size_t k, std::span<std::uint32_t> out,
                    const ExecContext& ctx = {}) const;
  [[nodiscard]] double cell() const noexcept { return cell_; }
  [[nodiscard]] std::array<int, 3> dims() const noexcept { return {nx_, ny_, nz_}; }
  [[nodiscard]] std::size_t size() const noexcept { return ids_.size(); }

 private:
  // Calls f(begin, end) for the ranges of entries in the boxes the ball of
  // squared radius r2 around q reaches (with a rounding slack).
  template <class F>
  void scan_ball(const Vec3d& q, double r2, F&& f) const;
  // nearest_bounded with the selection's bucket counts as scratch.
  double nearest_bounded(const Vec3d& q, std::size_t k, double bound, std::vector<std::uint32_t>& out,
                         std::vector<std::pair<double, std::uint32_t>>& scratch,
                         std::vector<std::uint32_t>& count) const;
  double cell_ = 1;
  Vec3d lo_ = Vec3d::Zero();
  int nx_ = 1, ny_ = 1, nz_ = 1;
  std::vector<std::uint32_t> start_;  // cell -> first entry (CSR)
  std::vector<std::uint32_t> ids_;    // polygon index per entry, in cell order
  std::vector<Vec3d> exact_;          // centroid per entry in double (exact distances)
  std::vector<Vec3d> by_id_;          // centroid per polygon index (bounds from a previous result)
  double radius_ = 0;                 // typical k_hint-th distance (first bound of a block of queries)
  std::size_t k_hint_ = 8;
};

/// Brute-force k nearest centroids (reference for tests and benchmarks).
void nearest_brute_force(std::span<const Vec3d> centroids, std::span<const std::uint8_t> skip, const Vec3d& q,
                         std::size_t k, std::vector<std::uint32_t>& out);

}  // namespace atelier
