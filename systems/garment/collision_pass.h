// Collision pass: a regenerated garment never enters the body and keeps the
// clearance it had on the source body (issue 7). Shared by detail and profile
// regeneration; seed 001 section 6 decodes without any collision step, seed
// 000 section 4.2 (Fig. 16) avoids collisions during fairing by sub-steps.
//
//  1. Encoding (once per garment): each garment vertex stores its signed
//     distance to the source body (its clearance) and its closest source
//     triangle (a hint: on a body of the same topology the distance to that
//     triangle bounds the distance to the whole surface from above).
//  2. Per body: a CollisionBody over the body triangles: the topology's
//     bounding-volume hierarchy refit to the body (float boxes rounded
//     outward), searched four boxes at a time. Queries are exact: closest
//     point by point-triangle distances within the hint's bound, sign by the
//     angle-weighted pseudo-normal of the closest feature (Baerentzen &
//     Aanaes 2005), computed on demand.
//  3. Pass: every vertex inside the body or closer than its target clearance
//     c_v = clamp(encoded, min_clearance, max_clearance) moves to x + c_v n
//     (x its closest body point, n the outward normal there: the distance
//     gradient, or the pseudo-normal on the surface); repeated a few rounds
//     where concave parts of the body make one push fall short. Then the
//     moved region (grown by `fair_rings` rings; none by default: spreading
//     a push over unmoved neighbours strains more edges, 0.2-0.7 points of
//     excess strain p95 on MakeHuman garments) is smoothed by umbrella
//     fairing (seed 000 section 4.2, Kobbelt's U2 Jacobi iteration, half
//     steps, along the body normal only) with all other vertices fixed.
//     What is faired is the pass's displacement (position minus position on
//     entry), not the garment: the bump a push leaves is spread over its
//     neighbours while the garment's own shape (its folds, and the skin
//     stretch the edge transfer gave it) is kept; fairing positions would
//     flatten it and add strain. Every move is applied in sub-steps and cut
//     at the last one that keeps the vertex at or above its target clearance.
//     Sub-steps are tested on the tangent plane at the closest body point
//     (first-order signed distance, no query); the end state is verified by
//     one exact query per vertex that moved by more than its margin over
//     its target (the distance is 1-Lipschitz, so the others cannot have
//     crossed it), and a vertex found deeper than both its target and its
//     pre-fairing distance returns to its pushed position.
//  4. Layers: garments are resolved in z_depth order (inner first); each
//     resolved layer leaves a clearance floor on the body vertices under it
//     and outer layers keep at least that floor plus `layer_gap`.
//
// Reads: body positions and triangles, garment positions and adjacency.
// Writes: garment positions (in place) and the report.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/smooth/fairing.h>

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
  [[nodiscard]] std::span<const Triangle> triangles() const noexcept { return triangles_; }
  [[nodiscard]] std::uint32_t point_count() const noexcept { return point_count_; }

 private:
  friend class CollisionBody;
  void build_tree(std::span<const Vec3d> positions) const;  // once, from the first body

  std::vector<Triangle> triangles_;
  std::uint32_t point_count_ = 0;
  std::vector<std::uint32_t> vt_offset_, vt_tri_;     // vertex -> incident triangles (CSR)
  std::vector<std::array<std::uint32_t, 3>> across_;  // triangle, edge k (corner k -> k+1) -> other triangle
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

struct CollisionBodyParams {
  /// Where the garment lies. The hierarchy covers the whole body whatever
  /// it is (its refit, ~0.3 ms for the MakeHuman skin, costs less than
  /// cutting the tree to a region), so answers and cost ignore it; callers
  /// that built the old region grid still pass it (apps/atelier/demo.cpp).
  Box3d roi;
};

/// Per-body query structure: the topology's hierarchy refit to these
/// positions (float boxes rounded outward, per wide-node lane and per
/// triangle). Keeps a view of the positions: they must stay alive and
/// unchanged while it is used.
class CollisionBody {
 public:
  /// Errors: positions count differs from the topology, non-finite
  /// position, bad parameters.
  [[nodiscard]] Status build(std::shared_ptr<const CollisionTopology> topology, std::span<const Vec3d> positions,
                             const CollisionBodyParams& params = {}, const ExecContext& ctx = {});
  [[nodiscard]] bool empty() const noexcept { return topo_ == nullptr; }
  [[nodiscard]] const CollisionTopology& topology() const noexcept { return *topo_; }
  [[nodiscard]] std::span<const Vec3d> positions() const noexcept { return pos_; }
  /// Nodes of the refit hierarchy (set-up size).
  [[nodiscard]] std::size_t hierarchy_nodes() const noexcept { return wide_box_.size(); }

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
  [[nodiscard]] Vec3d face_normal(std::uint32_t t) const noexcept;  // area-weighted (unnormalised)
  /// Sign and outward direction of p's closest point r on triangle t.
  [[nodiscard]] BodyDistance signed_distance(const Vec3d& p, std::uint32_t t, const TrianglePoint& r) const noexcept;

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
};

