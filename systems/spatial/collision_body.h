// The collision body: exact signed distances from points to a closed body
// mesh, for thousands of bodies of one topology (issue 7). The topology's
// bounding-volume hierarchy is laid out once, from the first body, and only
// refit per body (float boxes rounded outward), then searched four boxes at
// a time. Queries are exact: the closest point by point-triangle distances
// within a bound (a hint triangle's distance), the sign by the pseudo-normal
// rule of systems/spatial/triangle_query.h, so answers equal BodyBvh's.
// A second backend finds the closest triangle with Embree instead (a refit
// scene per body and rtcPointQuery bounded by the hint's distance; see
// CollisionBackend): same answers bit for bit, costs side by side in
// docs/collision.md.
//
// Reads: the body's triangles (once) and positions (per body, kept as a
// view). Writes: nothing outside itself.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/spatial/triangle_query.h>

namespace atelier {

/// Topology shared by every body of one family (built once): triangles,
/// the triangles around each vertex, the neighbour across each edge, and the
/// layout of a bounding-volume hierarchy over the triangles (which triangles
/// share a leaf, which nodes are siblings). The layout is made from the
/// first body built on the topology (median splits of triangle centroids)
/// and only refit on the others: bodies of one family are morphs of one
/// mesh, so the grouping stays tight, and a refit is O(n) with no sorting.
/// Errors: empty mesh, index out of range, an edge not shared by exactly two
/// oppositely oriented triangles (the body must be closed: inside and
/// clearance mean nothing on an open mesh).
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
  // The Embree backend's device and its idle refit scenes
  // (collision_body_embree.cpp): a scene is built once, on the first body
  // that needs one, and then lent to one body at a time and refit to it.
  struct EmbreePool;
  struct EmbreeScene;
  mutable std::once_flag embree_once_;
  mutable std::shared_ptr<EmbreePool> embree_pool_;
  void build_tree(std::span<const Vec3d> positions) const;  // once, from the first body

  TriangleTopology topo_;
  // Hierarchy layout, made by the first CollisionBody::build (call_once):
  // the results of queries never depend on it, only their cost.
  mutable std::once_flag tree_once_;
  mutable std::vector<std::uint32_t> leaf_tri_;   // triangles in leaf order, four slots per leaf (kNoTriangle pads)
  mutable std::vector<std::uint32_t> leaf_slot_;  // triangle -> its slot in leaf order
  // The same hierarchy with every other level removed: each wide node holds
  // up to four lanes (binary grandchildren), whose boxes a query tests at
  // once. Half the depth, a quarter of the dependent loads. Children always
  // follow their parent, so a reverse sweep refits.
  static constexpr std::uint32_t kEmptyLane = std::numeric_limits<std::uint32_t>::max();
  struct WideNode {
    std::uint32_t child[4];  // inner lane: wide node; leaf lane: first leaf slot; kEmptyLane
    std::uint8_t count[4];   // 0: inner lane; else the leaf's triangle count
  };
  mutable std::vector<WideNode> wide_;
};

/// Exact signed distance of a point to the body with its closest feature.
struct BodyDistance {
  double distance = 0;            // signed, negative inside
  Vec3d closest = Vec3d::Zero();  // closest body point
  Vec3d normal = Vec3d::Zero();   // unit outward direction at `closest`
  std::uint32_t triangle = kNoTriangle;
  Vec3d barycentric = Vec3d::Zero();
};

/// Which structure finds the closest triangle. Both cull only: the exact
/// distances (closest_point_on_triangle), the tie rule (smaller distance,
/// then smaller triangle index) and the sign (pseudo_normal_sign) are the
/// same code, so the answers are the same bit for bit; only the cost
/// differs (docs/collision.md).
///  * kHierarchy: the topology's hand-written 4-wide hierarchy, refit per
///    body in float boxes rounded outward;
///  * kEmbree: an Embree scene per body (RTC_BUILD_QUALITY_REFIT geometry:
///    built on the first body, refit on the others) searched by
///    rtcPointQuery, the sphere starting at the hint's distance and shrunk
///    as nearer triangles are found.
enum class CollisionBackend : std::uint8_t { kHierarchy, kEmbree };

struct CollisionBodyParams {
  /// Where the garment lies. The hierarchy covers the whole body whatever
  /// it is (its refit, ~0.3 ms for the MakeHuman skin, costs less than
  /// cutting the tree to a region), so answers and cost ignore it; callers
  /// that built the old region grid still pass it (apps/atelier/demo.cpp).
  Box3d roi;
  CollisionBackend backend = CollisionBackend::kHierarchy;
};

