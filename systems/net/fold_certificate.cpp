// The rounded result's certificate (issue 24, fold16): before the repair
// and fold check of fold_check.cpp, floating-point filters show for most
// results that no triangle with a rounded point is flat or near another,
// so both are skipped. Split from fold_check.cpp, whose fold semantics
// (which pairs count, coincident corners) it shares: read them together.
// cert17: no pair tests among the pieces of a cut triangle certified an
// embedded triangulation once rounded (fold_embedding.cpp), and a rule for
// pieces lying in a plane x_k = l (cert_level_apart). cert18: a piece
// decided against a whole embedded level patch at once (fold_level_patch.cpp).
// cert19: one walk of the hierarchies for a group of neighbouring cut
// triangles.
// Why this file is long: the pair filters and the one loop that applies them (with
// cert17's and cert18's shortcuts, whose rules live in their own files) are
// read together.
#include <atelier/engine/parallel.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>

#include "boolean_detail.h"
#include "fold_level_patch.h"

namespace atelier::net_detail {

// ---- The certificate (issue 24, fold16) ---------------------------------
//
// The fold check above builds a fold net, its hierarchy and the nets'
// neighbour pieces for every Boolean: 1.2-2.3x the Boolean's own time. Most
// results need none of it: every triangle with a new point is certainly not
// flat and certainly apart from every triangle of the result near it, which
// floating-point filters with Shewchuk's bounds show for almost every pair
// of a generic cut. certify_rounded_result tests exactly that, in the cut's
// own ids, before the output is touched; when it holds, the repair finds no
// flat triangle and the check no crossing (the same pairs, or more: it does
// not merge coincident copies), so the result is returned as the check
// would return it. When any filter fails, the whole repair and check run
// as before. Complete: a triangle of the result is a kept piece X of a net
// triangle u (a whole polygon is its triangles' pieces), its exact corners
// lie in u, and each rounded corner moved by at most delta per coordinate,
// so box(X) lies in box(u) grown by delta: every X whose box meets a
// suspect S's box is found by asking the nets' hierarchies for the
// triangles whose boxes meet box(S) grown by delta.
namespace {

/// A triangle of the rounded result in the cut's canonical ids, with its
/// corners, box and rounded normal (the self-check's SelfTri with points).
struct CertTri {
  std::array<std::uint32_t, 3> v{};
  std::array<Vec3d, 3> p;
  std::array<double, 6> box{};
  double n[3] = {}, nabs[3] = {};
};

/// The corners and box (cert_tri's first half: the box tests need no more).
void cert_corners(const Cut& cut, const TriMesh& a, const TriMesh& b, const std::array<std::uint32_t, 3>& piece,
                  CertTri& r) noexcept {
  for (std::size_t k = 0; k < 3; ++k) {
    r.v[k] = cut.canon[piece[k]];
    r.p[k] = cut.position(a, b, r.v[k]);
  }
  for (int k = 0; k < 3; ++k) {
    r.box[static_cast<std::size_t>(k)] = std::min({r.p[0][k], r.p[1][k], r.p[2][k]});
    r.box[static_cast<std::size_t>(k + 3)] = std::max({r.p[0][k], r.p[1][k], r.p[2][k]});
  }
}

/// The rounded normal and the permanents of the side test.
void cert_normal(CertTri& r) noexcept {
  const Vec3d u = r.p[1] - r.p[0], w = r.p[2] - r.p[0];
  r.n[0] = u.y() * w.z() - u.z() * w.y();
  r.n[1] = u.z() * w.x() - u.x() * w.z();
  r.n[2] = u.x() * w.y() - u.y() * w.x();
  r.nabs[0] = std::abs(u.y() * w.z()) + std::abs(u.z() * w.y());
  r.nabs[1] = std::abs(u.z() * w.x()) + std::abs(u.x() * w.z());
  r.nabs[2] = std::abs(u.x() * w.y()) + std::abs(u.y() * w.x());
}

void cert_tri(const Cut& cut, const TriMesh& a, const TriMesh& b, const std::array<std::uint32_t, 3>& piece,
              CertTri& r) noexcept {
  cert_corners(cut, a, b, piece, r);
  cert_normal(r);
}

bool cert_boxes_meet(const std::array<double, 6>& x, const std::array<double, 6>& y) noexcept {
  return (x[0] <= y[3]) & (y[0] <= x[3]) & (x[1] <= y[4]) & (y[1] <= x[4]) & (x[2] <= y[5]) & (y[2] <= x[5]);
}

/// The side of q against x's plane (filtered_plane_side), 0 when the
/// filter cannot tell.
int cert_side(const CertTri& x, const Vec3d& q) noexcept {
  return filtered_plane_side(x.n, x.nabs, x.p[0], q);
}

int cert_axis(const CertTri& x) noexcept {
  const double a = std::abs(x.n[0]), b = std::abs(x.n[1]), c = std::abs(x.n[2]);
  return a >= b ? (a >= c ? 0 : 2) : (b >= c ? 1 : 2);
}

/// Certainly not flat: a certain orientation seen along some axis (then its
/// corners are not collinear, which repair_flat_triangles looks for). Where
/// no filter can tell (a piece of a triangle far larger than the cut, as
/// Cray's slab at FLT_MAX), the caller asks the exact collinear().
bool cert_not_flat(const CertTri& x) noexcept {
  for (int k = 0; k < 3; ++k)
    if (certified_orient2(x.p[0], x.p[1], x.p[2], k) != 0) return true;
  return false;
}

/// The corners x and y share by id: bit i of in_y when x's corner i is one
/// of y's, bit j of in_x when y's corner j is one of x's.
void cert_shared_corners(const CertTri& x, const CertTri& y, unsigned& in_y, unsigned& in_x) noexcept {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (x.v[static_cast<std::size_t>(i)] == y.v[static_cast<std::size_t>(j)]) {
        in_y |= 1u << i;
        in_x |= 1u << j;
      }
}

/// True when x and y certainly meet at most in the corners (ids) they
/// share: the self-check's rules (self_check_pairs.cpp, self_apart), on
/// the triangles' own points. False: not known.
bool cert_apart(const CertTri& x, const CertTri& y) noexcept {
  unsigned in_y = 0, in_x = 0;
  cert_shared_corners(x, y, in_y, in_x);
  auto one_side = [](const CertTri& s, const CertTri& o, unsigned shared_of_o) {
    int side = 0;
    for (int k = 0; k < 3; ++k) {
      if (shared_of_o >> k & 1u) continue;
      const int d = cert_side(s, o.p[static_cast<std::size_t>(k)]);
      if (d == 0 || (side != 0 && d != side)) return false;
      side = d;
    }
    return side != 0;
  };
  if (one_side(x, y, in_x) || one_side(y, x, in_y)) return true;
  const int shared = std::popcount(in_y);
  const int axis = cert_axis(x);
  auto P = [](const CertTri& t, int k) -> const Vec3d& { return t.p[static_cast<std::size_t>((k % 3 + 3) % 3)]; };
  if (shared == 3) return false;
  if (shared == 2) {
    // The third corners certainly on opposite sides of the shared edge.
    const int ox = std::countr_zero(~in_y & 7u), oy = std::countr_zero(~in_x & 7u);
    const Vec3d &u = P(x, ox + 1), &w = P(x, ox + 2);
    const int sx = certified_orient2(u, w, P(x, ox), axis), sy = certified_orient2(u, w, P(y, oy), axis);
    return sx != 0 && sy != 0 && sx != sy;
  }
  if (shared == 1) {
    // Both keep a certain orientation along the axis, and a line through
    // the shared corner along one's edge has the other's far corners
    // strictly on the far side.
    const int ix = std::countr_zero(in_y), iy = std::countr_zero(in_x);
    const Vec3d& v = P(x, ix);
    const Vec3d &x1 = P(x, ix + 1), &x2 = P(x, ix + 2), &y1 = P(y, iy + 1), &y2 = P(y, iy + 2);
    const int sx = certified_orient2(v, x1, x2, axis), sy = certified_orient2(v, y1, y2, axis);
    if (sx == 0 || sy == 0) return false;
    auto separates = [&](const Vec3d& e, int s, const Vec3d& q1, const Vec3d& q2) {
      return certified_orient2(v, e, q1, axis) == -s && certified_orient2(v, e, q2, axis) == -s;
    };
    return separates(x1, sx, y1, y2) || separates(x2, -sx, y1, y2) || separates(y1, sy, x1, x2) ||
           separates(y2, -sy, x1, x2);
  }
  // No shared corner: an edge line of one triangle, along x's axis, with
  // its third corner strictly on one side and the other's corners strictly
  // on the other (disjoint projections).
  auto separated_by_edges = [&](const CertTri& s, const CertTri& o) {
    for (int k = 0; k < 3; ++k) {
      const Vec3d &e0 = P(s, k), &e1 = P(s, k + 1);
      const int d = certified_orient2(e0, e1, P(s, k + 2), axis);
      if (d != 0 && certified_orient2(e0, e1, o.p[0], axis) == -d && certified_orient2(e0, e1, o.p[1], axis) == -d &&
          certified_orient2(e0, e1, o.p[2], axis) == -d)
        return true;
    }
    return false;
  };
  return separated_by_edges(x, y) || separated_by_edges(y, x);
}

/// cert17: y lies in a plane x_k = l (its three k coordinates equal: CAD
/// faces, Cray's slab top, whose new points round onto the plane exactly)
/// and x does not; x's corners off the plane all strictly on one side
/// (exact comparisons of doubles). Then x meets the plane only in its
/// corners on it, q (none, one, or the edge of two), so x meets y at most
/// in y's part of hull(q): apart when q is shared with y by id (a corner,
/// or an edge of y), else when the unshared corner lies strictly outside y,
/// or the edge from a shared corner leaves y's angle there strictly, or the
/// edge and y are strictly apart by a line (certified orient2d along k).
/// The CAD pairs' common case: a small cut triangle's pieces against a
/// plane's fan of pieces whose far corners defeat the general filters.
bool cert_level_apart(const CertTri& y, const CertTri& x) noexcept {
  int k = 0;
  while (k < 3 && !(y.p[0][k] == y.p[1][k] && y.p[1][k] == y.p[2][k])) ++k;
  if (k == 3) return false;
  const double l = y.p[0][k];
  int side = 0, n_on = 0;
  std::size_t on[2] = {0, 0};
  for (std::size_t c = 0; c < 3; ++c) {
    const double v = x.p[c][k];
    if (v == l) {
      if (n_on == 2) return false;  // x in the plane too
      on[n_on++] = c;
      continue;
    }
    const int sd = v > l ? 1 : -1;
    if (side != 0 && sd != side) return false;
    side = sd;
  }
  if (!(l - l == 0)) return false;
  if (n_on == 0) return true;
  auto shared = [&](std::size_t c) { return x.v[c] == y.v[0] || x.v[c] == y.v[1] || x.v[c] == y.v[2]; };
  auto P = [&](int i) -> const Vec3d& { return y.p[static_cast<std::size_t>((i % 3 + 3) % 3)]; };
  // Points strictly beyond one edge line of y (its third corner strictly
  // on the other side).
  auto outside_y = [&](const Vec3d* q, int n) {
    for (int e = 0; e < 3; ++e) {
      const int d = certified_orient2(P(e), P(e + 1), P(e + 2), k);
      if (d == 0) continue;
      bool all = true;
      for (int i = 0; i < n && all; ++i) all = certified_orient2(P(e), P(e + 1), q[i], k) == -d;
      if (all) return true;
    }
    return false;
  };
  if (n_on == 1) return shared(on[0]) || outside_y(&x.p[on[0]], 1);
  const bool s0 = shared(on[0]), s1 = shared(on[1]);
  if (s0 && s1) return true;
  if (s0 || s1) {
    const std::size_t cv = s0 ? on[0] : on[1];
    const Vec3d& v = x.p[cv];
    const Vec3d& r = x.p[s0 ? on[1] : on[0]];
    int iv = 0;
    while (y.v[static_cast<std::size_t>(iv)] != x.v[cv]) ++iv;  // shared: one of y's ids
    const Vec3d &a = P(iv + 1), &b = P(iv + 2);
    const int sy = certified_orient2(v, a, b, k);
    return sy != 0 && (certified_orient2(v, a, r, k) == -sy || certified_orient2(v, r, b, k) == -sy);
  }
  const Vec3d q[2] = {x.p[on[0]], x.p[on[1]]};
  if (outside_y(q, 2)) return true;
  const int d = certified_orient2(q[0], q[1], y.p[0], k);
  return d != 0 && certified_orient2(q[0], q[1], y.p[1], k) == d && certified_orient2(q[0], q[1], y.p[2], k) == d;
}

/// A certified strict separation along axis n (any double vector), from
/// origin o: sharing a corner (o, skipped by `skip_x` / `skip_y`, bit k:
/// corner k), every other corner of x at n . (p - o) < 0 and of y at > 0,
/// or the other way round; sharing none, the values of x's corners all
/// below those of y's, or all above. Each p - o is rounded once (relative
/// error eps) and the dot product adds gamma_3, so
/// |error| <= 8e-16 * sum |n_i| |w_i| bounds both with room (eps = 2^-53).
bool cert_separates(const Vec3d& n, const Vec3d& o, const CertTri& x, unsigned skip_x, const CertTri& y,
                    unsigned skip_y) noexcept {
  // Per triangle: the lowest value minus its bound, the highest plus its.
  auto range = [&](const CertTri& t, unsigned skip, double& lo, double& hi) {
    lo = HUGE_VAL;
    hi = -HUGE_VAL;
    for (int k = 0; k < 3; ++k) {
      if (skip >> k & 1u) continue;
      const Vec3d& p = t.p[static_cast<std::size_t>(k)];
      const double wx = p.x() - o.x(), wy = p.y() - o.y(), wz = p.z() - o.z();
      const double d = n.x() * wx + n.y() * wy + n.z() * wz;
      const double e = 8e-16 * (std::abs(n.x() * wx) + std::abs(n.y() * wy) + std::abs(n.z() * wz)) + 1e-300;
      lo = std::min(lo, d - e);
      hi = std::max(hi, d + e);
    }
    return lo - lo == 0 && hi - hi == 0;  // finite
  };
  double xl = 0, xh = 0, yl = 0, yh = 0;
  if (!range(x, skip_x, xl, xh) || !range(y, skip_y, yl, yh)) return false;
  if (skip_x != 0)  // through the shared corner: strictly on opposite sides of 0
    return (xh < 0 && yl > 0) || (xl > 0 && yh < 0);
  return xh < yl || yh < xl;
}

/// Second-stage filters for a pair cert_apart leaves open (shared corners
/// by id, at most one): a plane that certainly separates them, through the
/// shared corner if any (then they meet only there). Candidate normals:
/// both triangles' normals, the cross products of their edges (the
/// separating axes of two triangles in space), and each edge crossed with
/// its triangle's normal (a line in a common plane: coplanar pieces of one
/// cut triangle). Sharing a corner v, also the disjointness of their angles
/// at v seen along each triangle's axis (two convex angles meeting only at
/// v, each triangle projected one-to-one: they meet only at v).
bool cert_apart_more(const CertTri& x, const CertTri& y) noexcept {
  unsigned in_y = 0, in_x = 0;
  cert_shared_corners(x, y, in_y, in_x);
  const int shared = std::popcount(in_y);
  const Vec3d nx(x.n[0], x.n[1], x.n[2]), ny(y.n[0], y.n[1], y.n[2]);
  if (shared == 2) {
    // A plane through the shared edge, across either triangle's own plane,
    // with the third corners strictly on opposite sides.
    const int ox = std::countr_zero(~in_y & 7u);
    const Vec3d& u = x.p[static_cast<std::size_t>((ox + 1) % 3)];
    const Vec3d e = x.p[static_cast<std::size_t>((ox + 2) % 3)] - u;
    return cert_separates(nx.cross(e), u, x, in_y, y, in_x) || cert_separates(ny.cross(e), u, x, in_y, y, in_x);
  }
  if (shared > 2) return false;
  const Vec3d o = shared == 1 ? x.p[static_cast<std::size_t>(std::countr_zero(in_y))] : x.p[0];
  if (shared == 1) {
    const int ix = std::countr_zero(in_y), iy = std::countr_zero(in_x);
    const Vec3d& v = o;
    const Vec3d &x1 = x.p[static_cast<std::size_t>((ix + 1) % 3)], &x2 = x.p[static_cast<std::size_t>((ix + 2) % 3)];
    const Vec3d &y1 = y.p[static_cast<std::size_t>((iy + 1) % 3)], &y2 = y.p[static_cast<std::size_t>((iy + 2) % 3)];
    for (const int axis : {cert_axis(x), cert_axis(y)}) {
      const int sx = certified_orient2(v, x1, x2, axis), sy = certified_orient2(v, y1, y2, axis);
      if (sx == 0 || sy == 0) continue;
      // Ray r strictly outside the angle (a, b) of orientation s at v.
      auto outside = [&](const Vec3d& a, const Vec3d& b, int s, const Vec3d& r) {
        return certified_orient2(v, a, r, axis) == -s || certified_orient2(v, r, b, axis) == -s;
      };
      if (outside(x1, x2, sx, y1) && outside(x1, x2, sx, y2) && outside(y1, y2, sy, x1) && outside(y1, y2, sy, x2))
        return true;
    }
  }
  if (cert_separates(nx, o, x, in_y, y, in_x) || cert_separates(ny, o, x, in_y, y, in_x)) return true;
  Vec3d ex[3], ey[3];
  for (std::size_t k = 0; k < 3; ++k) {
    ex[k] = x.p[(k + 1) % 3] - x.p[k];
    ey[k] = y.p[(k + 1) % 3] - y.p[k];
  }
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j)
      if (cert_separates(ex[i].cross(ey[j]), o, x, in_y, y, in_x)) return true;
  for (std::size_t k = 0; k < 3; ++k)
    if (cert_separates(nx.cross(ex[k]), o, x, in_y, y, in_x) || cert_separates(ny.cross(ey[k]), o, x, in_y, y, in_x))
      return true;
  return false;
}

/// The exact answer for a pair the filters leave open: triangles_cross on
/// the two triangles alone (corners shared by id).
bool cert_cross_exact(const CertTri& x, const CertTri& y) {
  TriMesh m;
  std::array<std::uint32_t, 3> tx{}, ty{};
  std::vector<std::uint32_t> ids;
  auto local = [&](std::uint32_t v, const Vec3d& p) {
    for (std::uint32_t k = 0; k < ids.size(); ++k)
      if (ids[k] == v) return k;
    ids.push_back(v);
    m.p.push_back(p);
    return static_cast<std::uint32_t>(ids.size() - 1);
  };
  for (std::size_t k = 0; k < 3; ++k) tx[k] = local(x.v[k], x.p[k]);
  for (std::size_t k = 0; k < 3; ++k) ty[k] = local(y.v[k], y.p[k]);
  m.tri = {tx, ty};
  return triangles_cross(m, 0, 1);
}

/// Cut triangles with at least this many pieces have them made once per
/// certificate and their pairs skipped when rounded_pieces_embedded holds:
/// below it the pair tests cost less than the embedding test (~0.4 us a
/// piece; on every triangle and neighbour it cost Cray 0.5 ms a Boolean,
/// and at 12 Offset3 x Offset4 2-5%; Cray's slab top has 93).
constexpr std::uint32_t kEmbedPieces = 32;

/// cert19: at most this many neighbouring cut triangles share one walk of
/// the hierarchies (their union box stays small: a few triangles along the
/// intersection curve).
constexpr std::size_t kWalkGroup = 8;

std::atomic<bool>& grouped_walk_flag() noexcept {
  static std::atomic<bool> on{true};
  return on;
}

std::atomic<bool>& embedding_shortcut_on() noexcept {
  static std::atomic<bool> on{true};
  return on;
}

}  // namespace

