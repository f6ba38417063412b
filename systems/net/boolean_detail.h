// Private machinery of the net Booleans (boolean.cpp, boolean_exact.cpp,
// net_soup.cpp): the triangulated net, simplex keys of intersection points,
// the box hierarchy for candidate pairs, and the exact kernel's entry points.
// CGAL stays inside boolean_exact.cpp (docs/architecture.md, third-party).
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/storage/union_find.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace atelier {
class PreparedNet;
struct BooleanOptions;
struct BooleanReport;
}  // namespace atelier

namespace atelier::net_detail {

inline constexpr std::uint32_t kNil = 0xffffffffu;

/// A status whose message is the parts streamed one after another.
template <class... A>
[[nodiscard]] Status fail(ErrorCode c, const A&... parts) {
  std::ostringstream s;
  (s << ... << parts);
  return {c, s.str()};
}

/// The end of one stage of a net operation: progress(stage, done, total) to
/// the caller, then kCancelled if the caller cancelled. The stages are
/// coarse (each at most a parallel pass), so a cancel is seen within one.
[[nodiscard]] inline Status stage_done(const ExecContext& ctx, std::string_view stage, std::size_t done,
                                       std::size_t total) {
  ctx.report(stage, done, total);
  if (ctx.cancelled()) return {ErrorCode::kCancelled, std::string(stage) + ": cancelled"};
  return {};
}

/// A simplex of one net: dimension (0 vertex, 1 edge, 2 triangle, 3 none)
/// and index, packed so keys sort and compare as integers.
enum : std::uint8_t { kDimVertex = 0, kDimEdge = 1, kDimFace = 2, kDimNone = 3 };
[[nodiscard]] constexpr std::uint64_t simplex(std::uint8_t dim, std::uint32_t idx) noexcept {
  return (std::uint64_t{dim} << 32) | idx;
}
[[nodiscard]] constexpr std::uint8_t dim_of(std::uint64_t s) noexcept {
  return static_cast<std::uint8_t>(s >> 32);
}
[[nodiscard]] constexpr std::uint32_t idx_of(std::uint64_t s) noexcept {
  return static_cast<std::uint32_t>(s);
}
inline constexpr std::uint64_t kNoSimplex = simplex(kDimNone, 0);

/// An intersection point named by the lowest-dimensional simplex of A and of
/// B holding it (the relative interiors of a net's simplices partition it,
/// so the pair is unique: the symbolic, exact identity of the point).
struct PointKey {
  std::uint64_t a = kNoSimplex;
  std::uint64_t b = kNoSimplex;
  friend bool operator==(const PointKey&, const PointKey&) = default;
  friend auto operator<=>(const PointKey&, const PointKey&) = default;
};

/// A closed net split into triangles: n-gons around their centroid
/// (seed 004 section 2), triangles as they are.
struct TriMesh {
  std::vector<Vec3d> p;                                // net vertices, then one centroid per split n-gon
  std::size_t net_vertices = 0;                        // p[0, net_vertices) are the net's own
  std::vector<std::array<std::uint32_t, 3>> tri;       // counter-clockwise from outside
  std::vector<std::array<std::uint32_t, 3>> tri_edge;  // edge k runs tri[k] -> tri[k+1]
  std::vector<std::array<std::uint32_t, 2>> edge;      // (smaller, larger) vertex
  std::vector<std::array<std::uint32_t, 2>> edge_tri;  // the two triangles of an edge
  std::vector<std::uint32_t> face_of;                  // net polygon of each triangle
  std::vector<std::uint32_t> face_tri_begin;           // polygon f has triangles [begin[f], begin[f+1])
  std::vector<std::array<double, 6>> box;              // per triangle: lo xyz, hi xyz (exact min/max)
  Box3d bounds;
  std::string name;  // "A" or "B" in messages
};

/// Builds the triangulated net and checks that it is a closed (unless
/// `open` is allowed: trimming), consistently oriented 2-manifold without
/// duplicate vertices or degenerate triangles (errors name the polygon).
/// A boundary edge has edge_tri[e][1] == kNil. Self-intersection is
/// checked separately.
[[nodiscard]] Status build_tri_mesh(const PolygonSoupView& soup, std::string name, TriMesh& out, const ExecContext& ctx,
                                    bool open = false);

/// Triangle t's box: min x, y, z then max x, y, z (net_mesh.cpp).
[[nodiscard]] std::array<double, 6> tri_box(const TriMesh& m, std::uint32_t t);

/// Indices of `key` (undirected edges (min << 32) | max over vertices
/// below n_vertices) in order of (key, index): a counting sort on the
/// smaller vertex, then each vertex's few edges sorted in place. Linear in
/// the edges for meshes of bounded valence, instead of a comparison sort.
void sort_edge_keys(std::span<const std::uint64_t> key, std::size_t n_vertices, std::vector<std::uint32_t>& order);

/// Bounding-volume hierarchy over triangle boxes (median split, leaves of
/// up to 8 triangles): node i has children or not (a leaf), and the range
/// of `order` below it.
struct Bvh {
  struct Node {
    std::array<double, 6> box;
    std::uint32_t left = kNil;  // inner: left child (right = left + 1); leaf: kNil
    std::uint32_t first = 0;    // first index into order
    std::uint32_t count = 0;    // triangles below the node
  };
  std::vector<Node> nodes;
  std::vector<std::uint32_t> order;        // triangle indices, leaves' ranges
  std::vector<std::array<double, 6>> box;  // box of triangle order[i]
};
void build_bvh(const TriMesh& m, Bvh& out, const ExecContext& ctx);

/// Candidate pairs (i in A, j in B) whose closed boxes overlap, sorted.
[[nodiscard]] std::vector<std::array<std::uint32_t, 2>> overlapping_pairs(const TriMesh& a, const Bvh& bvh_a,
                                                                          const TriMesh& b, const Bvh& bvh_b,
                                                                          const ExecContext& ctx);
/// The smallest pair i < j of triangles of one mesh that cross
/// (triangles_cross), or {kNil, kNil} when the mesh does not intersect itself.
[[nodiscard]] std::array<std::uint32_t, 2> first_self_crossing(const TriMesh& m, const Bvh& bvh,
                                                               const ExecContext& ctx);

/// The side of q against the plane through a with the rounded normal n:
/// orient3d expanded along q - a, the same products as Shewchuk's
/// expansion, so his first-stage bound (7 + 56 eps) eps times the permanent
/// holds (every input a double, each difference rounded once). nabs[k] is
/// n[k]'s permanent (the sum of its two products' magnitudes). 0 when the
/// filter cannot tell: below 1e-250 underflow could exceed the bound, and
/// infinity voids it. The self-check's and the result certificate's test.
[[nodiscard]] inline int filtered_plane_side(const double* n, const double* nabs, const Vec3d& a,
                                             const Vec3d& q) noexcept {
  const double wx = q.x() - a.x(), wy = q.y() - a.y(), wz = q.z() - a.z();
  const double det = wx * n[0] + wy * n[1] + wz * n[2];
  const double perm = std::abs(wx) * nabs[0] + std::abs(wy) * nabs[1] + std::abs(wz) * nabs[2];
  constexpr double kBound = 7.7715611723761027e-16;  // (7 + 56 eps) eps, eps = 2^-53
  if (!(perm > 1e-250) || !(perm < std::numeric_limits<double>::infinity())) return 0;
  const double bound = kBound * perm;
  return det > bound ? 1 : (-det > bound ? -1 : 0);
}

/// The orientation of (a, b, c) seen along `axis` (coordinates axis + 1 and
/// axis + 2): +1 or -1 when Shewchuk's orient2d bound (3 + 16 eps) eps
/// certifies it, 0 when the filter cannot tell.
[[nodiscard]] inline int certified_orient2(const Vec3d& a, const Vec3d& b, const Vec3d& c, int axis) noexcept {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const double left = (a[i] - c[i]) * (b[j] - c[j]), right = (a[j] - c[j]) * (b[i] - c[i]);
  const double det = left - right, sum = std::abs(left) + std::abs(right);
  constexpr double kBound = 3.3306690738754716e-16;  // (3 + 16 eps) eps
  if (!(sum > 1e-280) || !(sum < std::numeric_limits<double>::infinity())) return 0;
  const double bound = kBound * sum;
  return det > bound ? 1 : (-det > bound ? -1 : 0);
}

/// Per node of bvh (m's hierarchy): 1 when the node's triangles certainly
/// form an embedded disk (self_check.cpp: a disk whose triangles all
/// project along one axis with the same certain orientation and whose
/// boundary projects to a certainly simple polygon), so no two of them
/// cross and first_self_crossing skips the node's pairs with itself.
[[nodiscard]] std::vector<std::uint8_t> embedded_nodes(const TriMesh& m, const Bvh& bvh, const ExecContext& ctx);

// ----------------------------------------------------------- exact kernel
// All decisions below are exact (CGAL's filtered predicates on the input
// doubles, and the lazy exact kernel for constructed points).

/// Sign of the orientation of d against the plane of (a, b, c): +1 on the
/// side the normal (b - a) x (c - a) points to.
[[nodiscard]] int orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) noexcept;
/// Starts a new generation of orient3d's per-thread memo of far questions
/// (called by cut_nets): answers are never stale, but a benchmark repeating
/// one Boolean must not find the previous run's.
void new_orient3d_memo_generation() noexcept;
/// Exactly collinear (or coincident) points: a degenerate triangle.
[[nodiscard]] bool collinear(const Vec3d& a, const Vec3d& b, const Vec3d& c) noexcept;

