// The exact kernel of the net Booleans: every topological decision (which
// simplex of the other net holds a point, which side of a plane a vertex is
// on, the order of points in a refined triangle, the parity of a ray) is an
// exact predicate: CGAL's filtered Epick predicates on the input doubles, and
// the lazy exact kernel (Epeck) for points constructed from two simplices.
// Constructed points are never rounded before a decision; they are rounded
// once, for output (point_coordinates).
//
// Why not CGAL's corefinement: it runs every vertex of both nets through the
// exact kernel; here only the triangles that meet the other net see it, the
// rest stays plain doubles (docs/glossary.md, net Booleans).
//
// Why this file is long: it is the only file that sees CGAL (the exact
// kernel stays behind boolean_detail.h), so every exact predicate,
// construction and triangulation of the net operations lives here.
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mpzf.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/intersections.h>
#include <atelier/engine/parallel.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <numeric>
#include <sstream>

#include "boolean_detail.h"
#include "expansion.h"

namespace atelier::net_detail {

namespace {

using Ki = CGAL::Exact_predicates_inexact_constructions_kernel;
using Ke = CGAL::Exact_predicates_exact_constructions_kernel;
using Pi = Ki::Point_3;

Pi pi(const Vec3d& v) {
  return {v.x(), v.y(), v.z()};
}
Ke::Point_3 pe(const Vec3d& v) {
  return {v.x(), v.y(), v.z()};
}

/// An interval at most four ulps wide: its centre is the same bits on every
/// run and within 2 ulps of any value inside.
bool pinned(double lo, double hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) return false;
  for (int i = 0; i < 4 && lo < hi; ++i) lo = std::nextafter(lo, hi);
  return lo >= hi;
}

double centre(double lo, double hi) {
  return lo + 0.5 * (hi - lo);
}

int sgn(CGAL::Orientation o) {
  return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}

/// The two coordinates kept when dropping `axis`, in cyclic order, so the
/// 2D orientation of a projected triangle has the sign of its normal's
/// component along the axis.
inline int u_of(int axis) {
  return (axis + 1) % 3;
}
inline int v_of(int axis) {
  return (axis + 2) % 3;
}

Ki::Point_2 proj(const Vec3d& p, int axis) {
  return {p[u_of(axis)], p[v_of(axis)]};
}

int orient2(const Vec3d& a, const Vec3d& b, const Vec3d& c, int axis) {
  return sgn(CGAL::orientation(proj(a, axis), proj(b, axis), proj(c, axis)));
}

/// A projection axis along which the (non-degenerate) triangle stays
/// non-degenerate, and the sign of its projected orientation.
struct Projection {
  int axis = 2;
  int sign = 0;
};
Projection projection_of(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d n = (b - a).cross(c - a).cwiseAbs();
  std::array<int, 3> ax{0, 1, 2};
  std::sort(ax.begin(), ax.end(), [&](int i, int j) { return n[i] > n[j] || (n[i] == n[j] && i < j); });
  for (int k : ax) {
    const int s = orient2(a, b, c, k);
    if (s != 0) return {k, s};
  }
  return {2, 0};  // degenerate: refused before we get here
}

/// Where a point coplanar with triangle (c0, c1, c2) lies: -1 outside,
/// 0..2 vertex k, 3..5 edge k - 3 (from corner k to k+1), 6 interior.
int locate_coplanar(const Vec3d& p, const std::array<Vec3d, 3>& c, const Projection& pr) {
  int o[3];
  int zeros = 0;
  for (int k = 0; k < 3; ++k) {
    o[k] = orient2(c[k], c[(k + 1) % 3], p, pr.axis) * pr.sign;
    if (o[k] < 0) return -1;
    zeros += o[k] == 0;
  }
  if (zeros == 0) return 6;
  if (zeros == 1) {
    for (int k = 0; k < 3; ++k)
      if (o[k] == 0) return 3 + k;
  }
  // Two zero edges meet at their shared corner: edges k and k+1 share k+1.
  for (int k = 0; k < 3; ++k)
    if (o[k] == 0 && o[(k + 1) % 3] == 0) return (k + 1) % 3;
  return -1;
}

/// Where the line through p, q (crossing the triangle's plane) meets the
/// triangle: as locate_coplanar.
int locate_line(const Vec3d& p, const Vec3d& q, const std::array<Vec3d, 3>& c) {
  int o[3];
  int pos = 0, neg = 0, zeros = 0;
  for (int k = 0; k < 3; ++k) {
    o[k] = orient3d(p, q, c[k], c[(k + 1) % 3]);
    pos += o[k] > 0;
    neg += o[k] < 0;
    zeros += o[k] == 0;
  }
  if (pos && neg) return -1;
  if (zeros == 0) return 6;
  if (zeros == 1) {
    for (int k = 0; k < 3; ++k)
      if (o[k] == 0) return 3 + k;
  }
  for (int k = 0; k < 3; ++k)
    if (o[k] == 0 && o[(k + 1) % 3] == 0) return (k + 1) % 3;
  return -1;
}

/// Proper crossing of two coplanar segments in a projection (interiors meet
/// in one point); touching at an end is found by the vertex tests instead.
bool proper_crossing(const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s, int axis) {
  const int o1 = orient2(p, q, r, axis), o2 = orient2(p, q, s, axis);
  if (o1 * o2 >= 0) return false;
  const int o3 = orient2(r, s, p, axis), o4 = orient2(r, s, q, axis);
  return o3 * o4 < 0;
}

std::uint64_t local_simplex(const TriMesh& m, std::uint32_t t, int loc) {
  if (loc < 3) return simplex(kDimVertex, m.tri[t][static_cast<std::size_t>(loc)]);
  if (loc < 6) return simplex(kDimEdge, m.tri_edge[t][static_cast<std::size_t>(loc - 3)]);
  return simplex(kDimFace, t);
}

std::array<Vec3d, 3> corners(const TriMesh& m, std::uint32_t t) {
  const auto& v = m.tri[t];
  return {m.p[v[0]], m.p[v[1]], m.p[v[2]]};
}

/// One side of a triangle pair: the vertices and edges of triangle `ts` of
/// net `self` against triangle `to` of net `other`. `s` holds the
/// orientations of self's corners against other's plane.
template <class Push>
void half_pair(const TriMesh& self, std::uint32_t ts, const TriMesh& other, std::uint32_t to, const int* s,
               Push&& push) {
  const auto cs = corners(self, ts), co = corners(other, to);
  Projection pr;
  bool have_pr = false;
  auto projection = [&] {
    if (!have_pr) pr = projection_of(co[0], co[1], co[2]);
    have_pr = true;
    return pr;
  };
  for (int i = 0; i < 3; ++i) {
    if (s[i] != 0) continue;
    const int loc = locate_coplanar(cs[static_cast<std::size_t>(i)], co, projection());
    if (loc >= 0) push(simplex(kDimVertex, self.tri[ts][static_cast<std::size_t>(i)]), local_simplex(other, to, loc));
  }
  for (int k = 0; k < 3; ++k) {
    const int j = (k + 1) % 3;
    const std::uint64_t e = simplex(kDimEdge, self.tri_edge[ts][static_cast<std::size_t>(k)]);
    const Vec3d& p = cs[static_cast<std::size_t>(k)];
    const Vec3d& q = cs[static_cast<std::size_t>(j)];
    if (s[k] * s[j] < 0) {
      const int loc = locate_line(p, q, co);
      if (loc >= 0) push(e, local_simplex(other, to, loc));
    } else if (s[k] == 0 && s[j] == 0) {
      const Projection prj = projection();
      for (int m = 0; m < 3; ++m)
        if (proper_crossing(p, q, co[static_cast<std::size_t>(m)], co[static_cast<std::size_t>((m + 1) % 3)], prj.axis))
          push(e, local_simplex(other, to, 3 + m));
    }
  }
}

// ----------------------------------------------------------- constructions

Ke::Point_3 exact_point(const TriMesh& a, const TriMesh& b, const PointKey& k) {
  if (dim_of(k.a) == kDimVertex) return pe(a.p[idx_of(k.a)]);
  if (dim_of(k.b) == kDimVertex) return pe(b.p[idx_of(k.b)]);
  auto line = [](const TriMesh& m, std::uint64_t e) {
    const auto& ev = m.edge[idx_of(e)];
    return Ke::Line_3(pe(m.p[ev[0]]), pe(m.p[ev[1]]));
  };
  auto plane = [](const TriMesh& m, std::uint64_t f) {
    const auto& t = m.tri[idx_of(f)];
    return Ke::Plane_3(pe(m.p[t[0]]), pe(m.p[t[1]]), pe(m.p[t[2]]));
  };
  auto point_of = [](const auto& result) -> Ke::Point_3 {
    if (result) {
      if (const Ke::Point_3* p = boost::get<Ke::Point_3>(&*result)) return *p;
    }
    throw Error(Status(ErrorCode::kInternal, "net boolean: an intersection point has no unique construction"));
  };
  if (dim_of(k.a) == kDimEdge && dim_of(k.b) == kDimFace)
    return point_of(CGAL::intersection(line(a, k.a), plane(b, k.b)));
  if (dim_of(k.a) == kDimFace && dim_of(k.b) == kDimEdge)
    return point_of(CGAL::intersection(line(b, k.b), plane(a, k.a)));
  return point_of(CGAL::intersection(line(a, k.a), line(b, k.b)));
}

}  // namespace

