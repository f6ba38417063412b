// The result certificate's shortcut for the pieces of one net triangle
// (issue 24, cert17): when the rounded triangulation of a cut triangle u
// (or of two net triangles sharing an edge) is certainly still an
// embedding once projected along one axis, no two of its pieces meet
// beyond the corners they share, so certify_rounded_result
// (fold_certificate.cpp) tests none of those pairs.
//
// Why it holds (Floater, "One-to-one piecewise linear mappings over
// triangulations", Math. Comp. 72 (2003), the degree argument of its
// section 3): let T be a triangulated disc, consistently oriented, and f a
// piecewise-linear map of it into the plane that maps every triangle to a
// triangle of positive orientation and the boundary of T one-to-one onto a
// simple closed polygon. For a point y off the images of the edges, the
// number of triangles whose image holds y equals the winding number of
// f(boundary) about y (each triangle counts +1, and the interior edges
// cancel), which is 0 or 1 for a simple polygon. So the images of two
// triangles have disjoint interiors, and (the star of an interior vertex
// then covers a neighbourhood of its image exactly once, as does the
// half-star of a boundary vertex on the inner side of the simple boundary)
// two closed images meet exactly in the image of their common face: f is
// one-to-one. Here T is the cut's exact triangulation of u (the pieces,
// kept or not, in canonical ids: a triangulation of the triangle u by
// construction, whose combinatorics the exact fold check trusts as well;
// checked below only as far as it is cheap: each directed edge once, one
// boundary cycle through u's corners in u's order, Euler characteristic 1),
// and f is the projection of the pieces at their rounded positions along
// the dominant axis of u's normal. Two pieces X, Y are graphs over their
// projections (each projects to a proper triangle), so a point of X and Y
// projects into f(X) and f(Y), i.e. into the image of their common face,
// and is that face's point on both: X and Y meet only in the corners (or
// edge) they share by id, which is what the certificate's pair tests show
// one pair at a time.
//
// What is certified, in floating point with Shewchuk's bounds (no exact
// arithmetic: the shortcut is a filter, and a triangle it cannot certify
// simply has its pairs tested as before):
//   - every piece has a certain orient2d sign along the axis, the sign of
//     u's own corners (the pieces inherit u's orientation);
//   - the boundary polygon is simple: the points of each chain (the
//     boundary between two consecutive corners of u) strictly increase
//     along the chain's direction (so a chain's segments meet only where
//     consecutive), two chains through a common corner lie strictly on the
//     two sides of a line through it (the bisector of the corner's angle),
//     and for two net triangles, the opposite chains of the quadrilateral
//     strictly on the two sides of a line (along either one's direction).
// The corners of u are input doubles (never rounded); the other boundary
// points are rounded new points or the other net's vertices on u's edges.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "boolean_detail.h"