/// The intersection points of triangle ta of A and tb of B (exactly
/// classified, named by their simplex keys; sorted, unique) and whether the
/// two triangles are coplanar. Empty when they are disjoint.
struct PairHit {
  std::vector<PointKey> points;
  bool coplanar = false;
};
void intersect_pair(const TriMesh& a, std::uint32_t ta, const TriMesh& b, std::uint32_t tb, PairHit& out);

/// True when triangles t1 and t2 of one net intersect other than in the
/// vertices and edge they share (exact).
[[nodiscard]] bool triangles_cross(const TriMesh& m, std::uint32_t t1, std::uint32_t t2);

/// Global ids of intersection points: sorted unique keys; a key naming a
/// vertex of A is that vertex, one naming a vertex of B (and none of A) is
/// nA + that vertex, any other gets nA + nB + its rank among such keys.
struct PointIds {
  std::vector<PointKey> keys;     // sorted unique
  std::vector<std::uint32_t> id;  // per key
  [[nodiscard]] std::uint32_t find(const PointKey& k) const;
};

/// The lazy exact points of the new intersection points (in the order of
/// `keys`), made once and shared by every triangle holding one, so a point's
/// exact value is computed at most once (the lazy kernel caches it; its
/// evaluation is thread-safe). Opaque: CGAL stays in boolean_exact.cpp.
struct ExactPoints;
struct ExactPointsDeleter {
  void operator()(ExactPoints* p) const noexcept;
};
using ExactPointsPtr = std::unique_ptr<ExactPoints, ExactPointsDeleter>;
/// Only the keys with need[i] != 0 get their lazy exact point (the others'
/// ok stays 0): those of the cut triangles the certified fast path left to
/// the exact one, and those whose interval box does not pin the output.
[[nodiscard]] ExactPointsPtr make_exact_points(const TriMesh& a, const TriMesh& b, std::span<const PointKey> keys,
                                               std::span<const std::uint8_t> need, const ExecContext& ctx);