struct ExactPoints {
  std::vector<Ke::Point_3> p;
  std::vector<std::uint8_t> ok;  // 0: no construction (exact_point throws again where it is used)
  std::uint32_t first_id = 0;    // global id of p[0] (nA + nB)
};

void ExactPointsDeleter::operator()(ExactPoints* p) const noexcept {
  delete p;
}

ExactPointsPtr make_exact_points(const TriMesh& a, const TriMesh& b, std::span<const PointKey> keys,
                                 std::span<const std::uint8_t> need, const ExecContext& ctx) {
  ExactPointsPtr out(new ExactPoints);
  out->first_id = static_cast<std::uint32_t>(a.p.size() + b.p.size());
  out->p.resize(keys.size());
  out->ok.assign(keys.size(), 0);
  par::for_each_n(ctx, keys.size(), [&](std::size_t i) {
    if (!need[i]) return;
    try {
      out->p[i] = exact_point(a, b, keys[i]);
      out->ok[i] = 1;
    } catch (const Error&) {
      // Left out: the triangle using the point reports the error.
    }
  });
  return out;
}

namespace {

// ------------------------------------------------------------ ray parity

bool segment_hits_box(const Vec3d& o, const Vec3d& d, const std::array<double, 6>& box, double eps) {
  double t0 = 0.0, t1 = 1.0;
  for (int k = 0; k < 3; ++k) {
    const double lo = box[static_cast<std::size_t>(k)] - eps, hi = box[static_cast<std::size_t>(k + 3)] + eps;
    if (d[k] == 0.0) {
      if (o[k] < lo || o[k] > hi) return false;
      continue;
    }
    double ta = (lo - o[k]) / d[k], tb = (hi - o[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

/// Fixed pseudo-random directions (the same on every run and machine).
Vec3d ray_direction(int k) {
  std::uint64_t s = 0x9e3779b97f4a7c15ull * static_cast<std::uint64_t>(k + 1);
  auto next = [&] {
    s ^= s >> 31;
    s *= 0xbf58476d1ce4e5b9ull;
    s ^= s >> 29;
    return static_cast<double>(s >> 11) * 0x1.0p-53 * 2.0 - 1.0;
  };
  Vec3d d(next(), next(), next());
  if (d.norm() < 1e-3) d = Vec3d(0.57, 0.61, 0.55);
  return d.normalized();
}

/// Winding number by the parity of crossings of a segment from q to a point
/// outside the net's box, with exact predicates of kernel K; 0 ok, or a
/// degenerate direction (returns false). The hierarchy is culled by the
/// segment from qd, q's double stand-in: `spread` bounds |q - qd| per
/// coordinate (q an interval point: its box's half-width), so a node the
/// segment from q itself may cross is never skipped. Without it a wide box
/// (a point on Cray's 3.4e38 slab diagonal: 1e23 wide) gave a certain,
/// wrong parity: the uncertain predicates that would send the question to
/// the exact kernel were culled away (issue 24, round 13).
template <class K>
bool ray_winding(const TriMesh& m, const Bvh& bvh, const typename K::Point_3& q, const Vec3d& qd, const Vec3d& r,
                 double spread, int& w) {
  using P = typename K::Point_3;
  const double scale = std::max({m.bounds.lo.cwiseAbs().maxCoeff(), m.bounds.hi.cwiseAbs().maxCoeff(),
                                 qd.cwiseAbs().maxCoeff(), r.cwiseAbs().maxCoeff()});
  const double eps = 1e-9 * scale + 1e-300 + spread;
  const Vec3d d = r - qd;
  const P pr(r.x(), r.y(), r.z());
  w = 0;
  std::vector<std::uint32_t> stack{0};
  while (!stack.empty()) {
    const std::uint32_t n = stack.back();
    stack.pop_back();
    const Bvh::Node& node = bvh.nodes[n];
    if (!segment_hits_box(qd, d, node.box, eps)) continue;
    if (node.left != kNil) {
      stack.push_back(node.left);
      stack.push_back(node.left + 1);
      continue;
    }
    for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
      const auto& t = m.tri[bvh.order[i]];
      const P c0(m.p[t[0]].x(), m.p[t[0]].y(), m.p[t[0]].z());
      const P c1(m.p[t[1]].x(), m.p[t[1]].y(), m.p[t[1]].z());
      const P c2(m.p[t[2]].x(), m.p[t[2]].y(), m.p[t[2]].z());
      const int oq = sgn(CGAL::orientation(c0, c1, c2, q));
      const int orr = sgn(CGAL::orientation(c0, c1, c2, pr));
      if (orr == 0) return false;  // the far end lies on a plane: try another direction
      if (oq == orr) continue;
      const int e0 = sgn(CGAL::orientation(q, pr, c0, c1));
      const int e1 = sgn(CGAL::orientation(q, pr, c1, c2));
      const int e2 = sgn(CGAL::orientation(q, pr, c2, c0));
      if (oq == 0) {
        // q in the triangle's plane: the segment meets the plane at q only
        // (its far end is off it), so it crosses the triangle iff q is in
        // it, i.e. q on the net (callers never ask; try another direction).
        // q outside it, in the plane of a coplanar neighbour or of an
        // uncut coplanar face of the other net (a sphere and its copy
        // shifted along a face), is no crossing (issue 24, round 16).
        if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) return false;
        continue;
      }
      if (e0 == 0 || e1 == 0 || e2 == 0) {
        if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) return false;  // edge or vertex
        continue;
      }
      if (e0 != e1 || e1 != e2) continue;
      // q behind the triangle (against its outward normal) leaves the solid here.
      w += oq < 0 ? 1 : -1;
    }
  }
  return true;
}

template <class K>
int winding_any(const TriMesh& m, const Bvh& bvh, const typename K::Point_3& q, const Vec3d& qd, double spread = 0.0) {
  if (bvh.nodes.empty()) return 0;
  const Vec3d centre = 0.5 * (m.bounds.lo + m.bounds.hi);
  const double reach = 2.0 * ((m.bounds.hi - m.bounds.lo).norm() + (qd - centre).norm()) + 1.0;
  for (int k = 0; k < 64; ++k) {
    const Vec3d r = qd + reach * ray_direction(k);
    int w = 0;
    if (ray_winding<K>(m, bvh, q, qd, r, spread, w)) return w;
  }
  throw Error(Status(ErrorCode::kInternal, "net boolean: no generic ray direction found for a winding number"));
}

// Shewchuk's exact arithmetic (expansion.h): eight doubles never need more
// than eight components.
using Expansion = GrowExpansion<8>;

/// The sign of det[b - a, c - a, d - c] (= orient3d) when d - c is exact
/// in doubles: the cofactor row n = (c - a) x (d - c) = c x r3 - a x r3 is
/// summed exactly (an expansion of eight products per coordinate) and
/// rounded, so no cancellation between 3.4e38-sized products is lost; the
/// dot product with b - a (rounded, its tail known exactly) then has a
/// rigorous error bound. Cray's diagonal (c, d at 3.4e38) against an edge
/// (a, b) of A 1e4 from it: det about 1e47, the bound about 1e33. 2 when
/// it cannot tell or d - c rounds.
int orient3d_cofactor(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) noexcept {
  std::array<double, 3> r1, t1, r3;
  auto in_range = [](double x) { return x == 0.0 || (std::abs(x) > 0x1p-250 && std::abs(x) < 0x1p250); };
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    double t3;
    two_sum(d[k], -c[k], r3[i], t3);
    if (t3 != 0.0) return 2;
    two_sum(b[k], -a[k], r1[i], t1[i]);
    if (!in_range(r3[i]) || !in_range(a[k]) || !in_range(c[k]) || !in_range(r1[i])) return 2;
  }
  double p = 0.0, t = 0.0, det = 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    const std::size_t i = (k + 1) % 3, j = (k + 2) % 3;
    // n_k = c_i r3_j - c_j r3_i - a_i r3_j + a_j r3_i, each product as
    // head + tail (Two-Product).
    Expansion e;
    // Two-Product by a fused multiply-add; a zero factor (the slab's edges
    // along an axis) adds nothing.
    auto product = [&](double x, double y) {
      if (x == 0.0 || y == 0.0) return;
      const double h = x * y;
      e.add(std::fma(x, y, -h));
      e.add(h);
    };
    product(c[static_cast<int>(i)], r3[j]);
    product(-c[static_cast<int>(j)], r3[i]);
    product(-a[static_cast<int>(i)], r3[j]);
    product(a[static_cast<int>(j)], r3[i]);
    if (e.full) return 2;
    double n = 0.0;  // the components summed upwards: within 8 eps |n_k|
    for (std::size_t q = 0; q < e.n; ++q) n += e.e[q];
    det += r1[k] * n;
    p += std::abs(r1[k] * n);
    t += std::abs(t1[k] * n);
  }
  // |exact - det| <= (sum |t1| |n|) + (sum |r1| |n|)(8 eps for n + 3 eps
  // for the dot product), with room for the rounding of p and t.
  const double bound = 1.125 * (t + p * 0x1p-48);
  if (!std::isfinite(bound) || !std::isfinite(det)) return 2;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return 2;
}

