// The polygon soup: polygons over indices in CSR form, with or without
// positions. What readers produce before a Model is built, what generators
// and bodies share between thousands of position arrays, and what garments
// that a Model would refuse (non-manifold, inconsistently oriented) are kept
// as. Types that carry more (a reader's line numbers, a topology hash) are
// polygon soups with those members added.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>

namespace atelier {

/// Triangle as three indices into a point array, counter-clockwise seen from
/// outside (inside tests rely on that orientation).
using Triangle = std::array<std::uint32_t, 3>;

/// Face f has nodes face_nodes[face_offsets[f] .. face_offsets[f+1]),
/// counter-clockwise seen from outside. `positions` may be empty when the
/// soup describes a topology shared by many position arrays. `corner_uv`
/// holds texture coordinates per face corner (OBJ `vt`, seams kept), or is
/// empty: they belong to the topology, so a soup regenerated on another
/// body keeps them unchanged.
struct PolygonSoup {
  std::vector<Vec3d> positions;
  std::vector<std::uint32_t> face_offsets{0};  // size F+1, starts at 0
  std::vector<std::uint32_t> face_nodes;
  std::vector<Vec2d> corner_uv;  // empty, or one per face_nodes entry

  [[nodiscard]] std::size_t face_count() const noexcept { return face_offsets.size() - 1; }
  [[nodiscard]] std::span<const std::uint32_t> face(std::size_t f) const noexcept {
    return {face_nodes.data() + face_offsets[f], face_offsets[f + 1] - face_offsets[f]};
  }
  /// Appends a face over the given nodes.
  void add_face(std::span<const std::uint32_t> nodes);
  /// Undirected edges of the polygons (consecutive corners), sorted and
  /// unique; a corner repeated next to itself gives no edge.
  [[nodiscard]] std::vector<std::array<std::uint32_t, 2>> edges() const;
  /// Structure check: offsets start at 0 and never decrease, end at the
  /// node count, every face has at least 3 corners and every index is below
  /// `vertex_count` (positions.size() when 0), corner_uv empty or one per
  /// corner. Names the first bad face.
  [[nodiscard]] Status check(std::size_t vertex_count = 0) const;
};

/// The same arrays borrowed (zero copy from a reader's or a generator's
/// columns): the form functions that only read a soup take.
struct PolygonSoupView {
  std::span<const Vec3d> positions;
  std::span<const std::uint32_t> face_offsets;  // size F+1, starts at 0
  std::span<const std::uint32_t> face_nodes;

  PolygonSoupView() = default;
  PolygonSoupView(std::span<const Vec3d> p, std::span<const std::uint32_t> offsets,
                  std::span<const std::uint32_t> nodes) noexcept
      : positions(p), face_offsets(offsets), face_nodes(nodes) {}
  PolygonSoupView(const PolygonSoup& s) noexcept  // NOLINT(google-explicit-constructor)
      : positions(s.positions), face_offsets(s.face_offsets), face_nodes(s.face_nodes) {}
  [[nodiscard]] std::size_t face_count() const noexcept { return face_offsets.empty() ? 0 : face_offsets.size() - 1; }
};

}  // namespace atelier