/// A box certainly holding a new intersection point (lo xyz, hi xyz), from
/// interval arithmetic on the input doubles; ok false when no interval
/// formula bounds it (then only the exact path uses the point).
struct PointBox {
  std::array<double, 6> b{};
  bool ok = false;
};
[[nodiscard]] PointBox point_box(const TriMesh& a, const TriMesh& b, const PointKey& k) noexcept;

/// The certified fast path of refine_triangle: a constrained Delaunay
/// triangulation of the points' double coordinates (their boxes' centres,
/// in the triangle's affine frame) with CGAL's filtered predicates, then certified against the boxes (every
/// triangle's orientation certainly positive for any points in the boxes,
/// every cut segment an edge, the boundary the triangle's edges with their
/// points in certified order). False (and `out` as it was) when any check
/// cannot be certified: the caller then runs the exact refine_triangle.
/// `boxes` are the new points' (id first_new + i). projected: the
/// triangulation runs on the boxes' centres in the triangle's projection
/// instead of its affine frame (for a triangle much larger than its cut:
/// the frame would merge the points), with the same certificates.
[[nodiscard]] bool refine_triangle_fast(const TriMesh& a, const TriMesh& b, int side, std::uint32_t t,
                                        std::span<const PointKey> points,
                                        std::span<const std::array<PointKey, 2>> constraints, const PointIds& ids,
                                        std::span<const PointBox> boxes, std::uint32_t first_new,
                                        std::vector<std::array<std::uint32_t, 3>>& out, bool projected = false);