/// A question orient3d(a, b, c, d) up to the orders that keep or flip its
/// sign: each pair (a, b), (c, d) in lexicographic order (a swap flips
/// the sign) and the pairs in order (orient3d(c, d, a, b) is an even
/// permutation).
struct OrientMemoKey {
  std::array<const Vec3d*, 4> p;
  static bool less(const Vec3d& x, const Vec3d& y) noexcept {
    return std::lexicographical_compare(x.data(), x.data() + 3, y.data(), y.data() + 3);
  }
  /// Reorders p; returns +1 or -1, the sign relating the two questions.
  int canonical() noexcept {
    int flip = 1;
    if (less(*p[1], *p[0])) std::swap(p[0], p[1]), flip = -flip;
    if (less(*p[3], *p[2])) std::swap(p[2], p[3]), flip = -flip;
    if (less(*p[2], *p[0]) || (*p[2] == *p[0] && less(*p[3], *p[1]))) std::swap(p[0], p[2]), std::swap(p[1], p[3]);
    return flip;
  }
};
std::atomic<std::uint64_t> orient_memo_generation{1};
struct OrientMemoEntry {
  std::array<double, 12> x{};
  int sign = 0;
  std::uint64_t generation = 0;  // filled in this generation
  [[nodiscard]] bool same(const OrientMemoKey& k) const noexcept {
    for (std::size_t i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j)
        if (std::bit_cast<std::uint64_t>(x[3 * i + static_cast<std::size_t>(j)]) !=
            std::bit_cast<std::uint64_t>((*k.p[i])[j]))
          return false;
    return true;
  }
  void store(const OrientMemoKey& k, int s) noexcept {
    for (std::size_t i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j) x[3 * i + static_cast<std::size_t>(j)] = (*k.p[i])[j];
    sign = s;
    generation = orient_memo_generation.load(std::memory_order_relaxed);
  }
};
/// The slot of a canonical question in this thread's direct-mapped memo.
OrientMemoEntry& orient_memo_slot(const OrientMemoKey& k) noexcept {
  thread_local std::array<OrientMemoEntry, 256> memo;
  std::uint64_t h = 0x9e3779b97f4a7c15ULL;
  for (const Vec3d* q : k.p)
    for (int j = 0; j < 3; ++j) {
      h ^= std::bit_cast<std::uint64_t>((*q)[j]);
      h *= 0xff51afd7ed558ccdULL;
      h ^= h >> 29;
    }
  return memo[static_cast<std::size_t>(h >> 56)];
}

/// orient3d after its first filter fails (kept out of line so the filter
/// inlines into its callers): exact rules that need no CGAL, then CGAL's
/// filtered predicate.
[[gnu::noinline]] int orient3d_slow(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) noexcept {
  // A plane of constant coordinate k (Cray's slab, CAD boxes): the normal is
  // (0, 0, orient2d) along k, so the sign is that of d_k - a_k (an exact
  // comparison) times the exact orientation of the corners across k. The
  // filter above fails there whenever the corners are far (3.4e38) or d lies
  // on the plane; the exact fallback would take Mpzf products of 3.4e38^3.
  for (int k = 0; k < 3; ++k)
    if (a[k] == b[k] && a[k] == c[k]) return (d[k] > a[k] ? 1 : (d[k] < a[k] ? -1 : 0)) * orient2(a, b, c, k);
  // Without CGAL when d - c is exact: an edge (a, b) of A against an edge
  // (c, d) of Cray's slab, whose differences to a 3.4e38 corner no double
  // filter can use (the cofactor).
  // Only for pairs far apart against the short edge (callgrind: on
  // Offset3 x Offset4's coplanar zeros these stages cost more than CGAL's
  // Mpzf on short numbers).
  auto far = [](const Vec3d& p, const Vec3d& q, const Vec3d& r) {
    return (r - p).cwiseAbs().maxCoeff() > 0x1p20 * (q - p).cwiseAbs().maxCoeff();
  };
  const bool far_ab = far(a, b, c), far_cd = far(c, d, a);
  if (!far_ab && !far_cd) return sgn(CGAL::orientation(pi(a), pi(b), pi(c), pi(d)));
  // The same far question comes back from neighbouring pairs (an edge of A
  // and the slab's diagonal: from both triangles of the edge, against both
  // triangles of the diagonal): a per-thread memo of the answers. The
  // answer is a function of the question, so the memo changes no bit.
  OrientMemoKey key{{&a, &b, &c, &d}};
  const int flip = key.canonical();
  OrientMemoEntry& slot = orient_memo_slot(key);
  if (slot.generation == orient_memo_generation.load(std::memory_order_relaxed) && slot.same(key))
    return flip * slot.sign;
  int o = 2;
  if (far_ab) o = orient3d_cofactor(a, b, c, d);
  if (o == 2 && far_cd) o = orient3d_cofactor(c, d, a, b);  // an even permutation
  if (o == 2) o = sgn(CGAL::orientation(pi(a), pi(b), pi(c), pi(d)));
  slot.store(key, flip * o);
  return o;
}

}  // namespace

void new_orient3d_memo_generation() noexcept {
  orient_memo_generation.fetch_add(1, std::memory_order_relaxed);
}

int orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) noexcept {
  // Shewchuk's first-stage filter (orient3d, error bound A = (7 + 56 eps) eps
  // times the permanent): decides almost every call without CGAL's call
  // overhead; CGAL's filtered predicate (exact when it must be) takes the rest.
  const double adx = a.x() - d.x(), ady = a.y() - d.y(), adz = a.z() - d.z();
  const double bdx = b.x() - d.x(), bdy = b.y() - d.y(), bdz = b.z() - d.z();
  const double cdx = c.x() - d.x(), cdy = c.y() - d.y(), cdz = c.z() - d.z();
  const double bc = bdy * cdz - bdz * cdy, ca = cdy * adz - cdz * ady, ab = ady * bdz - adz * bdy;
  const double det = adx * bc + bdx * ca + cdx * ab;
  const double perm = (std::abs(bdy * cdz) + std::abs(bdz * cdy)) * std::abs(adx) +
                      (std::abs(cdy * adz) + std::abs(cdz * ady)) * std::abs(bdx) +
                      (std::abs(ady * bdz) + std::abs(adz * bdy)) * std::abs(cdx);
  constexpr double kBound = 7.7715611723761027e-16;  // (7 + 56 eps) eps, eps = 2^-53
  if (std::isfinite(perm) && perm > 1e-250) {
    const double bound = kBound * perm;
    // Shewchuk's determinant is positive when d lies on the side opposite
    // to the normal (b - a) x (c - a).
    if (det > bound) return -1;
    if (-det > bound) return 1;
  }
  return orient3d_slow(a, b, c, d);
}

bool collinear(const Vec3d& a, const Vec3d& b, const Vec3d& c) noexcept {
  return orient2(a, b, c, 0) == 0 && orient2(a, b, c, 1) == 0 && orient2(a, b, c, 2) == 0;
}

void intersect_pair(const TriMesh& a, std::uint32_t ta, const TriMesh& b, std::uint32_t tb, PairHit& out) {
  out.points.clear();
  out.coplanar = false;
  const auto ca = corners(a, ta), cb = corners(b, tb);
  int s[3], r[3];
  for (int i = 0; i < 3; ++i) s[i] = orient3d(cb[0], cb[1], cb[2], ca[static_cast<std::size_t>(i)]);
  if ((s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0)) return;
  for (int j = 0; j < 3; ++j) r[j] = orient3d(ca[0], ca[1], ca[2], cb[static_cast<std::size_t>(j)]);
  if ((r[0] > 0 && r[1] > 0 && r[2] > 0) || (r[0] < 0 && r[1] < 0 && r[2] < 0)) return;
  out.coplanar = s[0] == 0 && s[1] == 0 && s[2] == 0;
  half_pair(a, ta, b, tb, s, [&](std::uint64_t sa, std::uint64_t sb) { out.points.push_back({sa, sb}); });
  half_pair(b, tb, a, ta, r, [&](std::uint64_t sb, std::uint64_t sa) { out.points.push_back({sa, sb}); });
  std::sort(out.points.begin(), out.points.end());
  out.points.erase(std::unique(out.points.begin(), out.points.end()), out.points.end());
}