namespace atelier::net_detail {
namespace {

/// n . (q - o) in the plane of coordinates (i, j) with its error bound:
/// q - o rounded once per coordinate, each product and the sum once, so
/// the computed value is within 3.01 eps of the sum of the terms'
/// magnitudes (eps = 2^-53); 8e-16 leaves room, 1e-300 covers underflow.
/// False when a value is not finite.
bool dot_range(double ni, double nj, const Vec3d& o, const Vec3d& q, int i, int j, double& lo, double& hi) noexcept {
  const double wi = q[i] - o[i], wj = q[j] - o[j];
  const double d = ni * wi + nj * wj;
  const double e = 8e-16 * (std::abs(ni * wi) + std::abs(nj * wj)) + 1e-300;
  lo = d - e;
  hi = d + e;
  return lo - lo == 0 && hi - hi == 0;
}

/// certified_orient2 of (p, q, r) under each cyclic rotation until one is
/// certain (the same orientation): its differences are taken from the third
/// point, and a far third point (Cray's slab corners at 3.4e38 against
/// points of size 1e4) rounds both differences to the same vector.
int orient2_rotated(const Vec3d& p, const Vec3d& q, const Vec3d& r, int axis) noexcept {
  int d = certified_orient2(p, q, r, axis);
  if (d == 0) d = certified_orient2(q, r, p, axis);
  if (d == 0) d = certified_orient2(r, p, q, axis);
  return d;
}

/// Per-thread scratch of rounded_pieces_embedded.
struct EmbedScratch {
  std::vector<std::uint64_t> directed;  // (from << 32) | to, every piece edge
  std::vector<std::uint64_t> table;     // cert19: open addressing, the directed edges and (v << 32) | v
  std::vector<std::uint64_t> boundary;  // directed edges without their reverse
  std::vector<std::uint32_t> verts;     // piece corners, for the Euler count
  std::vector<std::uint32_t> cycle;     // the boundary cycle from the first corner
  std::vector<Vec3d> pos;               // its rounded positions
};

}  // namespace

bool rounded_pieces_embedded(const Cut& cut, const TriMesh& a, const TriMesh& b, int side,
                             std::span<const std::uint32_t> tris) {
  thread_local EmbedScratch sc;
  const CutSide& s = cut.sides[side];
  const TriMesh& m = *s.m;
  if (tris.empty() || tris.size() > 2) return false;
  // The patch's corners in boundary order (canonical ids) and positions:
  // u's three, or for u and a neighbour w sharing edge (x, y) of u (u runs
  // x -> y -> z, w runs y -> x -> v): x, v, y, z.
  const auto& tu = m.tri[tris[0]];
  std::uint32_t corner[4];
  Vec3d cp[4];
  int nc = 3;
  int rot = 0;  // u's corner the cycle starts at
  if (tris.size() == 2) {
    const auto& tw = m.tri[tris[1]];
    int found = -1, apex = -1;
    for (int k = 0; k < 3 && found < 0; ++k)
      for (int l = 0; l < 3; ++l)
        if (tu[static_cast<std::size_t>(k)] == tw[static_cast<std::size_t>((l + 1) % 3)] &&
            tu[static_cast<std::size_t>((k + 1) % 3)] == tw[static_cast<std::size_t>(l)]) {
          found = k;
          apex = (l + 2) % 3;
          break;
        }
    if (found < 0) return false;
    rot = found;
    nc = 4;
    const std::uint32_t x = tu[static_cast<std::size_t>(found)], y = tu[static_cast<std::size_t>((found + 1) % 3)],
                        z = tu[static_cast<std::size_t>((found + 2) % 3)], v = tw[static_cast<std::size_t>(apex)];
    const std::uint32_t order[4] = {x, v, y, z};
    for (int k = 0; k < 4; ++k) {
      corner[k] = cut.canon[order[k] + s.offset];
      cp[k] = m.p[order[k]];
    }
  } else {
    for (int k = 0; k < 3; ++k) {
      corner[k] = cut.canon[tu[static_cast<std::size_t>((k + rot) % 3)] + s.offset];
      cp[k] = m.p[tu[static_cast<std::size_t>((k + rot) % 3)]];
    }
  }
  // The axis: the dominant coordinate of u's normal; the sign: u's own
  // orientation seen along it, certain (every net triangle in the patch).
  const Vec3d& p0 = m.p[tu[0]];
  const Vec3d nu = (m.p[tu[1]] - p0).cross(m.p[tu[2]] - p0);
  const int axis = std::abs(nu.x()) >= std::abs(nu.y()) ? (std::abs(nu.x()) >= std::abs(nu.z()) ? 0 : 2)
                                                        : (std::abs(nu.y()) >= std::abs(nu.z()) ? 1 : 2);
  const int sign = orient2_rotated(m.p[tu[0]], m.p[tu[1]], m.p[tu[2]], axis);
  if (sign == 0) return false;
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;

  // Every piece: a certain orientation equal to u's; its directed edges.
  sc.directed.clear();
  sc.verts.clear();
  std::size_t faces = 0;
  for (const std::uint32_t t : tris) {
    for (std::uint32_t p = s.piece_begin[t]; p < s.piece_begin[t + 1]; ++p) {
      const auto& pc = s.piece[p];
      Vec3d q[3];
      for (std::size_t k = 0; k < 3; ++k) q[k] = cut.position(a, b, pc[k]);
      if (orient2_rotated(q[0], q[1], q[2], axis) != sign) return false;
      for (std::size_t k = 0; k < 3; ++k) {
        sc.directed.push_back((std::uint64_t{pc[k]} << 32) | pc[(k + 1) % 3]);
        sc.verts.push_back(pc[k]);
      }
      ++faces;
    }
  }
  // cert19: the directed edges and the vertices in one open-addressing set
  // (linear probing, a power of two at least four times the keys; a piece's
  // ids are distinct, as its orientation is certain, so a vertex's key
  // (v << 32) | v is never an edge's), not sorted: a repeated directed edge,
  // the boundary (the edges whose reverse is absent) and the vertex count in
  // one pass each; only the boundary, a few dozen edges, is sorted.
  std::size_t size = 64;
  int shift = 58;
  while (size < 8 * sc.directed.size()) {
    size *= 2;
    --shift;
  }
  constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  sc.table.assign(size, kEmpty);
  const std::size_t mask = size - 1;
  auto home = [&](std::uint64_t key) { return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift); };
  // 1: newly inserted, 0: present already.
  auto insert = [&](std::uint64_t key) {
    for (std::size_t i = home(key);; i = (i + 1) & mask) {
      if (sc.table[i] == key) return 0;
      if (sc.table[i] == kEmpty) {
        sc.table[i] = key;
        return 1;
      }
    }
  };
  auto has = [&](std::uint64_t key) {
    for (std::size_t i = home(key);; i = (i + 1) & mask) {
      if (sc.table[i] == key) return true;
      if (sc.table[i] == kEmpty) return false;
    }
  };
  std::size_t n_verts = 0;
  for (std::size_t k = 0; k < sc.directed.size(); ++k) {
    if (insert(sc.directed[k]) == 0) return false;  // a directed edge twice
    n_verts += static_cast<std::size_t>(insert((std::uint64_t{sc.verts[k]} << 32) | sc.verts[k]));
  }
  sc.boundary.clear();
  for (const std::uint64_t e : sc.directed) {
    const std::uint64_t rev = (e << 32) | (e >> 32);
    if (!has(rev)) sc.boundary.push_back(e);
  }
  std::sort(sc.boundary.begin(), sc.boundary.end());
  // Sorted by their first corner: a boundary vertex starts one boundary
  // edge, else the boundary is not one simple cycle.
  for (std::size_t k = 1; k < sc.boundary.size(); ++k)
    if (sc.boundary[k] >> 32 == sc.boundary[k - 1] >> 32) return false;
  // V - E + F = 1: E counts interior edges once and boundary edges once.
  const std::size_t n_edges = (sc.directed.size() + sc.boundary.size()) / 2;
  if (n_verts + faces != n_edges + 1) return false;