/// For a new point whose coordinates point_coordinates takes from its exact
/// value (not a pinned edge-face box): x = that value rounded to nearest
/// (the same doubles), and `box` narrowed to x's neighbours, which hold
/// the exact value. False (box and x as they were) for a pinned point or
/// when the rounding cannot be done without the lazy kernel.
[[nodiscard]] bool rounded_box(const TriMesh& a, const TriMesh& b, const PointKey& k, PointBox& box, Vec3d& x);

// ---- cray16: new points rounded by exact expansions (round_exact.cpp), the
// two-point split of a cut triangle (boolean_exact.cpp)
/// The point where edge (p, q) crosses a triangle lying in the plane
/// x_k = level, rounded to nearest (ties to even, +0 for a zero): the same
/// doubles as rounded_point's Mpzf rounding, from Shewchuk's expansions.
/// False (out untouched) when it cannot tell cheaply (inputs outside
/// [2^-400, 2^400], a zero or tiny coordinate, the edge in the plane): the
/// caller rounds in Mpzf.
[[nodiscard]] bool round_edge_through_level_plane(const Vec3d& p, const Vec3d& q, int k, double level,
                                                  Vec3d& out) noexcept;

/// The two-point split of refine_triangle_fast without CGAL's CDT (on by
/// default; off: every cut triangle through CGAL's CDT, the reference the
/// tests compare with). Process-wide; for tests and measurements.
void set_direct_split(bool on) noexcept;
/// How many cut triangles the two-point split took so far (all threads).
[[nodiscard]] std::uint64_t direct_split_count() noexcept;

/// Refines triangle t of one side (0: A, 1: B) by the given intersection
/// points (keys whose simplex on this side lies in the triangle's closure)
/// and constraint segments, by a constrained triangulation in exact
/// arithmetic. Appends triangles of global ids, oriented like t.
[[nodiscard]] Status refine_triangle(const TriMesh& a, const TriMesh& b, int side, std::uint32_t t,
                                     std::span<const PointKey> points,
                                     std::span<const std::array<PointKey, 2>> constraints, const PointIds& ids,
                                     const ExactPoints& exact, std::vector<std::array<std::uint32_t, 3>>& out);

/// Coordinates of a new intersection point, rounded from its exact value.
/// An edge through a triangle: its box's centre when the box is at most
/// four ulps wide in every coordinate (within 2 ulps of the exact value);
/// otherwise the exact value rounded to nearest.
[[nodiscard]] Vec3d point_coordinates(const TriMesh& a, const TriMesh& b, const PointKey& k, const PointBox& box,
                                      const ExactPoints& exact, std::size_t index);

/// Winding number of the closed net m about a point: a double point not on
/// m, or the centroid of three intersection points / vertices (exact), by an
/// exact ray parity with deterministic directions (a direction that meets
/// an edge or a vertex of m is replaced by the next).
[[nodiscard]] int winding_number(const TriMesh& m, const Bvh& bvh, const Vec3d& q);
/// `boxes`: each corner's PointBox when it is a new point (else nullptr),
/// for the certified interval path tried before the exact one.
[[nodiscard]] int winding_number_centroid(const TriMesh& m, const Bvh& bvh, const TriMesh& a, const TriMesh& b,
                                          const std::array<PointKey, 3>& corners,
                                          const std::array<const PointBox*, 3>& boxes);

/// Same orientation (+1) or opposite (-1) of two coplanar triangles.
[[nodiscard]] int coplanar_orientation(const TriMesh& a, std::uint32_t ta, const TriMesh& b, std::uint32_t tb);