bool triangles_cross(const TriMesh& m, std::uint32_t t1, std::uint32_t t2) {
  const auto& A = m.tri[t1];
  const auto& B = m.tri[t2];
  int shared = 0;
  int ia = -1, ib = -1;  // a shared corner in each
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (A[static_cast<std::size_t>(i)] == B[static_cast<std::size_t>(j)]) {
        ++shared;
        ia = i;
        ib = j;
      }
  // Fast exact rejection: the other triangle's own corners strictly on one
  // side of this one's plane (then they meet at most in shared corners).
  auto one_side = [&](const std::array<std::uint32_t, 3>& X, const std::array<std::uint32_t, 3>& Y) {
    int pos = 0, neg = 0;
    for (std::uint32_t y : Y) {
      if (std::find(X.begin(), X.end(), y) != X.end()) continue;
      const int o = orient3d(m.p[X[0]], m.p[X[1]], m.p[X[2]], m.p[y]);
      pos += o > 0;
      neg += o < 0;
      if (o == 0) return false;
    }
    return pos == 0 || neg == 0;
  };
  if (shared < 2 && (one_side(A, B) || one_side(B, A))) return false;
  const Ki::Triangle_3 ta(pi(m.p[A[0]]), pi(m.p[A[1]]), pi(m.p[A[2]]));
  const Ki::Triangle_3 tb(pi(m.p[B[0]]), pi(m.p[B[1]]), pi(m.p[B[2]]));
  if (shared == 0) return CGAL::do_intersect(ta, tb);
  if (shared == 1) {
    const Ki::Segment_3 sa(pi(m.p[A[static_cast<std::size_t>((ia + 1) % 3)]]),
                           pi(m.p[A[static_cast<std::size_t>((ia + 2) % 3)]]));
    const Ki::Segment_3 sb(pi(m.p[B[static_cast<std::size_t>((ib + 1) % 3)]]),
                           pi(m.p[B[static_cast<std::size_t>((ib + 2) % 3)]]));
    return CGAL::do_intersect(sa, tb) || CGAL::do_intersect(sb, ta);
  }
  if (shared == 2) {
    // The corners not shared; folded onto each other only when coplanar and
    // on the same side of the shared edge.
    int oa = 0, ob = 0;
    for (int i = 0; i < 3; ++i)
      if (std::find(B.begin(), B.end(), A[static_cast<std::size_t>(i)]) == B.end()) oa = i;
    for (int j = 0; j < 3; ++j)
      if (std::find(A.begin(), A.end(), B[static_cast<std::size_t>(j)]) == A.end()) ob = j;
    const Vec3d& u = m.p[A[static_cast<std::size_t>((oa + 1) % 3)]];
    const Vec3d& v = m.p[A[static_cast<std::size_t>((oa + 2) % 3)]];
    const Vec3d& x = m.p[A[static_cast<std::size_t>(oa)]];
    const Vec3d& y = m.p[B[static_cast<std::size_t>(ob)]];
    if (orient3d(u, v, x, y) != 0) return false;
    const Projection pr = projection_of(u, v, x);
    return orient2(u, v, x, pr.axis) * orient2(u, v, y, pr.axis) > 0;
  }
  return true;
}

std::uint32_t PointIds::find(const PointKey& k) const {
  const auto it = std::lower_bound(keys.begin(), keys.end(), k);
  return it != keys.end() && *it == k ? id[static_cast<std::size_t>(it - keys.begin())] : kNil;
}

namespace {

// Delaunay: among the triangulations with the cut segments, the one that
// avoids slivers. Nearly collinear cut points (a net cutting the coplanar
// fan of a split planar polygon) would otherwise give triangles a rounding
// of the points can fold over.
template <class K>
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<
    K,
    CGAL::Triangulation_data_structure_2<CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K>,
                                         CGAL::Constrained_triangulation_face_base_2<K>>,
    CGAL::No_constraint_intersection_requiring_constructions_tag>;

/// A cut triangle as both triangulations see it: its net, the global id
/// of the net's vertex 0, its corners and the projection that keeps it.
struct CutTriangle {
  CutTriangle(const TriMesh& a, const TriMesh& b, int side_, std::uint32_t t)
      : m(side_ == 0 ? a : b),
        side(side_),
        offset(side_ == 0 ? 0u : static_cast<std::uint32_t>(a.p.size())),
        c(corners(m, t)),
        pr(projection_of(c[0], c[1], c[2])),
        u(u_of(pr.axis)),
        v(v_of(pr.axis)) {}
  [[nodiscard]] std::uint64_t own(const PointKey& k) const noexcept { return side == 0 ? k.a : k.b; }
  const TriMesh& m;
  int side;
  std::uint32_t offset;
  std::array<Vec3d, 3> c;
  Projection pr;
  int u, v;
};

}  // namespace

