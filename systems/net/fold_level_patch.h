// cert18: the result certificate's rule for a whole level patch
// (fold_level_patch.cpp: the proof is at its top). Its own header, included
// only by fold_certificate.cpp, fold_level_patch.cpp and the certificate's
// tests, so that adding it does not rebuild every file of the net library.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "boolean_detail.h"

namespace atelier::net_detail {

/// The pieces (kept or not) of one cut triangle, or of two sharing an edge,
/// all lying in the plane x_k = l (as doubles): its vertices and edges by
/// canonical id. Only meaningful for pieces rounded_pieces_embedded
/// certified (the caller's part).
struct LevelPatch {
  int k = 0;
  double l = 0;
  /// An open-addressing set (linear probing, a power of two at least four
  /// times its size, ~0 empty) of the vertices, keyed (id << 32) | id, and
  /// the edges, keyed (min id << 32) | max id (a piece's ids are distinct,
  /// so the keys never collide): built in one pass, no sort.
  std::vector<std::uint64_t> keys;
  int shift = 64;
  [[nodiscard]] bool has(std::uint64_t key) const noexcept;
};
/// The level patch of `tris` on `side` (one cut triangle, or two sharing an
/// edge): false unless all their pieces' corners lie in one plane x_k = l
/// with l finite.
[[nodiscard]] bool make_level_patch(const Cut& cut, const TriMesh& a, const TriMesh& b, int side,
                                    std::span<const std::uint32_t> tris, LevelPatch& pt);
/// True when the triangle x (corners, canonical ids) certainly meets every
/// piece of the embedded level patch `pt` at most in the corners (or the
/// edge) it shares with it by id: x's corners off the plane strictly on one
/// side, and its corners on the plane none, a vertex or an edge of the
/// patch (the proof at the top of fold_level_patch.cpp).
[[nodiscard]] bool level_patch_apart(const LevelPatch& pt, const std::array<Vec3d, 3>& x,
                                     const std::array<std::uint32_t, 3>& x_ids) noexcept;
/// For the tests: rounded_pieces_embedded, make_level_patch and
/// level_patch_apart in one (the certificate makes its patches once and
/// calls the rule on its own pieces).
[[nodiscard]] bool level_patch_pieces_apart(const Cut& cut, const TriMesh& a, const TriMesh& b, int side,
                                            std::span<const std::uint32_t> tris, const std::array<Vec3d, 3>& x,
                                            const std::array<std::uint32_t, 3>& x_ids);
/// The rule on (the default) or off (cert17's certificate, the tests'
/// reference; set_embedding_shortcut(false) switches it off too).
/// Process-wide; for tests and measurements.
void set_level_patch_rule(bool on) noexcept;
[[nodiscard]] bool level_patch_rule_on() noexcept;
/// Process-wide counts: level patches made, and the times a piece (or a
/// query's suspect) was decided against a whole patch at once.
struct LevelPatchCounts {
  std::atomic<std::size_t> patches{0}, skips{0};
};
[[nodiscard]] LevelPatchCounts& level_patch_counts() noexcept;

// ---- cert19: the certificate's hierarchy walks shared (fold_certificate.cpp)
/// Neighbouring cut triangles cut into few pieces share one walk of the
/// nets' hierarchies (on, the default) or each walks them alone (off: the
/// tests' reference; the same pairs either way). Process-wide; for tests
/// and measurements.
void set_grouped_walk(bool on) noexcept;
[[nodiscard]] bool grouped_walk_on() noexcept;
/// Process-wide count of the certificate's walks (one per group).
struct CertWalkCounts {
  std::atomic<std::size_t> walks{0};
};
[[nodiscard]] CertWalkCounts& cert_walk_counts() noexcept;

}  // namespace atelier::net_detail