bool level_plane_pieces_apart(const std::array<Vec3d, 3>& y, const std::array<std::uint32_t, 3>& y_ids,
                              const std::array<Vec3d, 3>& x, const std::array<std::uint32_t, 3>& x_ids) noexcept {
  CertTri ty, tx;
  ty.p = y;
  ty.v = y_ids;
  tx.p = x;
  tx.v = x_ids;
  return cert_level_apart(ty, tx);
}

void set_grouped_walk(bool on) noexcept {
  grouped_walk_flag().store(on, std::memory_order_relaxed);
}

bool grouped_walk_on() noexcept {
  return grouped_walk_flag().load(std::memory_order_relaxed);
}

CertWalkCounts& cert_walk_counts() noexcept {
  static CertWalkCounts counts;
  return counts;
}

void set_embedding_shortcut(bool on) noexcept {
  embedding_shortcut_on().store(on, std::memory_order_relaxed);
}

bool certify_rounded_result(const Cut& cut, const TriMesh& a, const Bvh& bvh_a, const TriMesh& b, const Bvh& bvh_b,
                            const ExecContext& ctx, CertifyStats* stats) {
  const std::uint32_t first_new = cut.nA + cut.nB;
  // delta: how far a rounded point may lie from its exact value, per
  // coordinate. point_coordinates takes a box's centre (within 2 ulps) or
  // rounds to nearest (half an ulp); an ulp of x is at most 2^-52 |x|, so
  // 2^-48 of the largest coordinate is 8 times that bound.
  double largest = 0;
  for (const Vec3d& p : cut.new_points) {
    if (!p.allFinite()) return false;
    largest = std::max(largest, p.cwiseAbs().maxCoeff());
  }
  const double delta = std::ldexp(largest, -48) + 1e-300;
  auto is_suspect = [&](const std::array<std::uint32_t, 3>& piece) {
    return cut.canon[piece[0]] >= first_new || cut.canon[piece[1]] >= first_new || cut.canon[piece[2]] >= first_new;
  };
  // The cut triangles with a kept piece that has a new point.
  std::vector<std::array<std::uint32_t, 2>> items;  // side, triangle
  for (int side = 0; side < 2; ++side) {
    const CutSide& s = cut.sides[side];
    for (const std::uint32_t t : s.cut)
      for (std::uint32_t p = s.piece_begin[t]; p < s.piece_begin[t + 1]; ++p)
        if (s.keep[p] && is_suspect(s.piece[p])) {
          items.push_back({static_cast<std::uint32_t>(side), t});
          break;
        }
  }
  // cert17: the kept pieces of cut triangles cut into many (Cray's slab
  // top: ~90 each, found by nearly every query) made once, not per query
  // (their corners, box and normal: the same values cert_tri gives).
  std::vector<std::uint32_t> pre_begin[2];  // per cut slot: index in pre, or kNil
  std::vector<CertTri> pre[2];
  for (int side = 0; side < 2; ++side) {
    const CutSide& s = cut.sides[side];
    pre_begin[side].assign(s.cut.size(), kNil);
    for (std::size_t c = 0; c < s.cut.size(); ++c) {
      const std::uint32_t t = s.cut[c];
      if (s.piece_begin[t + 1] - s.piece_begin[t] < kEmbedPieces) continue;
      pre_begin[side][c] = static_cast<std::uint32_t>(pre[side].size());
      for (std::uint32_t p = s.piece_begin[t]; p < s.piece_begin[t + 1]; ++p) {
        pre[side].emplace_back();
        if (s.keep[p]) cert_tri(cut, a, b, s.piece[p], pre[side].back());
      }
    }
  }
  // cert17: per cut slot, bit 0: its pieces certified an embedded
  // triangulation once rounded (rounded_pieces_embedded); bit k + 1: with
  // its neighbour across edge k. Only triangles cut into many pieces (below
  // kEmbedPieces the pair tests cost less), both of a neighbouring pair;
  // the pair first, as its union being embedded makes each part so. Made
  // here once (deterministic), not per item: the test is ~0.4 us a piece.
  std::vector<std::uint8_t> embed_ok[2];
  std::size_t n_neighbour_patches = 0;
  const bool shortcut = embedding_shortcut_on().load(std::memory_order_relaxed);
  for (int side = 0; side < 2; ++side) {
    const CutSide& s = cut.sides[side];
    const TriMesh& m = *s.m;
    embed_ok[side].assign(s.cut.size(), 0);
    if (!shortcut) continue;
    auto many = [&](std::uint32_t t) {
      return t != kNil && s.slot[t] != kNil && s.piece_begin[t + 1] - s.piece_begin[t] >= kEmbedPieces;
    };
    for (std::size_t c = 0; c < s.cut.size(); ++c) {
      const std::uint32_t t = s.cut[c];
      if (!many(t)) continue;
      for (std::uint8_t k = 0; k < 3; ++k) {
        const auto& et = m.edge_tri[m.tri_edge[t][k]];
        const std::uint32_t u = et[0] == t ? et[1] : et[0];
        if (!many(u)) continue;
        std::uint8_t& mine = embed_ok[side][c];
        if (u < t) {  // made from u's side: copy its verdict
          const std::uint8_t theirs = embed_ok[side][s.slot[u]];
          for (std::uint8_t l = 0; l < 3; ++l) {
            const auto& eu = m.edge_tri[m.tri_edge[u][l]];
            if ((eu[0] == u ? eu[1] : eu[0]) == t && (theirs >> (l + 1) & 1u))
              mine |= static_cast<std::uint8_t>(1u | 2u << k);
          }
          continue;
        }
        const std::uint32_t two[2] = {t, u};
        if (rounded_pieces_embedded(cut, a, b, side, two)) {
          mine |= static_cast<std::uint8_t>(1u | 2u << k);
          ++n_neighbour_patches;
        }
      }
      const std::uint32_t own[1] = {t};
      if (!(embed_ok[side][c] & 1u) && rounded_pieces_embedded(cut, a, b, side, own)) embed_ok[side][c] |= 1u;
    }
  }
  // cert18: the level patches (fold_level_patch.cpp, the proof at its
  // top): per cut slot certified embedded whose pieces lie in one plane
  // x_k = l, with the first level neighbour (same plane) certified embedded
  // with it, if any. Made once here, in slot order (deterministic).
  std::vector<std::uint32_t> patch_of[2];       // per cut slot: index in patches, or kNil
  std::vector<std::uint32_t> patch_partner[2];  // per cut slot: the neighbour in its patch, or kNil
  std::vector<LevelPatch> patches[2];
  const bool level_rule = shortcut && level_patch_rule_on();
  for (int side = 0; side < 2; ++side) {
    const CutSide& s = cut.sides[side];
    const TriMesh& m = *s.m;
    patch_of[side].assign(s.cut.size(), kNil);
    patch_partner[side].assign(s.cut.size(), kNil);
    if (!level_rule) continue;
    for (std::size_t c = 0; c < s.cut.size(); ++c) {
      if (!(embed_ok[side][c] & 1u)) continue;
      const std::uint32_t t = s.cut[c];
      LevelPatch pt;
      bool made = false;
      for (std::size_t e = 0; e < 3 && !made; ++e) {  // with the first level neighbour certified with t
        if (!(embed_ok[side][c] >> (e + 1) & 1u)) continue;
        const auto& et = m.edge_tri[m.tri_edge[t][e]];
        const std::uint32_t w = et[0] == t ? et[1] : et[0];
        const std::uint32_t two[2] = {t, w};
        // w's patch made already with t: the same pieces, shared.
        const std::uint32_t cw = s.slot[w];
        if (cw < c && patch_of[side][cw] != kNil && patch_partner[side][cw] == t) {
          patch_of[side][c] = patch_of[side][cw];
          patch_partner[side][c] = w;
          made = true;
          break;
        }
        pt = LevelPatch{};
        made = make_level_patch(cut, a, b, side, two, pt);
        if (made) patch_partner[side][c] = w;
      }
      if (made && patch_of[side][c] != kNil) continue;
      if (!made) {
        const std::uint32_t own[1] = {t};
        pt = LevelPatch{};
        if (!make_level_patch(cut, a, b, side, own, pt)) continue;
      }
      patch_of[side][c] = static_cast<std::uint32_t>(patches[side].size());
      patches[side].push_back(std::move(pt));
    }
  }
  std::atomic<bool> failed{false};
  std::atomic<std::size_t> pairs{0}, exact{0}, embedded{0}, level_skips{0};
  const Bvh* bvhs[2] = {&bvh_a, &bvh_b};
  // cert19: the hierarchy walks shared. Neighbouring cut triangles of one
  // side, each cut into few pieces (Cray_left's small cut triangles along
  // the curve: ~90 queries of a few pieces each), are taken in groups of up
  // to kWalkGroup: the hierarchies are walked once with the union of their
  // query boxes, and each member's query keeps the found triangles whose
  // boxes meet its own (the walk with a smaller box finds a subset, in the
  // same order, so the pairs tested are exactly the same). Made here once,
  // in item order (deterministic).
  std::vector<std::uint32_t> group_begin{0}, group_items;
  group_items.reserve(items.size());
  {
    const bool grouped = grouped_walk_on();
    std::vector<std::uint32_t> item_of[2];  // per cut slot: index in items, or kNil
    for (int side = 0; side < 2; ++side) item_of[side].assign(cut.sides[side].cut.size(), kNil);
    for (std::size_t i = 0; i < items.size(); ++i)
      item_of[items[i][0]][cut.sides[items[i][0]].slot[items[i][1]]] = static_cast<std::uint32_t>(i);
    auto few = [&](std::uint32_t side, std::uint32_t t) {
      const CutSide& s = cut.sides[side];
      return s.piece_begin[t + 1] - s.piece_begin[t] < kEmbedPieces;
    };
    std::vector<std::uint8_t> taken(items.size(), 0);
    for (std::size_t i = 0; i < items.size(); ++i) {
      if (taken[i]) continue;
      taken[i] = 1;
      group_items.push_back(static_cast<std::uint32_t>(i));
      if (grouped && few(items[i][0], items[i][1])) {
        const std::uint32_t side = items[i][0];
        const CutSide& s = cut.sides[side];
        const TriMesh& m = *s.m;
        // Breadth first over edge neighbours that are items too.
        for (std::size_t h = group_begin.back(); h < group_items.size(); ++h) {
          const std::uint32_t t = items[group_items[h]][1];
          for (std::size_t k = 0; k < 3; ++k) {
            if (group_items.size() - group_begin.back() >= kWalkGroup) break;
            const auto& et = m.edge_tri[m.tri_edge[t][k]];
            const std::uint32_t u = et[0] == t ? et[1] : et[0];
            if (u == kNil || s.slot[u] == kNil) continue;
            const std::uint32_t j = item_of[side][s.slot[u]];
            if (j == kNil || taken[j] || !few(side, u)) continue;
            taken[j] = 1;
            group_items.push_back(j);
          }
        }
      }
      group_begin.push_back(static_cast<std::uint32_t>(group_items.size()));
    }
  }
  const std::size_t n_groups = group_begin.size() - 1;
  std::atomic<std::size_t> walks{0};
  // A cut triangle's pairs are microseconds of work, so even a few dozen
  // are worth the second thread (the context's threshold is sized for loops
  // of cheap elements). The verdict is an "and" over the triangles: the same
  // for any thread count and order.
  ExecContext pctx = ctx;
  pctx.sequential_threshold = 4;
  pctx.grain = 1;
  par::for_each_n(pctx, n_groups, [&](std::size_t g) {
    if (failed.load(std::memory_order_relaxed)) return;
    // The suspects (kept pieces with a new point) of every member, keyed
    // (side, piece), and each member's query box.
    thread_local std::vector<CertTri> sus_all;
    thread_local std::vector<std::uint64_t> key_all;
    thread_local std::vector<std::uint32_t> sus_begin;
    thread_local std::vector<std::array<double, 6>> boxes;
    thread_local std::vector<std::uint32_t> stack, found[2];
    sus_all.clear();
    key_all.clear();
    sus_begin.assign(1, 0);
    boxes.clear();
    std::array<double, 6> group_q{HUGE_VAL, HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (std::uint32_t mi = group_begin[g]; mi < group_begin[g + 1]; ++mi) {
      const int side = static_cast<int>(items[group_items[mi]][0]);
      const std::uint32_t t = items[group_items[mi]][1];
      const CutSide& s = cut.sides[side];
      std::array<double, 6> q{HUGE_VAL, HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
      for (std::uint32_t p = s.piece_begin[t]; p < s.piece_begin[t + 1]; ++p) {
        if (!s.keep[p] || !is_suspect(s.piece[p])) continue;
        sus_all.emplace_back();
        cert_tri(cut, a, b, s.piece[p], sus_all.back());
        if (!cert_not_flat(sus_all.back()) &&
            collinear(sus_all.back().p[0], sus_all.back().p[1], sus_all.back().p[2])) {
          failed = true;
          return;
        }
        key_all.push_back((std::uint64_t{static_cast<std::uint32_t>(side)} << 32) | p);
        for (std::size_t k = 0; k < 3; ++k) {
          q[k] = std::min(q[k], sus_all.back().box[k]);
          q[k + 3] = std::max(q[k + 3], sus_all.back().box[k + 3]);
        }
      }
      for (std::size_t k = 0; k < 3; ++k) {
        q[k] -= delta;
        q[k + 3] += delta;
        group_q[k] = std::min(group_q[k], q[k]);
        group_q[k + 3] = std::max(group_q[k + 3], q[k + 3]);
      }
      sus_begin.push_back(static_cast<std::uint32_t>(sus_all.size()));
      boxes.push_back(q);
    }
    // The walks: every leaf entry whose box meets the group's box, in the
    // hierarchy's order.
    for (int o = 0; o < 2; ++o) {
      const Bvh& h = *bvhs[o];
      found[o].clear();
      if (h.nodes.empty()) continue;
      stack.assign(1, 0);
      while (!stack.empty()) {
        const Bvh::Node& nd = h.nodes[stack.back()];
        stack.pop_back();
        if (!cert_boxes_meet(nd.box, group_q)) continue;
        if (nd.left != kNil) {
          stack.push_back(nd.left);
          stack.push_back(nd.left + 1);
          continue;
        }
        for (std::uint32_t j = nd.first; j < nd.first + nd.count; ++j)
          if (cert_boxes_meet(h.box[j], group_q)) found[o].push_back(j);
      }
    }
    walks += 1;
    for (std::uint32_t mi = group_begin[g]; mi < group_begin[g + 1] && !failed.load(std::memory_order_relaxed);
         ++mi) {
      const std::size_t member = mi - group_begin[g];
      const int side = static_cast<int>(items[group_items[mi]][0]);
      const std::uint32_t t = items[group_items[mi]][1];
      const CutSide& s = cut.sides[side];
      const std::array<double, 6>& q = boxes[member];
      const CertTri* sus = sus_all.data() + sus_begin[member];
      const std::uint64_t* sus_key = key_all.data() + sus_begin[member];
      const std::size_t n_sus = sus_begin[member + 1] - sus_begin[member];
      std::size_t n_pairs = 0, n_exact = 0, n_embedded = 0;
      // cert17: pairs of two pieces of u, or of u and a neighbour across one
      // of its edges, need no test when those pieces certainly form an
      // embedded triangulation once rounded (rounded_pieces_embedded,
      // fold_embedding.cpp): they meet only in the corners they share by id,
      // which is all the pair tests below show (verdicts made before the
      // loop: embed_ok).
      const std::uint32_t slot_t = s.slot[t];
      const bool own_embedded = embed_ok[side][slot_t] & 1u;
      // cert18: t's own level patch: a found piece apart from it is apart
      // from every suspect (all pieces of t).
      const LevelPatch* own_patch = patch_of[side][slot_t] != kNil ? &patches[side][patch_of[side][slot_t]] : nullptr;
      thread_local std::vector<std::uint8_t> skip;  // per suspect: apart from u's level patch
      std::size_t n_level = 0;
      n_embedded += own_embedded ? 1 : 0;
      const TriMesh& mt = *s.m;
      auto same_patch = [&](std::uint32_t u) {
        if (u == t || !own_embedded) return own_embedded;
        for (std::size_t k = 0; k < 3; ++k) {
          const auto& et = mt.edge_tri[mt.tri_edge[t][k]];
          if ((et[0] == t ? et[1] : et[0]) == u) return (embed_ok[side][slot_t] >> (k + 1) & 1u) != 0;
        }
        return false;
      };
      CertTri x;
      for (int o = 0; o < 2 && !failed.load(std::memory_order_relaxed); ++o) {
        const Bvh& h = *bvhs[o];
        const CutSide& so = cut.sides[o];
        {
          for (const std::uint32_t j : found[o]) {
            if (!cert_boxes_meet(h.box[j], q)) continue;
            const std::uint32_t u = h.order[j];
            if (o == side && same_patch(u)) continue;
            const std::uint32_t slot = so.slot[u];
            const CertTri* pre_u = slot != kNil && pre_begin[o][slot] != kNil ? &pre[o][pre_begin[o][slot]] : nullptr;
            // cert18: u in a level patch: the suspects apart from it skip
            // all of u's pieces (fold_level_patch.cpp), and u is skipped when
            // all are.
            bool any_skip = false;
            if (slot != kNil && patch_of[o][slot] != kNil) {
              const LevelPatch& pu = patches[o][patch_of[o][slot]];
              skip.assign(n_sus, 0);
              bool all = true;
              for (std::size_t k = 0; k < n_sus; ++k) {
                skip[k] = level_patch_apart(pu, sus[k].p, sus[k].v) ? 1 : 0;
                any_skip = any_skip || skip[k] != 0;
                all = all && skip[k] != 0;
              }
              if (any_skip) ++n_level;
              if (all) continue;
            }
            for (std::uint32_t p = so.piece_begin[u]; p < so.piece_begin[u + 1]; ++p) {
              if (!so.keep[p]) continue;
              // A made piece's box first: most of a fan's miss a small query.
              if (pre_u != nullptr && !cert_boxes_meet(q, pre_u[p - so.piece_begin[u]].box)) continue;
              const std::uint64_t key = (std::uint64_t{static_cast<std::uint32_t>(o)} << 32) | p;
              const bool suspect = is_suspect(so.piece[p]);
              int made = 0;  // 1: corners and box, 2: and the normal
              const CertTri* xp = &x;
              for (std::size_t k = 0; k < n_sus; ++k) {
                // A pair of suspects once, from the smaller key's side (its
                // query finds the other: the boxes' relation is symmetric).
                if (key == sus_key[k] || (suspect && key < sus_key[k])) continue;
                if (made == 0) {
                  if (pre_u != nullptr) {
                    xp = pre_u + (p - so.piece_begin[u]);
                    made = 2;
                  } else {
                    cert_corners(cut, a, b, so.piece[p], x);
                    made = 1;
                  }
                  if (!cert_boxes_meet(q, xp->box)) break;
                  if (own_patch != nullptr && level_patch_apart(*own_patch, xp->p, xp->v)) {
                    ++n_level;
                    break;
                  }
                }
                if (any_skip && skip[k] != 0) continue;
                if (!cert_boxes_meet(sus[k].box, xp->box)) continue;
                if (made == 1) {
                  cert_normal(x);
                  made = 2;
                }
                ++n_pairs;
                // The level-plane rule after the self-check's rules (which
                // decide most pairs of a generic cut at no extra cost), before
                // the separating planes (17 candidates).
                if (cert_apart(sus[k], *xp) ||
                    (shortcut && (cert_level_apart(sus[k], *xp) || cert_level_apart(*xp, sus[k]))) ||
                    cert_apart_more(sus[k], *xp))
                  continue;
                ++n_exact;
                if (cert_cross_exact(sus[k], *xp)) {
                  failed = true;
                  return;
                }
              }
            }
          }
        }
      }
      pairs += n_pairs;
      exact += n_exact;
      embedded += n_embedded;
      level_skips += n_level;
    }
  });
  (failed ? result_check_counts().full : result_check_counts().certified) += 1;
  level_patch_counts().patches += patches[0].size() + patches[1].size();
  level_patch_counts().skips += level_skips;
  cert_walk_counts().walks += walks;
  result_check_counts().pairs += pairs;
  result_check_counts().embedded += embedded;
  if (stats != nullptr) {
    stats->cut_triangles = items.size();
    stats->pairs = pairs;
    stats->exact_pairs = exact;
    stats->certified = !failed;
    stats->embedded_triangles = embedded;
    stats->embedded_neighbours = n_neighbour_patches;
  }
  return !failed;
}

ResultCheckCounts& result_check_counts() noexcept {
  static ResultCheckCounts counts;
  return counts;
}

}  // namespace atelier::net_detail