/// One net's share of the cut: its cut triangles, their points and
/// segments, their refinement, and its pieces.
struct CutSide {
  const TriMesh* m = nullptr;
  int side = 0;
  std::uint32_t offset = 0;                                        // global id of vertex 0
  std::vector<std::uint32_t> slot;                                 // triangle -> index in cut, or kNil
  std::vector<std::uint32_t> cut;                                  // cut triangles, increasing
  std::vector<std::vector<PointKey>> points;                       // per cut triangle
  std::vector<std::vector<std::array<PointKey, 2>>> segments;      // per cut triangle
  std::vector<std::vector<std::uint32_t>> coplanar_with;           // per cut triangle: the other net's triangles
  std::vector<std::vector<std::array<std::uint32_t, 3>>> refined;  // per cut triangle, canonical ids
  std::vector<std::uint64_t> edges;                                // sorted edges of the refined triangles
  // Pieces: triangle t owns pieces [piece_begin[t], piece_begin[t+1]).
  std::vector<std::uint32_t> piece_begin;
  std::vector<std::array<std::uint32_t, 3>> piece;
  std::vector<std::int8_t> coplanar;  // per piece: 0 no, +1 same orientation as the other net, -1 opposite
  std::vector<std::uint32_t> component;
  std::vector<std::uint8_t> keep;  // per piece
};

/// Both nets cut along their intersection.
struct Cut {
  CutSide sides[2];
  PointIds ids;
  std::uint32_t nA = 0, nB = 0;           // ids: A's vertices, then B's, then new points
  std::vector<std::uint32_t> canon;       // id -> canonical id (A's vertex where a B vertex coincides)
  std::vector<std::uint64_t> on_a, on_b;  // canonical id -> simplex of A / B holding it, or none
  std::vector<PointKey> new_keys;         // new points (id nA + nB + k)
  std::vector<Vec3d> new_points;          // their rounded coordinates
  std::vector<PointBox> new_boxes;        // their interval boxes
  std::size_t candidate_pairs = 0, intersecting_pairs = 0;
  std::size_t refined_exact = 0;  // cut triangles the certified fast path left to the exact triangulation
  [[nodiscard]] Vec3d position(const TriMesh& a, const TriMesh& b, std::uint32_t id) const {
    return id < nA ? a.p[id] : (id < nA + nB ? b.p[id - nA] : new_points[id - nA - nB]);
  }
};

/// A cut or a Boolean that failed (st) on nets a and b: when either net
/// crosses itself (a caller's promise broken with the self-intersection
/// check off: the cut is not defined for it), the check's own error naming
/// the first crossing pair of faces, the other net (side 1 - first) first;
/// else st. Runs the self-intersection test: failure paths only.
[[nodiscard]] Status explain_by_crossing(Status st, const TriMesh& a, const Bvh& bvh_a, const TriMesh& b,
                                         const Bvh& bvh_b, const ExecContext& ctx, int first = 1);

/// Cuts A and B along their intersection (either may be open: trimming).
/// exact_only: every cut triangle by the exact triangulation (the
/// reference the certified fast path is tested against).
[[nodiscard]] Status cut_nets(const TriMesh& a, const Bvh& bvh_a, const TriMesh& b, const Bvh& bvh_b,
                              const ExecContext& ctx, Cut& out, bool exact_only = false);