  // The boundary cycle from corner 0; the corners in order along it.
  sc.cycle.clear();
  std::size_t at[4] = {0, 0, 0, 0};
  int next_corner = 1;
  std::uint32_t v = corner[0];
  for (std::size_t step = 0; step < sc.boundary.size(); ++step) {
    sc.cycle.push_back(v);
    const auto it = std::lower_bound(sc.boundary.begin(), sc.boundary.end(), std::uint64_t{v} << 32);
    if (it == sc.boundary.end() || (*it >> 32) != v) return false;
    v = static_cast<std::uint32_t>(*it & 0xffffffffu);
    if (next_corner < nc && v == corner[next_corner])
      at[next_corner++] = step + 1;
    else if (v != corner[0])
      for (int k = 0; k < nc; ++k)
        if (v == corner[k]) return false;  // a corner out of order
    if (v == corner[0]) {
      if (step + 1 != sc.boundary.size()) return false;  // a second cycle
      break;
    }
  }
  if (v != corner[0] || next_corner != nc) return false;
  const std::size_t nb = sc.cycle.size();
  sc.pos.resize(nb + 1);
  for (std::size_t k = 0; k < nb; ++k) sc.pos[k] = cut.position(a, b, sc.cycle[k]);
  sc.pos[nb] = sc.pos[0];
  std::size_t start[5];
  for (int k = 0; k < nc; ++k) start[k] = at[k];
  start[nc] = nb;  // chain k runs over pos[start[k] .. start[k + 1]]
  for (int k = 0; k < nc; ++k)
    if (!(sc.pos[start[k]] == cp[k])) return false;  // the corners are the net's own points

