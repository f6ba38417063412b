// Booleans of closed nets (seed 004, Linsen "Netbased modelling", sections
// 2-3): union, intersection and the two differences of two closed polygon
// nets, in two modes.
//
// Exact mode (default; this project's rule, not the paper's): both sets of
// intersection points (A's edges through B's triangles and B's edges through
// A's) are inserted into both nets, so the intersection polygons of the two
// nets are the same polygon and the result is watertight. Paper mode: the
// result of exact mode, after which each intersection polygon's points from
// A and from B are paired by one of the paper's correspondences (Fig. 2) and
// each pair merged at its midpoint (section 3).
//
// Steps (docs/glossary.md, "net Booleans"):
//  1. n-gons are split into n triangles around their centroid (section 2);
//     each net is checked: closed, consistently oriented outwards, 2-manifold,
//     no duplicate vertices, no degenerate triangles, not self-intersecting.
//  2. Candidate triangle pairs: boxes overlapping in a box hierarchy.
//  3. Each pair is classified exactly (CGAL's filtered predicates): every
//     intersection point is named by the lowest-dimensional simplex of each
//     net holding it (vertex, edge or triangle), so coincidences (shared
//     vertices, touching solids, coplanar faces) are decided, not guessed.
//  4. Each cut triangle is re-triangulated in exact arithmetic with its
//     points and cut segments; the intersection polygons are edges of both.
//  5. The pieces between intersection polygons are kept by the winding
//     number of the other net about them (exact ray parity): union keeps
//     the outside pieces of both, intersection the inside ones, A minus B
//     A's outside and B's inside pieces reversed. Coplanar overlaps are kept
//     once (A's triangles) by the orientation rule.
// Untouched polygons (n-gons included) are copied whole.
//
// Prepared operands (geometry-central's one-call function beside a reusable
// solver; OpenVDB's and Embree's explicit commit of derived data): step 1
// and the box hierarchy depend on one net only, so PreparedNet::prepare does
// them once and net_boolean(PreparedNet, PreparedNet) reuses them; the
// one-call net_boolean(soup, soup) is prepare + prepare + that Boolean (the
// same bits and errors). With BooleanOptions::prepare_result the result
// comes prepared too, with all of prepare()'s checks (the rounded cut can
// fold a sliver over a neighbour), so a chain A - B1 - B2 - ... builds and
// checks each net once.
//
// Reads: the two polygon soups. Writes: nothing (the result is returned).
// Errors (nothing returned): kInvalidArgument, kDegenerate, kTopology,
// kNonManifold naming the net ("A"/"B") and the face (0-based, in the soup's
// order); kInternal for a bug. Results are the same bits for any thread
// count.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/net/connect.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace atelier {

namespace net_detail {
struct PreparedData;
struct PreparedAccess;
}  // namespace net_detail

enum class BooleanOp : std::uint8_t { kUnion, kIntersection, kAMinusB, kBMinusA };
enum class BooleanMode : std::uint8_t { kExact, kPaper };
/// How the kept parts are joined: along the intersection polygons (section
/// 3), or by connecting meshes across the gap left when every cut polygon
/// is dropped (section 4, Figs. 3-7).
enum class BooleanJoin : std::uint8_t { kCut, kMeshes };

/// The correspondences of seed 004 Fig. 2 between the points of a pair of
/// intersection polygons (paper mode).
enum class Correspondence : std::uint8_t {
  kVisual,       // each point to the closest point of the other polygon (short edges)
  kTopological,  // every point of the smaller polygon matched (keeps the nets' topology)
  kWindowSmall,  // compromise: topology inside a window of 2 points, else closest
  kWindowLarge,  // compromise: topology inside a window of 4 points, else closest
};

[[nodiscard]] Expected<BooleanOp> parse_boolean_op(std::string_view s);
[[nodiscard]] Expected<BooleanMode> parse_boolean_mode(std::string_view s);
[[nodiscard]] Expected<Correspondence> parse_correspondence(std::string_view s);
[[nodiscard]] Expected<BooleanJoin> parse_boolean_join(std::string_view s);  // cut, meshes

struct BooleanOptions {
  BooleanOp op = BooleanOp::kUnion;
  BooleanMode mode = BooleanMode::kExact;
  Correspondence correspondence = Correspondence::kVisual;  // paper mode only
  BooleanJoin join = BooleanJoin::kCut;
  ConnectRule rule = ConnectRule::kTriShortest;  // join by meshes only
  /// Refuse self-intersecting nets (exact test over box-overlapping pairs).
  /// Off saves about a third of the time when the caller knows. A crossing
  /// the cut meets is still refused (kTopology naming two crossing faces,
  /// found once the cut fails); one it does not meet is copied into the
  /// result unseen.
  bool check_self_intersection = true;
  /// Re-triangulate every cut triangle in exact arithmetic, without the
  /// certified fast path on doubles (the reference the fast path is tested
  /// against; the results differ at most in the diagonals chosen).
  bool exact_refinement = false;
  /// Also return the result as a PreparedNet (BooleanReport::prepared),
  /// named like a, with prepare()'s checks, self-intersection included: the
  /// exact cut does not cross itself, but its points rounded to doubles can
  /// (a sliver folded over a neighbour), and paper mode and connecting
  /// meshes move or add faces.
  bool prepare_result = false;
  /// Exact mode, joined by the cut: repair and check the result once its
  /// new points are rounded to doubles (fold_check.cpp). Slivers that
  /// rounded flat are flipped away, a fold within 16 ulps collapsed; a
  /// result that still crosses itself is refused (kTopology naming two
  /// triangles) rather than returned. On by default (issue 24, fold16): a
  /// floating-point certificate first shows, for almost every result, that
  /// no triangle with a new point is flat or meets another beyond their
  /// shared corners (1.07-1.15x the unchecked Boolean on the bench's
  /// spheres, 1.3-1.6x on its CAD pairs: docs/performance.md, fold16); only
  /// the results it cannot certify (degenerate pairs:
  /// near-copies, ulp-scale touches) pay the repair and exact check (1.2-2.3x
  /// a Boolean, fold15). Off: the rounded result is returned unchecked (it
  /// may cross itself on such pairs). prepare_result checks fully.
  bool check_result = true;
};

