// Quadrangulation of one face cycle (seed 003 section 6.1): the cycle's
// control polygon (b vertices, b even) is filled with quads by an advancing
// front (Schaefer, Warren & Zorin 2004, the paper's Fig. 9): the front starts
// as the boundary; each step lays a row of quads along a chain of the front
// between two corners (front vertices with an interior angle at most
// `corner_angle_degrees`) and replaces the chain by the row's inner side,
// so the front loses two edges; a chain whose opposite side has as many
// edges closes the front. The new vertices of a row get their positions by
// eq. (3): q_i = p_i + (1 - s_i) v_0 + s_i v_n, where v_0 and v_n are the
// front edges leaving the chain's two ends inwards and s_i the arc-length
// fraction of p_i along the chain. A front whose chains all have two edges
// (a triangle, pentagon, ... cut at its side midpoints) is closed by a fan
// of quads around one new vertex at its centroid; so is any front for which
// no row can be laid without repeating an edge or making a forbidden chord
// (always possible for an even front: the fan joins no two front vertices).
//
// The result is a quad disk: with I new vertices, F = I + b/2 - 1 faces;
// the boundary vertices keep their positions (they are not copied: local
// indices [0, b) are the boundary, [b, b + I) the new vertices). Quads run
// in the boundary's direction (counter-clockwise when it is).
//
// Reads: the boundary positions. Writes: nothing outside the result.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>

namespace atelier {

struct QuadrangulateOptions {
  double corner_angle_degrees = 135.0;
  /// Close fronts whose chains all have 2 edges with a centre fan.
  bool centre_fill = true;
};

/// Optional: chords (new edges between two boundary vertices, local
/// indices) the caller forbids, e.g. between two points of a curve segment
/// that the face on its other side could join too.
using ChordFilter = std::function<bool(std::uint32_t, std::uint32_t)>;

struct QuadPatch {
  std::vector<Vec3d> interior;                      // new vertices, local index b + i
  std::vector<std::array<std::uint32_t, 4>> quads;  // local indices
  std::size_t rows = 0, closing_rows = 0, fans = 0;
};

/// Errors: fewer than 4 or an odd number of boundary vertices, a
/// non-finite position (kInvalidArgument).
[[nodiscard]] Expected<QuadPatch> quadrangulate_cycle(std::span<const Vec3d> boundary,
                                                      const QuadrangulateOptions& opt = {},
                                                      const ChordFilter& forbidden = {});

}  // namespace atelier
