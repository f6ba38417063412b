// The result certificate's rule for a whole level patch (issue 24, cert18):
// a piece x of one net triangle is decided against every piece of a cut
// triangle u lying in a plane x_k = l at once, not one pair at a time.
//
// The setting: u's pieces (kept or not) all lie in a plane x_k = l (every
// corner's k coordinate equal to l as doubles: Cray's slab top, CAD faces,
// whose new points round onto the plane exactly), and they form an
// embedded triangulation once rounded (rounded_pieces_embedded: u alone, or
// u with a level neighbour across an edge; the patch P).
//
// Why it holds: x's corners off the plane are all strictly on one side
// (exact comparisons of doubles), so x meets the plane exactly in the hull
// q of its corners on it (none, a point, or an edge: x is convex and its
// other points lie strictly off the plane). Every piece y of P lies in the
// plane, so x and y meet at most in q and y. When q is empty they are
// apart. When q is a vertex or an edge of P's triangulation (by canonical
// id: the ids the cut's pieces use, one rounded position each), q and y are
// two simplices of one embedded simplicial complex: cert17's proof at the
// top of fold_embedding.cpp makes the rounded map of P one-to-one, and as
// the pieces lie in the plane its projection along k loses nothing. Two
// simplices of an embedded complex meet exactly in their common face:
// nothing, a corner of y that is a corner of q and so of x by id, or q
// itself when q is an edge of y (x and y then share that edge by id and
// meet only in it). That is all the certificate's pair tests (cert_apart,
// cert_level_apart) show one pair at a time, so skipping those pairs
// certifies nothing they would not. A q whose corners are not a vertex or
// an edge of P (a point of x on the plane inside a piece, an edge across
// pieces, a point at a patch vertex's place under another id) is left to
// the pair tests.
//
// Where it pays (Cray, the prepared Booleans): Cray_left's small cut
// triangles cross the slab top along edges of its fan (both sides of the
// intersection curve carry the same new points), and the slab's side faces
// meet the top in its boundary edges or corners: about 1,800 of the
// certificate's ~2,200 pairs per Boolean, now one rule per (piece, patch).
#include "fold_level_patch.h"

#include <algorithm>

namespace atelier::net_detail {
namespace {

std::uint64_t edge_key(std::uint32_t i, std::uint32_t j) noexcept {
  return (std::uint64_t{std::min(i, j)} << 32) | std::max(i, j);
}

constexpr std::uint64_t kEmpty = ~std::uint64_t{0};

std::size_t slot_of(std::uint64_t key, int shift) noexcept {
  return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift);
}

/// The plane x_k = l holding every corner of t's pieces (kept or not), as
/// doubles; false when there is none (or l is not finite).
bool piece_level(const Cut& cut, const TriMesh& a, const TriMesh& b, const CutSide& s, std::uint32_t t, int& k,
                 double& l) {
  if (s.piece_begin[t] == s.piece_begin[t + 1]) return false;
  const Vec3d p0 = cut.position(a, b, cut.canon[s.piece[s.piece_begin[t]][0]]);
  bool level[3] = {true, true, true};
  for (std::uint32_t p = s.piece_begin[t]; p < s.piece_begin[t + 1]; ++p)
    for (std::size_t c = 0; c < 3; ++c) {
      const Vec3d q = cut.position(a, b, cut.canon[s.piece[p][c]]);
      for (int i = 0; i < 3; ++i) level[i] = level[i] && q[i] == p0[i];
    }
  for (k = 0; k < 3; ++k)
    if (level[k]) {
      l = p0[k];
      return l - l == 0;
    }
  return false;
}

std::atomic<bool>& rule_on() noexcept {
  static std::atomic<bool> on{true};
  return on;
}

}  // namespace

bool make_level_patch(const Cut& cut, const TriMesh& a, const TriMesh& b, int side, std::span<const std::uint32_t> tris,
                      LevelPatch& pt) {
  const CutSide& s = cut.sides[side];
  for (std::size_t i = 0; i < tris.size(); ++i) {
    int k = 0;
    double l = 0;
    if (!piece_level(cut, a, b, s, tris[i], k, l)) return false;
    if (i == 0) {
      pt.k = k;
      pt.l = l;
    } else if (k != pt.k || l != pt.l) {
      return false;
    }
  }
  std::size_t n = 0;
  for (const std::uint32_t t : tris) n += 6 * (s.piece_begin[t + 1] - s.piece_begin[t]);
  std::size_t size = 16;
  pt.shift = 60;
  while (size < 4 * n) {
    size *= 2;
    --pt.shift;
  }
  pt.keys.assign(size, kEmpty);
  auto insert = [&](std::uint64_t key) {
    for (std::size_t i = slot_of(key, pt.shift);; i = (i + 1) & (size - 1)) {
      if (pt.keys[i] == key) return;
      if (pt.keys[i] == kEmpty) {
        pt.keys[i] = key;
        return;
      }
    }
  };
  for (const std::uint32_t t : tris)
    for (std::uint32_t p = s.piece_begin[t]; p < s.piece_begin[t + 1]; ++p) {
      std::uint32_t v[3];
      for (std::size_t c = 0; c < 3; ++c) v[c] = cut.canon[s.piece[p][c]];
      for (std::size_t c = 0; c < 3; ++c) {
        insert(edge_key(v[c], v[c]));
        insert(edge_key(v[c], v[(c + 1) % 3]));
      }
    }
  return true;
}

bool level_patch_apart(const LevelPatch& pt, const std::array<Vec3d, 3>& x,
                       const std::array<std::uint32_t, 3>& x_ids) noexcept {
  int side = 0, n_on = 0;
  std::uint32_t on[2] = {0, 0};
  for (std::size_t c = 0; c < 3; ++c) {
    const double v = x[c][pt.k];
    if (v == pt.l) {
      if (n_on == 2) return false;  // x in the plane
      on[n_on++] = x_ids[c];
      continue;
    }
    if (!(v < pt.l || v > pt.l)) return false;  // NaN
    const int sd = v > pt.l ? 1 : -1;
    if (side != 0 && sd != side) return false;  // x crosses the plane
    side = sd;
  }
  if (n_on == 0) return true;
  if (n_on == 1) return pt.has(edge_key(on[0], on[0]));
  return on[0] != on[1] && pt.has(edge_key(on[0], on[1]));
}

bool LevelPatch::has(std::uint64_t key) const noexcept {
  if (keys.empty()) return false;
  const std::size_t mask = keys.size() - 1;
  for (std::size_t i = slot_of(key, shift);; i = (i + 1) & mask) {
    if (keys[i] == key) return true;
    if (keys[i] == kEmpty) return false;
  }
}

bool level_patch_pieces_apart(const Cut& cut, const TriMesh& a, const TriMesh& b, int side,
                              std::span<const std::uint32_t> tris, const std::array<Vec3d, 3>& x,
                              const std::array<std::uint32_t, 3>& x_ids) {
  if (!rounded_pieces_embedded(cut, a, b, side, tris)) return false;
  LevelPatch pt;
  return make_level_patch(cut, a, b, side, tris, pt) && level_patch_apart(pt, x, x_ids);
}

void set_level_patch_rule(bool on) noexcept {
  rule_on().store(on, std::memory_order_relaxed);
}

bool level_patch_rule_on() noexcept {
  return rule_on().load(std::memory_order_relaxed);
}

LevelPatchCounts& level_patch_counts() noexcept {
  static LevelPatchCounts counts;
  return counts;
}

}  // namespace atelier::net_detail