/// Clearance encoding of a garment on its source body.
struct ClearanceEncoding {
  std::vector<float> clearance;         // signed distance to the source body per vertex
  std::vector<std::uint32_t> triangle;  // closest source triangle per vertex (hint on other bodies)
};

/// Signed distances of the garment vertices to the source body. Errors:
/// empty garment, non-finite vertex (naming it).
[[nodiscard]] Expected<ClearanceEncoding> encode_clearance(std::span<const Vec3d> garment, const CollisionBody& source,
                                                           const ExecContext& ctx = {});

struct CollisionParams {
  double min_clearance = 0.0005;  // floor of every target clearance (m)
  double max_clearance = 0.05;    // cap: a loose garment's far parts are never pushed farther
  /// Vertices within this much below their target are left alone (the pass
  /// does not chase rounding).
  double tolerance = 0.001;
  int push_rounds = 3;       // push, re-query, push again where concavities make it fall short
  int fair_rings = 0;        // rings of unmoved neighbours freed around the moved region (0: the moved region alone)
  int fair_iterations = 10;  // umbrella iterations (0: no smoothing)
  int substeps = 4;          // sub-steps of a fairing move (tested on the tangent plane)
  double layer_gap = 0.001;  // resolve_layers: outer layer at least this far outside the inner one
};

struct CollisionReport {
  std::size_t vertices = 0;
  std::size_t inside_before = 0;  // signed distance < 0 on entry
  std::size_t below_before = 0;   // below target clearance - tolerance on entry
  std::size_t pushed = 0;         // vertices moved by the push
  std::size_t faired = 0;         // free vertices of the smoothing
  std::size_t inside_after = 0;   // signed distance < 0 on exit
  std::size_t below_after = 0;    // below min(target, floor) - tolerance on exit
  double max_depth_before = 0;    // deepest penetration on entry (>= 0)
  double max_depth_after = 0;
  std::uint64_t queries = 0;        // exact body queries
  std::uint64_t refused_moves = 0;  // fairing sub-steps cut by the collision test
};

/// The pass, in place on `garment`. `encoding` gives the target clearances
/// and hints (its triangles must index the body's topology; an empty
/// `triangle` array means no hints). Errors: empty garment, sizes that do
/// not match, empty body, bad parameters, non-finite vertex.
[[nodiscard]] Expected<CollisionReport> resolve_collisions(std::span<Vec3d> garment, const NodeAdjacency& adjacency,
                                                           const ClearanceEncoding& encoding, const CollisionBody& body,
                                                           const CollisionParams& params, const ExecContext& ctx = {});
/// The same, also giving each vertex's exact distance to the body at its
/// final position (the pass's own last query of it), so that a caller
/// reporting clearance does not query every vertex again.
[[nodiscard]] Expected<CollisionReport> resolve_collisions(std::span<Vec3d> garment, const NodeAdjacency& adjacency,
                                                           const ClearanceEncoding& encoding, const CollisionBody& body,
                                                           const CollisionParams& params,
                                                           std::vector<BodyDistance>& final_distance,
                                                           const ExecContext& ctx = {});

/// One garment of a layered outfit.
struct GarmentLayer {
  std::span<Vec3d> positions;
  const NodeAdjacency* adjacency = nullptr;
  const ClearanceEncoding* encoding = nullptr;
  int z_depth = 0;  // MakeHuman's layer order: smaller is nearer the skin
};

/// Resolves the layers inner first (stable by z_depth); each outer layer's
/// target clearance is at least the clearance of the inner layers under it
/// (interpolated on the body triangle under the vertex) plus layer_gap.
/// Reports in the order given.
[[nodiscard]] Expected<std::vector<CollisionReport>> resolve_layers(std::span<GarmentLayer> layers,
                                                                    const CollisionBody& body,
                                                                    const CollisionParams& params,
                                                                    const ExecContext& ctx = {});

}  // namespace atelier
