// CornerMesh: the face-corner incidence of a polygon soup in flat arrays
// (CSR, no pointers), what Catmull-Clark refinement and the control-mesh
// fairing walk. Corner c of face f is face_verts[face_offsets[f] + k]; its
// outgoing edge (to the next corner of the face) is corner_edge[c]. An edge
// knows its two corners (the second is kNoCorner on the boundary); a vertex
// knows its corners (one per incident face), in increasing corner order.
//
// Reads: a polygon soup's faces. Writes: nothing outside the returned mesh.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>

namespace atelier {

inline constexpr std::uint32_t kNoCorner = 0xffffffffu;

struct CornerMesh {
  std::uint32_t vertex_count = 0;
  std::vector<std::uint32_t> face_offsets{0};  // F + 1
  std::vector<std::uint32_t> face_verts;       // one per corner
  std::vector<std::uint32_t> corner_face;      // one per corner; empty when `quads`
  /// Every face has 4 corners and face f owns corners 4f .. 4f+3: corner
  /// arithmetic replaces corner_face (Catmull-Clark levels after the first).
  bool quads = false;
  std::vector<std::uint32_t> corner_edge;                  // edge from this corner to the next one of its face
  std::vector<std::array<std::uint32_t, 2>> edge_verts;    // (tail, head) of the first corner's direction
  std::vector<std::array<std::uint32_t, 2>> edge_corners;  // [1] = kNoCorner on the boundary
  std::vector<std::uint32_t> vert_offsets;                 // V + 1
  std::vector<std::uint32_t> vert_corners;                 // corners at each vertex

  [[nodiscard]] std::size_t face_count() const noexcept { return face_offsets.size() - 1; }
  [[nodiscard]] std::size_t edge_count() const noexcept { return edge_verts.size(); }
  [[nodiscard]] std::size_t corner_count() const noexcept { return face_verts.size(); }
  [[nodiscard]] std::uint32_t face_of(std::uint32_t c) const noexcept { return quads ? c >> 2 : corner_face[c]; }
  [[nodiscard]] std::uint32_t next_corner(std::uint32_t c) const noexcept {
    if (quads) return (c & ~3u) | ((c + 1) & 3u);
    const std::uint32_t f = corner_face[c];
    return c + 1 == face_offsets[f + 1] ? face_offsets[f] : c + 1;
  }
  [[nodiscard]] std::uint32_t prev_corner(std::uint32_t c) const noexcept {
    if (quads) return (c & ~3u) | ((c + 3) & 3u);
    const std::uint32_t f = corner_face[c];
    return c == face_offsets[f] ? face_offsets[f + 1] - 1 : c - 1;
  }
  [[nodiscard]] bool is_boundary_edge(std::uint32_t e) const noexcept { return edge_corners[e][1] == kNoCorner; }
  /// The edge between a and b, or kNoCorner.
  [[nodiscard]] std::uint32_t find_edge(std::uint32_t a, std::uint32_t b) const noexcept;
  /// Neighbours of v in rotation order (following faces across edges),
  /// and whether the ring closes (v is interior). Neighbours appear once.
  bool ring(std::uint32_t v, std::vector<std::uint32_t>& out) const;
};

/// Builds the incidence of `vertex_count` vertices and the soup's faces
/// (positions unused). Errors naming the face: an index out of range, a
/// face with fewer than 3 corners or a repeated vertex, an edge used twice
/// in the same direction or by more than two faces (the mesh must be an
/// oriented 2-manifold with boundary).
[[nodiscard]] Expected<CornerMesh> build_corner_mesh(const PolygonSoupView& faces, std::size_t vertex_count,
                                                     const ExecContext& ctx = {});

}  // namespace atelier