/// The rounded result's repair and fold check (fold_check.cpp, issue 24,
/// round 19), on the result before unpinch. is_new: per output vertex, a
/// new (rounded) point. repair_flat_triangles removes each triangle with a
/// new point whose corners rounded onto one line, the middle one strictly
/// between the others, and splits the face across its long edge at that
/// corner (a fan from it); returns how many, split_edges gets the removed
/// long edges (undirected keys). check_rounded_result tests the result's
/// triangles with a new point against each other and against the kept
/// pieces of both nets near them (exact triangles_cross; coincident points
/// count as one; flat triangles left out): a kTopology error naming them
/// when a pair crosses, and in short_edge the shortest edge of the two
/// within 16 ulps that has a new point (else kNil): collapse = {that edge}
/// first (the new point snapped onto the other end when the link condition
/// allows it), then the check again, may remove the fold.
/// touched (snap17; per output vertex, when given): set for the vertex a
/// collapse keeps and the corner a flip fans from, so that the caller
/// passes is_new | touched to check_rounded_result as its suspects (a face
/// changed by the repair whose corners are all the nets' own vertices is
/// otherwise tested by nobody: not a suspect, and its cut piece, holding
/// the collapsed new point, not a neighbour).
std::size_t repair_flat_triangles(PolygonSoup& out, std::vector<std::uint8_t>& face_side,
                                  std::span<const std::uint8_t> is_new, std::vector<std::uint64_t>& split_edges,
                                  std::span<const std::array<std::uint32_t, 2>> collapse = {},
                                  std::vector<std::uint8_t>* touched = nullptr);
/// snap17: the crossing pair check_rounded_result found, when `pair` is
/// given: per triangle, its corners' output ids (kNil for a point not in
/// the output: a whole n-gon's centroid) and positions.
struct FoldPair {
  std::array<std::array<std::uint32_t, 3>, 2> v{};
  std::array<std::array<Vec3d, 3>, 2> p{};
};
[[nodiscard]] Status check_rounded_result(const Cut& cut, const TriMesh& a, const Bvh& bvh_a, const TriMesh& b,
                                          const Bvh& bvh_b, const PolygonSoup& out,
                                          std::span<const std::uint32_t> out_index,
                                          std::span<const std::uint8_t> is_new,
                                          std::span<const std::uint64_t> split_edges,
                                          std::array<std::uint32_t, 2>& short_edge, const ExecContext& ctx,
                                          FoldPair* pair = nullptr);

// ---- cross18: the whole self-test of a result with coincident vertex copies (fold_check.cpp)
/// The result's faces that cross (a pair of output face indices; {f, f}
/// when face f itself is degenerate), or {kNil, kNil} when none: its
/// polygons split as build_tri_mesh splits them, vertex ids merged by exact
/// position (coincident copies of a pinched vertex count as one corner: a
/// touch there is not a crossing, as in the fold check), flat triangles left
/// out (or, with flat_refused, named as {f, f}), every pair whose boxes
/// meet decided by triangles_cross. For results prepare_result stops at
/// (duplicate vertices) before its crossing test.
[[nodiscard]] std::array<std::uint32_t, 2> pinched_self_crossing(const PolygonSoup& out, const ExecContext& ctx,
                                                                 bool flat_refused);

// ---- flat19: zero-length edges merged away (flat_merge.cpp)
struct FlatMerge {
  std::size_t merged = 0;  // zero-length edges whose two ids became one
  std::size_t left = 0;    // zero-length edges left (the merge would not leave a 2-manifold)
};
/// On a result after unpinch: every edge whose two ids are at one position
/// (a zero-length edge, as in a flat face two of whose corners coincide)
/// has its ids merged into the smaller one when the result stays a
/// 2-manifold about it (each edge at the kept id in exactly two faces, one
/// each way, and its faces one fan): the faces using the edge lose the
/// repeated corner (a triangle vanishes; it had no area), no position
/// moves. Ids no face uses any more are dropped; remap gets, per old id,
/// its new id (a merged id: its keeper's; kNil: dropped), identity-sized
/// only when something changed (empty otherwise). face_side follows the
/// faces.
[[nodiscard]] FlatMerge merge_flat_edges(PolygonSoup& out, std::vector<std::uint8_t>& face_side,
                                         std::vector<std::uint32_t>& remap);
/// How many zero-length edges the Booleans merged away (process-wide, for
/// the tests: a test shows the merge ran).
[[nodiscard]] std::atomic<std::size_t>& flat_merge_count() noexcept;

