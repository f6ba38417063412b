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
#include <string_view>
#include <vector>

namespace atelier {

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
  /// Off saves about a third of the time when the caller knows.
  bool check_self_intersection = true;
  /// Re-triangulate every cut triangle in exact arithmetic, without the
  /// certified fast path on doubles (the reference the fast path is tested
  /// against; the results differ at most in the diagonals chosen).
  bool exact_refinement = false;
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
};

/// The Boolean `opt.op` of the closed nets a and b (see above).
[[nodiscard]] Expected<BooleanReport> net_boolean(const PolygonSoupView& a, const PolygonSoupView& b,
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