Status refine_triangle(const TriMesh& a, const TriMesh& b, int side, std::uint32_t t, std::span<const PointKey> points,
                       std::span<const std::array<PointKey, 2>> constraints, const PointIds& ids,
                       const ExactPoints& exact, std::vector<std::array<std::uint32_t, 3>>& out) {
  using Ct = Cdt<Ke>;
  const CutTriangle ctri(a, b, side, t);
  const TriMesh& m = ctri.m;
  const std::uint32_t offset = ctri.offset;
  const auto& tv = m.tri[t];
  const auto& c = ctri.c;
  const Projection pr = ctri.pr;
  const int u = ctri.u, v = ctri.v;
  auto own = [&](const PointKey& k) { return ctri.own(k); };
  try {
    Ct ct;
    std::array<Ct::Vertex_handle, 3> corner;
    for (std::size_t k = 0; k < 3; ++k) {
      corner[k] = ct.insert(Ke::Point_2(c[k][u], c[k][v]));
      corner[k]->info() = tv[k] + offset;
    }
    std::vector<std::pair<PointKey, Ct::Vertex_handle>> handle;
    handle.reserve(points.size());
    auto project = [&](const Ke::Point_3& p) {
      return pr.axis == 0 ? Ke::Point_2(p.y(), p.z())
                          : (pr.axis == 1 ? Ke::Point_2(p.z(), p.x()) : Ke::Point_2(p.x(), p.y()));
    };
    // Points on the triangle's edges go in by their known place (the edge,
    // sorted along it), so no predicate has to find out that they are
    // collinear with its corners: an exact zero the filters cannot certify.
    std::array<std::vector<std::pair<Ke::Point_3, PointKey>>, 3> on_edge;
    std::vector<std::pair<Ke::Point_3, PointKey>> inside;
    for (const PointKey& k : points) {
      const std::uint64_t s = own(k);
      if (dim_of(s) == kDimVertex) {
        for (std::size_t q = 0; q < 3; ++q)
          if (tv[q] == idx_of(s)) handle.emplace_back(k, corner[q]);
        continue;
      }
      std::size_t slot = 3;
      if (dim_of(s) == kDimEdge)
        for (std::size_t q = 0; q < 3; ++q)
          if (m.tri_edge[t][q] == idx_of(s)) slot = q;
      const std::uint32_t id = ids.find(k);
      const bool shared =
          id != kNil && id >= exact.first_id && id - exact.first_id < exact.p.size() && exact.ok[id - exact.first_id];
      (slot < 3 ? on_edge[slot] : inside).emplace_back(shared ? exact.p[id - exact.first_id] : exact_point(a, b, k), k);
    }
    auto add = [&](Ct::Vertex_handle h, const PointKey& k) -> Status {
      const std::uint32_t id = ids.find(k);
      h->info() = id;
      handle.emplace_back(k, h);
      return {};
    };
    for (std::size_t q = 0; q < 3; ++q) {
      auto& list = on_edge[q];
      const Vec3d d = c[(q + 1) % 3] - c[q];
      int ax = 0;
      d.cwiseAbs().maxCoeff(&ax);
      const bool up = d[ax] > 0;
      std::sort(list.begin(), list.end(), [&](const auto& x, const auto& y) {
        return up ? x.first[ax] < y.first[ax] : y.first[ax] < x.first[ax];
      });
      // Two points of one edge at one place (different simplices of the
      // other net there: that net crosses itself, a promise broken with the
      // self-intersection check off). Inserted "into the edge", the second
      // would be a zero-length edge: the triangulation is then corrupt (the
      // crash of issue 24), so refuse it; cut_nets names the crossing faces.
      for (std::size_t i = 0; i + 1 < list.size(); ++i)
        if (!(list[i].first[ax] != list[i + 1].first[ax])) {
          std::ostringstream msg;
          msg << "net boolean: two intersection points coincide on an edge of triangle " << t << " of " << m.name;
          return {ErrorCode::kInternal, msg.str()};
        }
      Ct::Vertex_handle prev = corner[q];
      for (const auto& [p, k] : list) {
        Ct::Face_handle f;
        int i = 0;
        if (!ct.is_edge(prev, corner[(q + 1) % 3], f, i)) {
          std::ostringstream msg;
          msg << "net boolean: points on an edge of triangle " << t << " of " << m.name << " are out of order";
          return {ErrorCode::kInternal, msg.str()};
        }
        const Ct::Vertex_handle h = ct.insert(project(p), Ct::EDGE, f, i);
        (void)add(h, k);
        prev = h;
      }
    }
    for (const auto& [p, k] : inside) {
      const std::size_t before = ct.number_of_vertices();
      const Ct::Vertex_handle h = ct.insert(project(p));
      if (ct.number_of_vertices() == before) {
        std::ostringstream msg;
        msg << "net boolean: two intersection points coincide in triangle " << t << " of " << m.name;
        return {ErrorCode::kInternal, msg.str()};
      }
      (void)add(h, k);
    }
    std::sort(handle.begin(), handle.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    auto find = [&](const PointKey& k) {
      const auto it = std::lower_bound(handle.begin(), handle.end(), k,
                                       [](const auto& x, const PointKey& key) { return x.first < key; });
      return it != handle.end() && it->first == k ? it->second : Ct::Vertex_handle();
    };
    for (const auto& seg : constraints) {
      const Ct::Vertex_handle h0 = find(seg[0]), h1 = find(seg[1]);
      if (h0 == Ct::Vertex_handle() || h1 == Ct::Vertex_handle()) {
        std::ostringstream msg;
        msg << "net boolean: a cut segment of triangle " << t << " of " << m.name << " lacks an end point";
        return {ErrorCode::kInternal, msg.str()};
      }
      if (h0 != h1) ct.insert_constraint(h0, h1);
    }
    for (auto f = ct.finite_faces_begin(); f != ct.finite_faces_end(); ++f) {
      if (CGAL::orientation(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point()) != CGAL::LEFT_TURN) {
        std::ostringstream msg;
        msg << "net boolean: a refined triangle of triangle " << t << " of " << m.name << " is flat ("
            << on_edge[0].size() << "," << on_edge[1].size() << "," << on_edge[2].size() << " edge points, "
            << inside.size() << " inside)";
        return {ErrorCode::kInternal, msg.str()};
      }
      std::array<std::uint32_t, 3> tri{f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
      if (pr.sign < 0) std::swap(tri[1], tri[2]);
      out.push_back(tri);
    }
  } catch (const Error& e) {
    return e.status();
  } catch (const std::exception& e) {
    std::ostringstream msg;
    msg << "net boolean: cut segments cross inside triangle " << t << " of " << m.name << " (" << e.what() << ")";
    return {ErrorCode::kInternal, msg.str()};
  }
  return {};
}

namespace {

/// cray16: CGAL's constrained Delaunay triangulation of the commonest cut
/// triangle (two cut points, on two different edges, joined by the one cut
/// segment) is a function of a few bits: which edge each point is on, in
/// which order they go in, and the Delaunay choice of the diagonal of the
/// quadrilateral left after the corner (the sign of one in-circle test,
/// CGAL's own exact predicate on the same doubles). The insertions, the
/// flip and the constraint are then the same operations on the same
/// containers, so the triangles come out in the same order with the same
/// first vertex. The first triangulation of each key is CGAL's (recorded
/// here, per thread); later ones reuse its list of local vertex triples,
/// with the same certificates. A key's record is the same on every thread:
/// no bit depends on which thread saw a key first.
struct SplitPattern {
  bool known = false;
  std::array<std::array<std::uint8_t, 3>, 3> tri{};
};
constexpr int kSplitKeys = 27;  // 3 x 3 edge pairs (6 used) x 3 in-circle signs
std::atomic<bool> direct_split_on{true};
std::atomic<std::uint64_t> direct_split_taken{0};

}  // namespace

std::uint64_t direct_split_count() noexcept {
  return direct_split_taken.load(std::memory_order_relaxed);
}

void set_direct_split(bool on) noexcept {
  direct_split_on.store(on, std::memory_order_relaxed);
}

bool refine_triangle_fast(const TriMesh& a, const TriMesh& b, int side, std::uint32_t t,
                          std::span<const PointKey> points, std::span<const std::array<PointKey, 2>> constraints,
                          const PointIds& ids, std::span<const PointBox> boxes, std::uint32_t first_new,
                          std::vector<std::array<std::uint32_t, 3>>& out, bool projected) {
  using Ct = Cdt<Ki>;
  using I = CGAL::Interval_nt<true>;
  const CutTriangle ctri(a, b, side, t);
  const TriMesh& m = ctri.m;
  const TriMesh& other = side == 0 ? b : a;
  const auto& tv = m.tri[t];
  const auto& c = ctri.c;
  const Projection pr = ctri.pr;
  const int u = ctri.u, v = ctri.v;
  auto own = [&](const PointKey& k) { return ctri.own(k); };
  auto theirs = [&](const PointKey& k) { return side == 0 ? k.b : k.a; };
  // Every vertex: its global id, its projected box (lo u, lo v, hi u, hi v)
  // and the double point the triangulation sees (the box's centre).
  struct Vert {
    std::uint32_t id;
    std::array<double, 4> box;
  };
  // Per-thread scratch (cray16): the vectors keep their room from one cut
  // triangle to the next instead of six allocations per triangle. Not
  // re-entered: nothing below calls refine_triangle_fast.
  struct Scratch {
    std::vector<Vert> vert;
    std::array<std::vector<std::uint32_t>, 3> on_edge;
    std::vector<std::uint32_t> inside, chain;
    std::vector<std::pair<PointKey, std::uint32_t>> by_key;
    std::vector<Ki::Point_2> frame;
  };
  thread_local Scratch scratch;
  std::vector<Vert>& vert = scratch.vert;
  vert.clear();
  vert.reserve(points.size() + 3);
  for (std::size_t q = 0; q < 3; ++q) vert.push_back({tv[q] + ctri.offset, {c[q][u], c[q][v], c[q][u], c[q][v]}});
  std::array<std::vector<std::uint32_t>, 3>& on_edge = scratch.on_edge;  // indices into vert
  for (auto& l : on_edge) l.clear();
  std::vector<std::uint32_t>& inside = scratch.inside;
  inside.clear();
  std::vector<std::pair<PointKey, std::uint32_t>>& by_key = scratch.by_key;  // (key, index into vert)
  by_key.clear();
  by_key.reserve(points.size());
  for (const PointKey& k : points) {
    const std::uint64_t s = own(k);
    if (dim_of(s) == kDimVertex) {
      for (std::uint32_t q = 0; q < 3; ++q)
        if (tv[q] == idx_of(s)) by_key.emplace_back(k, q);
      continue;
    }
    const std::uint32_t id = ids.find(k);
    if (id == kNil) return false;
    std::array<double, 6> box3;
    const std::uint64_t o = theirs(k);
    if (dim_of(o) == kDimVertex) {
      const Vec3d& x = other.p[idx_of(o)];
      box3 = {x.x(), x.y(), x.z(), x.x(), x.y(), x.z()};
    } else {
      if (id < first_new || id - first_new >= boxes.size() || !boxes[id - first_new].ok) return false;
      box3 = boxes[id - first_new].b;
    }
    const auto n = static_cast<std::uint32_t>(vert.size());
    vert.push_back({id,
                    {box3[static_cast<std::size_t>(u)], box3[static_cast<std::size_t>(v)],
                     box3[static_cast<std::size_t>(u + 3)], box3[static_cast<std::size_t>(v + 3)]}});
    by_key.emplace_back(k, n);
    std::size_t slot = 3;
    if (dim_of(s) == kDimEdge)
      for (std::size_t q = 0; q < 3; ++q)
        if (m.tri_edge[t][q] == idx_of(s)) slot = q;
    (slot < 3 ? on_edge[slot] : inside).push_back(n);
  }
  // The triangulation runs in the triangle's own affine frame (corners
  // (0, 0), (1, 0), (0, 1)), where a point on an edge can be put exactly on
  // it in doubles ((l, 0), (x, 1 - x) with x = fl(1 - l), (0, y)): CGAL's
  // triangulation must see consistent geometry. Interior points are mapped
  // in doubles; where they land only guides the combinatorics, which are
  // certified below on the boxes.
  const double p0u = c[0][u], p0v = c[0][v];
  const double e1u = c[1][u] - p0u, e1v = c[1][v] - p0v, e2u = c[2][u] - p0u, e2v = c[2][v] - p0v;
  const double det = e1u * e2v - e1v * e2u;
  if (!projected && (!(std::abs(det) > 0) || !std::isfinite(det))) return false;
  auto mid2 = [&](std::uint32_t i) {
    const auto& x = vert[i].box;
    return std::array<double, 2>{centre(x[0], x[2]) - p0u, centre(x[1], x[3]) - p0v};
  };
  std::vector<Ki::Point_2>& frame = scratch.frame;
  frame.assign(vert.size(), Ki::Point_2(0.0, 0.0));
  frame[0] = {0.0, 0.0};
  frame[1] = {1.0, 0.0};
  frame[2] = {0.0, 1.0};
  // Projected: the boxes' centres as they are (the triangle's corners
  // exact), for a triangle whose frame would merge its points (a corner at
  // 3.4e38 and cut points of size 1e4: Cray). An edge point then lies on
  // its edge in doubles only where the projected edge is axis-parallel or
  // the centre happens to be exactly on it; elsewhere the boundary
  // certificate below fails and the exact path decides.
  for (std::uint32_t i = 0; projected && i < vert.size(); ++i) {
    const auto& x = vert[i].box;
    frame[i] = {centre(x[0], x[2]), centre(x[1], x[3])};
  }
  for (std::uint32_t q = 0; q < 3 && !projected; ++q)
    for (std::uint32_t i : on_edge[q]) {
      // The parameter along the edge from its first corner.
      const auto m2 = mid2(i);
      const double s1 = (m2[0] * e2v - m2[1] * e2u) / det, s2 = (e1u * m2[1] - e1v * m2[0]) / det;
      const double l = q == 0 ? s1 : (q == 1 ? s2 : 1.0 - s2);
      if (!(l > 0.0 && l < 1.0)) return false;
      if (q == 0) {
        frame[i] = {l, 0.0};
      } else if (q == 1) {
        const double x = 1.0 - l;
        frame[i] = {x, 1.0 - x};  // x + (1 - x) == 1 exactly (Sterbenz: 1 - l or 1 - x is exact)
      } else {
        frame[i] = {0.0, 1.0 - l};
      }
    }
  for (std::uint32_t i : inside) {
    if (projected) break;
    const auto m2 = mid2(i);
    frame[i] = {(m2[0] * e2v - m2[1] * e2u) / det, (e1u * m2[1] - e1v * m2[0]) / det};
  }
  // Certified sign of the orientation of three vertices, for any points in
  // their boxes: +1, -1, or 0 when the intervals cannot tell.
  auto orient_from = [&](std::uint32_t i, std::uint32_t j, std::uint32_t k) {
    const auto &p = vert[i].box, &q = vert[j].box, &r = vert[k].box;
    const I px(p[0], p[2]), py(p[1], p[3]), qx(q[0], q[2]), qy(q[1], q[3]), rx(r[0], r[2]), ry(r[1], r[3]);
    const I d = (qx - px) * (ry - py) - (qy - py) * (rx - px);
    return d.inf() > 0 ? 1 : (d.sup() < 0 ? -1 : 0);
  };
  // Projected, a corner far from the cut (3.4e38 against points of size
  // 1e4) swamps the differences taken from it: the determinant is also
  // taken from the other two vertices (a cyclic turn keeps the sign), whose
  // differences to each other are small and exact-ish.
  auto orient_box = [&](std::uint32_t i, std::uint32_t j, std::uint32_t k) {
    int o = orient_from(i, j, k);
    if (o == 0 && projected) o = orient_from(j, k, i);
    if (o == 0 && projected) o = orient_from(k, i, j);
    return o;
  };
  // Points on an edge in their certified order along it (a coordinate in
  // which the edge is monotone; disjoint intervals).
  std::vector<std::uint32_t>& chain = scratch.chain;  // the boundary: corner, edge points, next corner, ...
  chain.clear();
  for (std::size_t q = 0; q < 3; ++q) {
    auto& list = on_edge[q];
    const Vec3d d = c[(q + 1) % 3] - c[q];
    const int ax = std::abs(d[u]) >= std::abs(d[v]) ? 0 : 1;  // projected coordinate along the edge
    const bool up = d[ax == 0 ? u : v] > 0;
    auto lo = [&](std::uint32_t i) {
      return up ? vert[i].box[static_cast<std::size_t>(ax)] : -vert[i].box[static_cast<std::size_t>(ax + 2)];
    };
    auto hi = [&](std::uint32_t i) {
      return up ? vert[i].box[static_cast<std::size_t>(ax + 2)] : -vert[i].box[static_cast<std::size_t>(ax)];
    };
    std::sort(list.begin(), list.end(),
              [&](std::uint32_t x, std::uint32_t y) { return lo(x) + hi(x) < lo(y) + hi(y); });
    for (std::size_t i = 0; i + 1 < list.size(); ++i)
      if (!(hi(list[i]) < lo(list[i + 1]))) return false;
    chain.push_back(static_cast<std::uint32_t>(q));
    chain.insert(chain.end(), list.begin(), list.end());
  }
  // The two-point split (SplitPattern): its key, and its record when known.
  int split_key = -1;
  std::size_t split_n = 0;
  thread_local std::array<SplitPattern, kSplitKeys> split_memo;
  if (!projected && vert.size() == 5 && by_key.size() == 2 && inside.empty() && constraints.size() == 1 &&
      direct_split_on.load(std::memory_order_relaxed)) {
    const auto& sg = constraints[0];
    const bool joined = (sg[0] == by_key[0].first && sg[1] == by_key[1].first) ||
                        (sg[0] == by_key[1].first && sg[1] == by_key[0].first);
    int qa = -1, qb = -1;
    for (int q = 0; q < 3; ++q)
      for (const std::uint32_t i : on_edge[static_cast<std::size_t>(q)]) (i == 3 ? qa : qb) = q;
    // Each point strictly inside its edge in doubles (not on a corner: CGAL
    // would merge it, a different sequence of operations).
    auto off_corners = [&](std::uint32_t i) {
      return frame[i] != frame[0] && frame[i] != frame[1] && frame[i] != frame[2];
    };
    if (joined && qa >= 0 && qb >= 0 && qa != qb && off_corners(3) && off_corners(4)) {
      // The corner the segment cuts off is the one the two edges share; the
      // quadrilateral left is (point 3, point 4, the other two corners).
      const int cut_corner = (qa + 1) % 3 == qb ? qb : qa;
      const Ki::Point_2 &o1 = frame[static_cast<std::size_t>((cut_corner + 1) % 3)],
                        &o2 = frame[static_cast<std::size_t>((cut_corner + 2) % 3)];
      const int circle = static_cast<int>(CGAL::side_of_oriented_circle(frame[3], frame[4], o1, o2)) + 1;
      split_key = (qa * 3 + qb) * 3 + circle;
      const SplitPattern& pat = split_memo[static_cast<std::size_t>(split_key)];
      if (pat.known) {
        const std::size_t before = out.size();
        for (const auto& tr : pat.tri) {
          if (orient_box(tr[0], tr[1], tr[2]) != pr.sign) {
            out.resize(before);
            return false;
          }
          out.push_back({vert[tr[0]].id, vert[tr[1]].id, vert[tr[2]].id});
        }
        direct_split_taken.fetch_add(1, std::memory_order_relaxed);
        return true;
      }
    }
  }
  try {
    Ct ct;
    std::vector<Ct::Vertex_handle> handle(vert.size());
    // Projected, the points go in as the exact path puts them in (corners,
    // each edge's points along it, then the inner points), so that with the
    // same predicate outcomes its triangles come out in the same order.
    // (Nothing is allocated for the frame's first try, the common case.)
    std::vector<std::uint32_t> insertion;
    std::vector<std::uint8_t> on_an_edge;
    if (projected) {
      insertion.assign({0u, 1u, 2u});
      for (const auto& list : on_edge) insertion.insert(insertion.end(), list.begin(), list.end());
      insertion.insert(insertion.end(), inside.begin(), inside.end());
      on_an_edge.assign(vert.size(), 0);
      for (std::size_t q = 0; q < 3; ++q)
        for (const std::uint32_t i : on_edge[q]) on_an_edge[i] = static_cast<std::uint8_t>(q + 1);
    }
    for (std::uint32_t n = 0; n < vert.size(); ++n) {
      const std::uint32_t i = projected ? insertion[n] : n;
      const std::size_t before = ct.number_of_vertices();
      if (projected && on_an_edge[i]) {
        // Into the rest of its edge, as the exact path does (the same
        // triangulation operations, so the same order of triangles).
        const std::size_t q = on_an_edge[i] - 1u;
        const auto& list = on_edge[q];
        const auto at = std::find(list.begin(), list.end(), i);
        const std::uint32_t prev = at == list.begin() ? static_cast<std::uint32_t>(q) : *(at - 1);
        Ct::Face_handle f;
        int j = 0;
        // Only a point on the edge in doubles (else the boundary
        // certificate could not hold: the exact path decides).
        const Ki::Point_2 &p0 = frame[prev], &p1 = frame[(q + 1) % 3];
        if (CGAL::orientation(p0, frame[i], p1) != CGAL::COLLINEAR ||
            !CGAL::collinear_are_strictly_ordered_along_line(p0, frame[i], p1) ||
            !ct.is_edge(handle[prev], handle[(q + 1) % 3], f, j))
          return false;
        handle[i] = ct.insert(frame[i], Ct::EDGE, f, j);
        handle[i]->info() = i;
        continue;
      }
      handle[i] = ct.insert(frame[i]);
      if (ct.number_of_vertices() == before) return false;  // two points coincide in doubles
      handle[i]->info() = i;
    }
    std::sort(by_key.begin(), by_key.end());
    auto find = [&](const PointKey& k) {
      const auto it = std::lower_bound(by_key.begin(), by_key.end(), std::pair{k, 0u});
      return it != by_key.end() && it->first == k ? it->second : kNil;
    };
    std::vector<std::array<std::uint32_t, 2>> seg;
    seg.reserve(constraints.size());
    for (const auto& sg : constraints) {
      const std::uint32_t i = find(sg[0]), j = find(sg[1]);
      if (i == kNil || j == kNil) return false;
      if (i == j) continue;
      ct.insert_constraint(handle[i], handle[j]);
      seg.push_back({i, j});
    }
    // Certificates. (1) Each cut segment is an edge (not split at a point
    // the doubles put on it).
    for (const auto& sg : seg) {
      Ct::Face_handle f;
      int j = 0;
      if (!ct.is_edge(handle[sg[0]], handle[sg[1]], f, j)) return false;
    }
    // (2) The boundary is the chain of the triangle's edges, in order.
    if (ct.number_of_vertices() != vert.size()) return false;
    std::size_t hull = 0;
    for (std::size_t i = 0; i < chain.size(); ++i) {
      Ct::Face_handle f;
      int j = 0;
      if (!ct.is_edge(handle[chain[i]], handle[chain[(i + 1) % chain.size()]], f, j)) return false;
      if (!ct.is_infinite(f) && !ct.is_infinite(f->neighbor(j))) return false;
      ++hull;
    }
    if (ct.infinite_vertex()->degree() != hull) return false;
    // (3) Every triangle certainly counter-clockwise for the exact points
    // (inside their boxes): with (2), the triangles tile the triangle (a
    // disk whose boundary goes once around is covered once by triangles of
    // one orientation), so the result is the exact path's up to the choice
    // of diagonals.
    const std::size_t before = out.size();
    for (auto f = ct.finite_faces_begin(); f != ct.finite_faces_end(); ++f) {
      const std::uint32_t i0 = f->vertex(0)->info(), i1 = f->vertex(1)->info(), i2 = f->vertex(2)->info();
      // Counter-clockwise in the frame is the triangle's own orientation,
      // which the projection shows with the sign pr.sign; counter-clockwise
      // in the projection is that orientation when pr.sign > 0.
      if (orient_box(i0, i1, i2) != (projected ? 1 : pr.sign)) {
        out.resize(before);
        return false;
      }
      if (projected && pr.sign < 0)
        out.push_back({vert[i0].id, vert[i2].id, vert[i1].id});
      else
        out.push_back({vert[i0].id, vert[i1].id, vert[i2].id});
      if (split_key >= 0) {
        if (split_n < 3)
          split_memo[static_cast<std::size_t>(split_key)].tri[split_n] = {
              static_cast<std::uint8_t>(i0), static_cast<std::uint8_t>(i1), static_cast<std::uint8_t>(i2)};
        ++split_n;
      }
    }
    if (split_key >= 0 && split_n == 3) split_memo[static_cast<std::size_t>(split_key)].known = true;
  } catch (const std::exception&) {
    return false;  // constraints cross in doubles: the exact path decides
  }
  return true;
}

namespace {

/// An edge through a triangle (key edge x face, either way round): the
/// edge's ends p, q and the triangle's corners c; false for other keys.
struct EdgeFace {
  const Vec3d *p, *q;
  std::array<const Vec3d*, 3> c;
};
bool edge_face_of(const TriMesh& a, const TriMesh& b, const PointKey& k, EdgeFace& out) noexcept {
  const bool edge_face = dim_of(k.a) == kDimEdge && dim_of(k.b) == kDimFace;
  if (!edge_face && !(dim_of(k.a) == kDimFace && dim_of(k.b) == kDimEdge)) return false;
  const TriMesh& me = edge_face ? a : b;
  const TriMesh& mf = edge_face ? b : a;
  const auto& ev = me.edge[idx_of(edge_face ? k.a : k.b)];
  const auto& tv = mf.tri[idx_of(edge_face ? k.b : k.a)];
  out = {&me.p[ev[0]], &me.p[ev[1]], {&mf.p[tv[0]], &mf.p[tv[1]], &mf.p[tv[2]]}};
  return true;
}

}  // namespace

PointBox point_box(const TriMesh& a, const TriMesh& b, const PointKey& k) noexcept {
  // An edge through a triangle (the common point of a cut): x = p + t (q -
  // p) with t = o_p / (o_p - o_q), o the orientations of the edge's ends
  // against the triangle, in interval arithmetic from the triangle's corner
  // (no constructed plane, whose offset cancels): bounds almost every point
  // tightly enough that the lazy kernel's exact fallback is not needed.
  PointBox out;
  using I = CGAL::Interval_nt<true>;
  if (dim_of(k.a) == kDimEdge && dim_of(k.b) == kDimEdge) {
    // Two edges meeting in one point: x = p + s d1, s = ((r - p) x d2) . n
    // / (n . n), n = d1 x d2 (not zero: the lines are not parallel).
    const auto& ea = a.edge[idx_of(k.a)];
    const auto& eb = b.edge[idx_of(k.b)];
    const Vec3d &p = a.p[ea[0]], &q = a.p[ea[1]], &r = b.p[eb[0]], &w = b.p[eb[1]];
    std::array<I, 3> d1, d2, rp;
    for (std::size_t j = 0; j < 3; ++j) {
      d1[j] = I(q[static_cast<int>(j)]) - I(p[static_cast<int>(j)]);
      d2[j] = I(w[static_cast<int>(j)]) - I(r[static_cast<int>(j)]);
      rp[j] = I(r[static_cast<int>(j)]) - I(p[static_cast<int>(j)]);
    }
    auto cross = [](const std::array<I, 3>& x, const std::array<I, 3>& y) {
      return std::array<I, 3>{x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
    };
    const auto n = cross(d1, d2), m = cross(rp, d2);
    const I nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (!(nn.inf() > 0)) return out;
    const I sv = (m[0] * n[0] + m[1] * n[1] + m[2] * n[2]) / nn;
    for (std::size_t j = 0; j < 3; ++j) {
      const I xj = I(p[static_cast<int>(j)]) + sv * d1[j];
      if (!std::isfinite(xj.inf()) || !std::isfinite(xj.sup())) return out;
      out.b[j] = xj.inf();
      out.b[j + 3] = xj.sup();
    }
    out.ok = true;
    return out;
  }
  EdgeFace ef;
  if (!edge_face_of(a, b, k, ef)) return out;
  const Vec3d &p = *ef.p, &q = *ef.q, &c0 = *ef.c[0], &c1 = *ef.c[1], &c2 = *ef.c[2];
  std::array<I, 3> u, v, wp, wq;
  for (int j = 0; j < 3; ++j) {
    u[static_cast<std::size_t>(j)] = I(c1[j]) - I(c0[j]);
    v[static_cast<std::size_t>(j)] = I(c2[j]) - I(c0[j]);
    wp[static_cast<std::size_t>(j)] = I(p[j]) - I(c0[j]);
    wq[static_cast<std::size_t>(j)] = I(q[j]) - I(c0[j]);
  }
  const I n0 = u[1] * v[2] - u[2] * v[1], n1 = u[2] * v[0] - u[0] * v[2], n2 = u[0] * v[1] - u[1] * v[0];
  const I op = n0 * wp[0] + n1 * wp[1] + n2 * wp[2];
  const I oq = n0 * wq[0] + n1 * wq[1] + n2 * wq[2];
  const I den = op - oq;
  if (!(den.inf() > 0 || den.sup() < 0)) return out;
  const I t = op / den;
  for (int j = 0; j < 3; ++j) {
    const I xj = I(p[j]) + t * (I(q[j]) - I(p[j]));
    if (!std::isfinite(xj.inf()) || !std::isfinite(xj.sup())) return out;
    out.b[static_cast<std::size_t>(j)] = xj.inf();
    out.b[static_cast<std::size_t>(j + 3)] = xj.sup();
  }
  out.ok = true;
  return out;
}

namespace {

/// x = num / den rounded to nearest (ties to even, as centre() rounds them),
/// from a first guess: the guess moves by one ulp until num / den lies
/// between the midpoints to its neighbours, every comparison exact (the
/// midpoints are dyadic, so Mpzf holds them and den times them exactly).
/// False when the guess is not finite or wanders (the caller goes exact).
bool round_quotient(CGAL::Mpzf num, CGAL::Mpzf den, double guess, double& out) {
  if (den.sign() == 0 || !std::isfinite(guess)) return false;
  if (den.sign() < 0) {
    num = -num;
    den = -den;
  }
  // num / den against the midpoint (lo + c) / 2 is 2 num against
  // den (lo + c): one exact product per comparison instead of two.
  const CGAL::Mpzf num2 = num + num;
  double c = guess;
  for (int step = 0; step < 16; ++step) {
    const double lo = std::nextafter(c, -HUGE_VAL), hi = std::nextafter(c, HUGE_VAL);
    if (!std::isfinite(lo) || !std::isfinite(hi)) return false;
    const int below = Mpzf_cmp(num2, den * (CGAL::Mpzf(lo) + CGAL::Mpzf(c)));
    if (below < 0) {
      c = lo;
      continue;
    }
    if (below == 0) {
      out = centre(lo, c) + 0.0;
      return true;
    }
    const int above = Mpzf_cmp(num2, den * (CGAL::Mpzf(c) + CGAL::Mpzf(hi)));
    if (above > 0) {
      c = hi;
      continue;
    }
    if (above == 0) {
      out = centre(c, hi) + 0.0;
      return true;
    }
    out = c + 0.0;  // an exact zero is +0, as the rational's interval gives it
    return true;
  }
  return false;
}

/// The new point k rounded to nearest in each coordinate, the same doubles
/// as the lazy kernel's exact value rounded (the intersection of a line and
/// a plane or of two lines is one point, however it is written), from its
/// closed form in Mpzf (exact sums and products of doubles, no gcd, no
/// allocation for short numbers): an edge through a triangle is
/// x = (o_p q - o_q p) / (o_p - o_q), o the orientations of the edge's ends
/// against the triangle; two edges meeting are x = p + s d1 with
/// s = ((r - p) x d2) . n / (n . n), n = d1 x d2. The guess is the
/// quotient in doubles (the box's centre where that overflows). False when
/// a guess is not finite or a rounding wanders (the caller goes exact).
bool rounded_point(const TriMesh& a, const TriMesh& b, const PointKey& k, const PointBox& box, Vec3d& out) {
  using Z = CGAL::Mpzf;
  auto diff = [](const Vec3d& x, const Vec3d& y) {
    return std::array<Z, 3>{Z(x[0]) - Z(y[0]), Z(x[1]) - Z(y[1]), Z(x[2]) - Z(y[2])};
  };
  auto cross = [](const std::array<Z, 3>& x, const std::array<Z, 3>& y) {
    return std::array<Z, 3>{x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
  };
  auto dot = [](const std::array<Z, 3>& x, const std::array<Z, 3>& y) {
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
  };
  std::array<Z, 3> num;
  Z den;
  if (dim_of(k.a) == kDimEdge && dim_of(k.b) == kDimEdge) {
    const auto& ea = a.edge[idx_of(k.a)];
    const auto& eb = b.edge[idx_of(k.b)];
    const Vec3d &p = a.p[ea[0]], &q = a.p[ea[1]], &r = b.p[eb[0]], &w = b.p[eb[1]];
    const auto d1 = diff(q, p), d2 = diff(w, r);
    const auto n = cross(d1, d2);
    den = dot(n, n);
    const Z s = dot(cross(diff(r, p), d2), n);
    for (std::size_t j = 0; j < 3; ++j) num[j] = Z(p[static_cast<int>(j)]) * den + s * d1[j];
  } else {
    EdgeFace ef;
    if (!edge_face_of(a, b, k, ef)) return false;
    const Vec3d &p = *ef.p, &q = *ef.q, &c0 = *ef.c[0];
    // A triangle in a plane of constant coordinate (Cray's slab): exact
    // expansions of a degree-2 form instead of Mpzf (round_exact.cpp).
    for (int j = 0; j < 3; ++j)
      if (c0[j] == (*ef.c[1])[j] && c0[j] == (*ef.c[2])[j]) {
        if (round_edge_through_level_plane(p, q, j, c0[j], out)) return true;
        break;
      }
    const auto n = cross(diff(*ef.c[1], c0), diff(*ef.c[2], c0));
    const Z op = dot(n, diff(p, c0)), oq = dot(n, diff(q, c0));
    den = op - oq;
    for (std::size_t j = 0; j < 3; ++j) num[j] = op * Z(q[static_cast<int>(j)]) - oq * Z(p[static_cast<int>(j)]);
  }
  for (std::size_t j = 0; j < 3; ++j) {
    double guess = num[j].to_double() / den.to_double();  // a few ulps off
    if (!std::isfinite(guess) && box.ok) guess = centre(box.b[j], box.b[j + 3]);
    if (!round_quotient(num[j], den, guess, out[static_cast<int>(j)])) return false;
  }
  return true;
}

}  // namespace

bool rounded_box(const TriMesh& a, const TriMesh& b, const PointKey& k, PointBox& box, Vec3d& x) {
  // point_coordinates' choice: a pinned edge-face point keeps its box.
  const bool edge_face = dim_of(k.a) == kDimFace || dim_of(k.b) == kDimFace;
  if (edge_face && box.ok && pinned(box.b[0], box.b[3]) && pinned(box.b[1], box.b[4]) && pinned(box.b[2], box.b[5]))
    return false;
  if (!rounded_point(a, b, k, box, x)) return false;
  // x is the exact value rounded to nearest: the exact value lies within
  // its neighbours.
  for (int j = 0; j < 3; ++j) {
    const auto lo = static_cast<std::size_t>(j), hi = static_cast<std::size_t>(j + 3);
    double l = std::nextafter(x[j], -HUGE_VAL), h = std::nextafter(x[j], HUGE_VAL);
    if (box.ok) {
      l = std::max(l, box.b[lo]);
      h = std::min(h, box.b[hi]);
    }
    box.b[lo] = l;
    box.b[hi] = h;
  }
  box.ok = true;
  return true;
}

Vec3d point_coordinates(const TriMesh& a, const TriMesh& b, const PointKey& k, const PointBox& box,
                        const ExactPoints& exact, std::size_t index) {
  // An edge through a triangle with a pinned box takes the box's centre;
  // any other point its exact value rounded to nearest, always evaluated (a
  // lazy number's interval depends on whether a predicate has already
  // forced its exact value: the output must not).
  const bool edge_face = dim_of(k.a) == kDimFace || dim_of(k.b) == kDimFace;
  if (edge_face && box.ok && pinned(box.b[0], box.b[3]) && pinned(box.b[1], box.b[4]) && pinned(box.b[2], box.b[5]))
    return {centre(box.b[0], box.b[3]), centre(box.b[1], box.b[4]), centre(box.b[2], box.b[5])};
  if (Vec3d x; rounded_point(a, b, k, box, x)) return x;
  const Ke::Point_3 pt = index < exact.p.size() && exact.ok[index] ? exact.p[index] : exact_point(a, b, k);
  auto coord = [&](const Ke::FT& x) {
    const auto& e = CGAL::exact(x);
    const std::pair<double, double> iv = CGAL::to_interval(e);
    if (!(iv.first < iv.second)) return iv.first;
    using Q = std::decay_t<decltype(e)>;
    const Q mid = (Q(iv.first) + Q(iv.second)) / 2;
    return e < mid ? iv.first : (mid < e ? iv.second : centre(iv.first, iv.second));
  };
  return {coord(pt.x()), coord(pt.y()), coord(pt.z())};
}

int winding_number(const TriMesh& m, const Bvh& bvh, const Vec3d& q) {
  return winding_any<Ki>(m, bvh, pi(q), q);
}

int winding_number_centroid(const TriMesh& m, const Bvh& bvh, const TriMesh& a, const TriMesh& b,
                            const std::array<PointKey, 3>& corners3, const std::array<const PointBox*, 3>& boxes) {
  // Certified first: the parity of the ray from the centroid's interval box
  // (the corners' boxes, or their exact doubles, averaged in intervals) is
  // the exact centroid's when every orientation is certain; the first
  // uncertain one sends the question to the lazy exact kernel.
  {
    using Iv = CGAL::Interval_nt<true>;
    using Kv = CGAL::Simple_cartesian<Iv>;
    std::array<Iv, 3> sum{Iv(0), Iv(0), Iv(0)};
    bool have = true;
    for (std::size_t k = 0; k < 3 && have; ++k) {
      const PointKey& key = corners3[k];
      const Vec3d* x = dim_of(key.a) == kDimVertex ? &a.p[idx_of(key.a)]
                                                   : (dim_of(key.b) == kDimVertex ? &b.p[idx_of(key.b)] : nullptr);
      for (std::size_t j = 0; j < 3 && have; ++j) {
        if (x != nullptr)
          sum[j] += Iv((*x)[static_cast<int>(j)]);
        else if (boxes[k] != nullptr && boxes[k]->ok)
          sum[j] += Iv(boxes[k]->b[j], boxes[k]->b[j + 3]);
        else
          have = false;
      }
    }
    if (have) {
      const Kv::Point_3 c(sum[0] / 3, sum[1] / 3, sum[2] / 3);
      const Vec3d cd(centre(c.x().inf(), c.x().sup()), centre(c.y().inf(), c.y().sup()),
                     centre(c.z().inf(), c.z().sup()));
      // Rounded upwards: |q - cd| <= spread for every q in the box.
      const double spread = std::max({c.x().sup() - cd.x(), cd.x() - c.x().inf(), c.y().sup() - cd.y(),
                                      cd.y() - c.y().inf(), c.z().sup() - cd.z(), cd.z() - c.z().inf()}) *
                            (1.0 + 0x1p-50);
      if (cd.allFinite() && std::isfinite(spread)) {
        try {
          return winding_any<Kv>(m, bvh, c, cd, spread);
        } catch (const CGAL::Uncertain_conversion_exception&) {
          // An orientation the intervals cannot decide: exact below.
        }
      }
    }
  }
  const Ke::Point_3 c =
      CGAL::centroid(exact_point(a, b, corners3[0]), exact_point(a, b, corners3[1]), exact_point(a, b, corners3[2]));
  const Vec3d cd(CGAL::to_double(c.x()), CGAL::to_double(c.y()), CGAL::to_double(c.z()));
  return winding_any<Ke>(m, bvh, c, cd);
}

int coplanar_orientation(const TriMesh& a, std::uint32_t ta, const TriMesh& b, std::uint32_t tb) {
  const auto ca = corners(a, ta), cb = corners(b, tb);
  const Projection pr = projection_of(ca[0], ca[1], ca[2]);
  return pr.sign * orient2(cb[0], cb[1], cb[2], pr.axis);
}

}  // namespace atelier::net_detail