// ---- snap17: folds repaired by moving new points (fold_repair.cpp)
/// Called when fold15's repair and check leave the result crossing itself
/// (`st`, the check's error, and `pair`, its crossing pair): new points of
/// each crossing pair are moved to a nearby double (another rounding of
/// their exact value's neighbourhood: up to 1024 ulps per coordinate, the
/// star never flat and crossing fewer triangles near it, exactly counted) or
/// snapped onto a neighbour (an edge collapse under the link condition),
/// and check_rounded_result runs again, up to a budget of rounds. Returns
/// the check's last status (its suspects: `suspect`, is_new | touched,
/// updated by the collapses): ok when the result no longer crosses itself
/// (then `out` and face_side hold the repaired result), else the error
/// (`out` may hold some moves: the caller refuses the Boolean).
/// Sequential and in a fixed order: the same bits for any thread count.
[[nodiscard]] Status repair_folds(const Cut& cut, const TriMesh& a, const Bvh& bvh_a, const TriMesh& b,
                                  const Bvh& bvh_b, PolygonSoup& out, std::vector<std::uint8_t>& face_side,
                                  std::span<const std::uint32_t> out_index, std::span<const std::uint8_t> is_new,
                                  std::vector<std::uint64_t>& split_edges, std::vector<std::uint8_t>& suspect,
                                  Status st, FoldPair pair, const ExecContext& ctx);
/// Process-wide count of Booleans whose fold repair_folds removed (tests
/// and the bench read it).
[[nodiscard]] std::atomic<std::size_t>& fold_repair_count() noexcept;
/// degen19: process-wide switch (tests) between repair_folds' lean search
/// (true, the default: a candidate's crossings counted only until they
/// reach the best so far, ulp steps computed once per step, boxes and
/// scratch meshes reused) and snap17's search as merged (false). The same
/// moves, verdicts and bytes either way (degenerate_pairs_test.cpp).
[[nodiscard]] std::atomic<bool>& fold_repair_lean() noexcept;

// ---- fold16: the rounded result's certificate (fold_certificate.cpp)
/// What certify_rounded_result looked at: the cut triangles with a kept
/// piece that has a new point, the pairs of triangles whose boxes meet (each
/// with such a piece), how many of them the filters left to the exact
/// test, and the verdict.
struct CertifyStats {
  std::size_t cut_triangles = 0, pairs = 0, exact_pairs = 0;
  bool certified = false;
  /// cert17: the cut triangles whose own pieces rounded_pieces_embedded
  /// certified (their pairs skipped), and the neighbouring pairs of net
  /// triangles it certified together.
  std::size_t embedded_triangles = 0, embedded_neighbours = 0;
};
/// True when the rounded result (the kept pieces of `cut`, its new points
/// rounded) certainly needs neither repair nor fold check: every kept piece
/// with a new point is certainly not flat and meets every other kept piece
/// (of both nets) at most in the corners it shares with it (by canonical
/// id). Floating-point filters with Shewchuk's bounds, triangles_cross
/// where they cannot tell; false as soon as a pair is not certainly apart.
/// Then repair_flat_triangles and check_rounded_result would leave the
/// result as it is and find no crossing.
[[nodiscard]] bool certify_rounded_result(const Cut& cut, const TriMesh& a, const Bvh& bvh_a, const TriMesh& b,
                                          const Bvh& bvh_b, const ExecContext& ctx, CertifyStats* stats = nullptr);

// ---- cert17: the certificate's shortcut within a net triangle (fold_embedding.cpp)
/// True when the pieces (kept or not) of `tris` on `side` -- one cut
/// triangle u, or u and a neighbour sharing an edge with it, u first --
/// certainly form an embedded triangulation at their rounded positions,
/// seen along the dominant axis of u's normal: every piece with a certain
/// orient2d sign equal to u's, and the boundary (u's or the
/// quadrilateral's corners, the points on its edges between them)
/// certainly a simple polygon. Then two of those pieces meet only in the
/// corners they share by id (Floater 2003; the proof at the top of
/// fold_embedding.cpp), and certify_rounded_result skips their pairs.
/// Floating-point filters only: false when one cannot tell.
[[nodiscard]] bool rounded_pieces_embedded(const Cut& cut, const TriMesh& a, const TriMesh& b, int side,
                                           std::span<const std::uint32_t> tris);