  // Each chain strictly monotone along its corners' direction: every
  // consecutive difference certainly positive along d.
  for (int k = 0; k < nc; ++k) {
    const Vec3d& c0 = cp[k];
    const Vec3d& c1 = cp[(k + 1) % nc];
    const double di = c1[i] - c0[i], dj = c1[j] - c0[j];
    for (std::size_t q = start[k]; q < start[k + 1]; ++q) {
      double lo = 0, hi = 0;
      if (!dot_range(di, dj, sc.pos[q], sc.pos[q + 1], i, j, lo, hi) || !(lo > 0)) return false;
    }
  }
  // Value range of chain k's points (skipping its corner `skip_start` /
  // `skip_end`) along n from o.
  auto chain_range = [&](int k, bool skip_start, bool skip_end, double ni, double nj, const Vec3d& o, double& lo,
                         double& hi) {
    lo = HUGE_VAL;
    hi = -HUGE_VAL;
    for (std::size_t q = start[k] + (skip_start ? 1 : 0); q + (skip_end ? 1 : 0) <= start[k + 1]; ++q) {
      double l = 0, h = 0;
      if (!dot_range(ni, nj, o, sc.pos[q], i, j, l, h)) return false;
      lo = std::min(lo, l);
      hi = std::max(hi, h);
    }
    return true;
  };
  // Two chains through corner k (chain k - 1 ends there, chain k starts):
  // strictly on the two sides of the line through it along the bisector of
  // the directions to the neighbouring corners (any double vector m: the
  // bound is on the computed products with it).
  for (int k = 0; k < nc; ++k) {
    const Vec3d& c = cp[k];
    const Vec3d& prev = cp[(k + nc - 1) % nc];
    const Vec3d& next = cp[(k + 1) % nc];
    const double ai = prev[i] - c[i], aj = prev[j] - c[j], bi = next[i] - c[i], bj = next[j] - c[j];
    const double la = std::hypot(ai, aj), lb = std::hypot(bi, bj);
    if (!(la > 0) || !(lb > 0) || !std::isfinite(la) || !std::isfinite(lb)) return false;
    const double mi = ai / la + bi / lb, mj = aj / la + bj / lb;
    const double ni = -mj, nj = mi;
    double l0 = 0, h0 = 0, l1 = 0, h1 = 0;
    if (!chain_range((k + nc - 1) % nc, false, true, ni, nj, c, l0, h0) ||
        !chain_range(k, true, false, ni, nj, c, l1, h1))
      return false;
    if (!((h0 < 0 && l1 > 0) || (l0 > 0 && h1 < 0))) return false;
  }
  // A quadrilateral's opposite chains: strictly apart along the normal of
  // either one's corners' line.
  if (nc == 4)
    for (int k = 0; k < 2; ++k) {
      bool apart = false;
      for (const int e : {k, k + 2}) {
        const Vec3d& c0 = cp[e];
        const Vec3d& c1 = cp[(e + 1) % 4];
        const double ni = -(c1[j] - c0[j]), nj = c1[i] - c0[i];
        double l0 = 0, h0 = 0, l1 = 0, h1 = 0;
        if (!chain_range(k, false, false, ni, nj, c0, l0, h0) || !chain_range(k + 2, false, false, ni, nj, c0, l1, h1))
          continue;
        if (h0 < l1 || h1 < l0) {
          apart = true;
          break;
        }
      }
      if (!apart) return false;
    }
  return true;
}

}  // namespace atelier::net_detail
