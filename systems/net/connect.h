// Connecting nets by meshes (seed 004 section 4, Figs. 3-7): the gap
// between two boundary polygons P and Q is closed by a strip of new meshes
// whose edges all run from P to Q (no new vertex). Every rule is a shortest
// monotone path through the grid of the two polygons (node (i, j) = new
// edge p_i q_j; a step (di, dj) = one mesh with di edges of P and dj of Q),
// with the rule's cost:
//   triangles (steps (1,0) and (0,1); always m + n triangles):
//     (a) kTriShortest     total length of the new edges,
//     (b) kTriOneSided     valences of P's vertices towards 6, then length,
//     (c) kTriTwoSided     valences of both towards 6, length only to break ties;
//   quads (steps (1,1), (2,0), (0,2); all quads exactly when m + n is even):
//     (i)   kQuadValence          valences towards 4 and the meshes' sides,
//     (ii)  kQuadRegularVertices  fewest vertices of valence != 4 (meshes
//                                 of 5 sides allowed),
//     (iii) kQuadRegularMeshes    fewest non-quads (at most one: a triangle
//                                 when m + n is odd), then fewest irregular
//                                 vertices.
// The valence of a polygon vertex in the joined net is its valence in its
// net plus the new edges at it. Departure (docs/glossary.md): the vertices
// of the first new edge (the seam of the closed path) are charged their
// valence at the path's start and end separately.
//
// Branching (one polygon facing several): P is split by chords between the
// vertices where its nearest facing polygon changes, and each part is
// connected to its own polygon (a middle face closes the chords when there
// are three or more).
//
// Reads: positions, the polygons. Writes: nothing (faces are returned).
#pragma once

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace atelier {

enum class ConnectRule : std::uint8_t {
  kTriShortest,          // (a)
  kTriOneSided,          // (b)
  kTriTwoSided,          // (c)
  kQuadValence,          // (i)
  kQuadRegularVertices,  // (ii)
  kQuadRegularMeshes,    // (iii)
};
[[nodiscard]] Expected<ConnectRule> parse_connect_rule(std::string_view s);  // a, b, c, i, ii, iii

/// A closed boundary polygon: vertex indices in the order of its free
/// (faceless) side, so that the new meshes run along p_k -> p_{k+1}; two
/// facing polygons of a gap therefore run in opposite directions.
struct BoundaryPolygon {
  std::vector<std::uint32_t> vertices;
  /// Valence of each vertex in its net (empty: 4 for triangle rules, 3 for
  /// quad rules, the valences of a regular net's boundary).
  std::vector<std::uint32_t> valence;
};

struct ConnectOptions {
  ConnectRule rule = ConnectRule::kTriShortest;
  /// Largest new-edge run kept exactly in the valence cost (longer runs
  /// cost as this many).
  int max_run = 15;
};

struct ConnectReport {
  PolygonSoup faces;  // positions empty: indices are the caller's
  std::size_t triangles = 0, quads = 0, other = 0;
  std::size_t irregular_vertices = 0;  // polygon vertices whose valence ends != 6 (tri) or != 4 (quad rules)
  double new_edge_length = 0.0;
  double cost = 0.0;  // the rule's cost of the chosen path
};

/// Closes the gap between P and Q (see above). Errors: fewer than 3
/// vertices, an index outside `positions`, a valence list of the wrong size.
[[nodiscard]] Expected<ConnectReport> connect_polygons(std::span<const Vec3d> positions, const BoundaryPolygon& p,
                                                       const BoundaryPolygon& q, const ConnectOptions& opt = {});

/// Branching: P faces several polygons qs (seed 004 section 4).
[[nodiscard]] Expected<ConnectReport> connect_branching(std::span<const Vec3d> positions, const BoundaryPolygon& p,
                                                        std::span<const BoundaryPolygon> qs,
                                                        const ConnectOptions& opt = {});

}  // namespace atelier