/// The certificate's level-plane rule (cert17) on two triangles given by
/// corners and ids (equal ids: the same point): true when y lies in a plane
/// x_k = l, x does not, and they certainly meet at most in the corners they
/// share by id. For the tests (the certificate calls it on its own pieces).
[[nodiscard]] bool level_plane_pieces_apart(const std::array<Vec3d, 3>& y, const std::array<std::uint32_t, 3>& y_ids,
                                            const std::array<Vec3d, 3>& x,
                                            const std::array<std::uint32_t, 3>& x_ids) noexcept;
/// cert17's rules on (the default) or off (no pair skipped, no level-plane
/// rule: fold16's certificate, the reference the tests compare verdicts and
/// bytes with). Process-wide; for tests and measurements.
void set_embedding_shortcut(bool on) noexcept;
/// Process-wide counts of certify_rounded_result's verdicts (tests and the
/// bench read them): results certified, results sent to the full check.
struct ResultCheckCounts {
  std::atomic<std::size_t> certified{0}, full{0};
  /// cert17: the pairs the certificate tested, and the cut triangles whose
  /// own pieces rounded_pieces_embedded certified.
  std::atomic<std::size_t> pairs{0}, embedded{0};
};
[[nodiscard]] ResultCheckCounts& result_check_counts() noexcept;

/// Appends the kept pieces of one side (`keep` of its CutSide) to `out`:
/// untouched polygons whole (n-gons stay n-gons), cut ones as triangles;
/// out_index maps ids to output vertices (kNil: not yet used), face_side
/// records the side of each face.
void emit_side(const Cut& cut, const TriMesh& a, const TriMesh& b, int side, const PolygonSoupView& soup, bool reverse,
               PolygonSoup& out, std::vector<std::uint32_t>& out_index, std::vector<std::uint8_t>& face_side);

/// The tables of a prepared net (PreparedNet, prepared_net.cpp): what the
/// Booleans compute per operand, once.
struct PreparedData {
  TriMesh mesh;
  Bvh bvh;
  PolygonSoup owned;            // the polygons, when the prepared net owns them
  PolygonSoupView soup;         // their arrays: owned's, or the caller's (the one-call net_boolean)
  double volume = 0, area = 0;  // soup_volume, soup_area
  bool self_checked = false;    // tested for self-intersection (a Boolean's prepared result always is)
};

/// The outcome of each step of prepare_data, kept apart so that the
/// one-call Boolean reports two nets' errors in its order: both builds,
/// then both volumes, then both self-intersection tests.
struct PrepareSteps {
  Status built, volume, crossing;
};

/// Builds d.mesh and d.bvh from d.soup (set by the caller) and checks them:
/// build_tri_mesh, a positive volume, and first_self_crossing when asked
/// (and the volume is positive); d.volume and d.area when built.
void prepare_data(PreparedData& d, std::string name, bool check_self_intersection, const ExecContext& ctx,
                  PrepareSteps& steps);

/// The result of a Boolean as a prepared net named `name`, checked as
/// prepare() checks it, self-intersection included (the cut's rounded
/// points can fold a sliver over a neighbour: issue 24, round 18); empty
/// with the reason in `why` otherwise.
[[nodiscard]] PreparedNet prepare_result(const PolygonSoup& result, std::string name, const ExecContext& ctx,
                                         Status& why);

/// The tables behind a PreparedNet (nullptr when empty), and a PreparedNet
/// over given tables.
struct PreparedAccess {
  [[nodiscard]] static const PreparedData* get(const PreparedNet& p) noexcept;
  [[nodiscard]] static PreparedNet make(std::shared_ptr<const PreparedData> d) noexcept;
};

/// Paper mode (seed 004 section 3, Fig. 2): on an exact result, the points
/// of A's and of B's intersection polygons (`from_a`, `from_b` per vertex;
/// both for points on an edge of each) along each curve of `curve` edges are
/// paired by the correspondence and each pair merged at its midpoint.
[[nodiscard]] Status apply_paper_mode(PolygonSoup& result, std::span<const std::array<std::uint32_t, 2>> curve,
                                      std::span<const std::uint8_t> from_a, std::span<const std::uint8_t> from_b,
                                      int correspondence, std::size_t& merged, std::size_t& vertices,
                                      std::size_t& irregular, std::size_t& vmin, std::size_t& vmax, double& vmean,
                                      std::vector<std::uint32_t>& seam);

}  // namespace atelier::net_detail