/// Per-body query structure: the topology's hierarchy refit to these
/// positions (float boxes rounded outward, per wide-node lane and per
/// triangle). Keeps a view of the positions: they must stay alive and
/// unchanged while it is used.
class CollisionBody {
 public:
  /// Errors: positions count differs from the topology, non-finite
  /// position, bad parameters; kEmbree: a coordinate beyond float range
  /// (Embree holds vertices in float), an Embree error.
  [[nodiscard]] Status build(std::shared_ptr<const CollisionTopology> topology, std::span<const Vec3d> positions,
                             const CollisionBodyParams& params = {}, const ExecContext& ctx = {});
  [[nodiscard]] bool empty() const noexcept { return topo_ == nullptr; }
  [[nodiscard]] const CollisionTopology& topology() const noexcept { return *topo_; }
  [[nodiscard]] std::span<const Vec3d> positions() const noexcept { return pos_; }
  /// Nodes of the refit hierarchy (set-up size).
  [[nodiscard]] std::size_t hierarchy_nodes() const noexcept { return wide_box_.size(); }
  [[nodiscard]] CollisionBackend backend() const noexcept {
    return embree_ ? CollisionBackend::kEmbree : CollisionBackend::kHierarchy;
  }

  /// Exact signed distance. `hint`: a triangle believed near (e.g. the
  /// closest one on the source body, or kNoTriangle); it only speeds the
  /// search up, the result is exact either way. Thread-safe.
  [[nodiscard]] BodyDistance query(const Vec3d& p, std::uint32_t hint = kNoTriangle) const noexcept;
  /// The same answers for a cluster of nearby points (say, 8 neighbouring
  /// garment vertices), each with its hint, in one traversal: the hints
  /// bound the distance to the cluster's bounding box within which every
  /// point's answer lies, those leaves are collected once and each point
  /// tests only them. Points without a hint, more than kClusterMax points,
  /// or a box holding too many leaves fall back to query() per point.
  /// Errors: spans of different sizes, an empty body. Thread-safe.
  static constexpr std::size_t kClusterMax = 32;
  [[nodiscard]] Status query_cluster(std::span<const Vec3d> p, std::span<const std::uint32_t> hint,
                                     std::span<BodyDistance> out) const;
  /// The same answers for many points with hints (empty: none), in
  /// parallel: the points are ordered by their hint's place in the
  /// hierarchy (a counting sort) and queried in clusters of 8 neighbours.
  /// Errors: sizes that differ, an empty body.
  [[nodiscard]] Status query_many(std::span<const Vec3d> p, std::span<const std::uint32_t> hint,
                                  std::span<BodyDistance> out, const ExecContext& ctx = {}) const;
  /// Pseudo-normal signed distance to one given triangle (the triangle must
  /// hold the closest point for the sign to be meaningful).
  [[nodiscard]] BodyDistance query_triangle(const Vec3d& p, std::uint32_t t) const noexcept;

 private:
  struct Best;        // the best triangle so far of one query
  struct FloatPoint;  // a query point in float lanes, with its rounding slack
  struct WideBox;
  [[nodiscard]] static unsigned lanes_within(const FloatPoint& q, const WideBox& b, float bound, float d2[4]) noexcept;
  [[nodiscard]] Best start_from_hint(const Vec3d& p, std::uint32_t hint) const noexcept;
  void scan_leaf(const Vec3d& p, const FloatPoint& fp, std::uint32_t first, Best& best) const noexcept;
  void query_cluster_at(const std::uint32_t* idx, std::size_t n, std::span<const Vec3d> p,
                        std::span<const std::uint32_t> hint, std::span<BodyDistance> out) const noexcept;
  /// Sign and outward direction of p's closest point r on triangle t.
  [[nodiscard]] BodyDistance signed_distance(const Vec3d& p, std::uint32_t t, const TrianglePoint& r) const noexcept;
  // The Embree backend (collision_body_embree.cpp).
  [[nodiscard]] Status build_embree(const ExecContext& ctx);
  [[nodiscard]] BodyDistance query_embree(const Vec3d& p, std::uint32_t hint) const noexcept;
  void query_cluster_embree(const std::uint32_t* idx, std::size_t n, std::span<const Vec3d> p,
                            std::span<const std::uint32_t> hint, std::span<BodyDistance> out) const noexcept;

  std::shared_ptr<const CollisionTopology> topo_;
  std::span<const Vec3d> pos_;
  struct alignas(16) WideBox {
    float lo[3][4], hi[3][4];  // [axis][lane]; empty lanes are inverted infinite boxes
  };
  std::vector<WideBox> wide_box_;  // per wide node
  // Per leaf (four slots), its triangles' boxes (float, rounded outward)
  // as one block [lo x, y, z, hi x, y, z][slot].
  std::vector<float> tri_box_;
  double extent_ = 0;  // largest absolute coordinate (bounds float rounding)
  // kEmbree: the scene lent by the topology's pool (back to it when the
  // last holder lets go); null for kHierarchy.
  std::shared_ptr<CollisionTopology::EmbreeScene> embree_;
};

}  // namespace atelier