/// Valences (edge counts) of the vertices of the merged intersection
/// polygons in the result (paper mode), and how many differ from the
/// regular valence of a triangle net (6).
struct ValenceStats {
  std::size_t vertices = 0;
  std::size_t irregular = 0;
  std::size_t min = 0, max = 0;
  double mean = 0.0;
};

struct PrepareOptions {
  /// The net's name in messages: "net A: face 3 ..." ("A" and "B" in the
  /// one-call net_boolean).
  std::string name = "A";
  /// Refuse a self-intersecting net (exact test over box-overlapping pairs,
  /// about a third of a Boolean's time). A net prepared without it can only
  /// be used with BooleanOptions::check_self_intersection = false.
  bool check_self_intersection = true;
};

/// A closed net made ready for Booleans: its polygons (a copy), their split
/// into triangles, the checks (closed, consistently oriented outwards,
/// 2-manifold, no duplicate vertices or degenerate triangles, optionally
/// not self-intersecting; the errors of net_boolean, naming the face), the
/// box hierarchy, its volume and area. Immutable once made: a handle to
/// shared read-only data, cheap to copy, usable by several threads at once.
class PreparedNet {
 public:
  PreparedNet() = default;  // empty: not an operand
  [[nodiscard]] static Expected<PreparedNet> prepare(const PolygonSoupView& soup, const PrepareOptions& opt = {},
                                                     const ExecContext& ctx = {});
  /// The same, keeping the soup without a copy.
  [[nodiscard]] static Expected<PreparedNet> prepare(PolygonSoup&& soup, const PrepareOptions& opt = {},
                                                     const ExecContext& ctx = {});

  [[nodiscard]] bool empty() const noexcept { return !data_; }
  [[nodiscard]] const PolygonSoup& soup() const noexcept;
  [[nodiscard]] const std::string& name() const noexcept;
  [[nodiscard]] double volume() const noexcept;  // soup_volume
  [[nodiscard]] double area() const noexcept;    // soup_area
  [[nodiscard]] std::size_t triangle_count() const noexcept;
  /// Tested for self-intersection (a Boolean's prepared result always is).
  [[nodiscard]] bool self_checked() const noexcept;

 private:
  friend struct net_detail::PreparedAccess;
  explicit PreparedNet(std::shared_ptr<const net_detail::PreparedData> d) noexcept : data_(std::move(d)) {}
  std::shared_ptr<const net_detail::PreparedData> data_;
};

struct BooleanReport {
  PolygonSoup result;  // closed, outward, counter-clockwise polygons
  double volume_a = 0, volume_b = 0, volume = 0;
  double area_a = 0, area_b = 0, area = 0;
  std::size_t intersection_polygons = 0;  // closed curves where the nets meet
  std::size_t candidate_pairs = 0;        // box-overlapping triangle pairs
  std::size_t intersecting_pairs = 0;     // pairs that meet
  std::size_t intersection_points = 0;    // new points (not vertices of either net)
  std::size_t cut_triangles = 0;          // triangles re-triangulated, both nets
  std::size_t refined_exact = 0;          // of them, by the exact triangulation (not certified on doubles)
  std::size_t merged_pairs = 0;           // paper mode: matched pairs merged to midpoints
  std::vector<std::uint32_t> seam;        // result vertices on the intersection polygons (sorted)
  ValenceStats valence;                   // paper mode
  ConnectReport connecting;               // join by meshes: the connecting meshes (faces empty)
  std::size_t gaps = 0;                   // join by meshes: gaps closed
  /// With BooleanOptions::prepare_result: the result as an operand, or
  /// empty with the reason in prepared_status (an empty result, or a result
  /// that prepare() would refuse: coincident copies of a pinched vertex,
  /// paper mode's merged points crossing, a rounded sliver crossing a
  /// neighbour).
  PreparedNet prepared;
  Status prepared_status;
};

/// The Boolean `opt.op` of the closed nets a and b (see above).
[[nodiscard]] Expected<BooleanReport> net_boolean(const PolygonSoupView& a, const PolygonSoupView& b,
                                                  const BooleanOptions& opt = {}, const ExecContext& ctx = {});

/// The same Boolean of two prepared nets, without preparing them again
/// (nothing is re-checked: their checks are those of their prepare). Reads
/// a and b only: several threads may use the same prepared nets at once.
/// kInvalidArgument for an empty operand, or one prepared without the
/// self-intersection test when opt.check_self_intersection is set.
[[nodiscard]] Expected<BooleanReport> net_boolean(const PreparedNet& a, const PreparedNet& b,
                                                  const BooleanOptions& opt = {}, const ExecContext& ctx = {});

/// The live faces of a model as one polygon soup (nodes that came from the
/// same file vertex, "source_vertex", and still coincide are one vertex),
/// for nets read from files.
[[nodiscard]] PolygonSoup net_polygons(const Model& m);

/// Signed volume (divergence theorem; n-gons split around their centroid as
/// in the Booleans) and area of a polygon soup.
[[nodiscard]] double soup_volume(const PolygonSoupView& s);
[[nodiscard]] double soup_area(const PolygonSoupView& s);

}  // namespace atelier
