// The self-intersection check's pair traversal: first_self_crossing walks
// the net's box hierarchy against itself (skipping the inside of the
// patches embedded_nodes certifies, self_check.cpp) and decides each pair of
// triangles whose boxes overlap by certified floating-point rules, leaving
// only the pairs none of them can decide to the exact test
// (triangles_cross). Every rule answers "certainly apart" or "not known",
// so the verdict (the smallest crossing pair) is the exact one.
#include <atelier/engine/parallel.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "boolean_detail.h"

namespace atelier::net_detail {

namespace {

/// One triangle as the pair decisions read it (the box tests read the
/// hierarchy's own boxes): its corners, then its plane for the certified
/// side test: the rounded normal n = (b - a) x (c - a) and, per
/// component, the sum of the absolute values of its two products (the part
/// of Shewchuk's orient3d permanent that does not depend on the tested
/// point).
struct SelfTri {
  std::uint32_t v[3];
  double n[3];
  double nabs[3];
};

void self_tri(const TriMesh& m, std::uint32_t t, SelfTri& r) noexcept {
  const auto& v = m.tri[t];
  for (int k = 0; k < 3; ++k) r.v[k] = v[static_cast<std::size_t>(k)];
  const Vec3d& a = m.p[v[0]];
  const double ux = m.p[v[1]].x() - a.x(), uy = m.p[v[1]].y() - a.y(), uz = m.p[v[1]].z() - a.z();
  const double vx = m.p[v[2]].x() - a.x(), vy = m.p[v[2]].y() - a.y(), vz = m.p[v[2]].z() - a.z();
  r.n[0] = uy * vz - uz * vy;
  r.n[1] = uz * vx - ux * vz;
  r.n[2] = ux * vy - uy * vx;
  r.nabs[0] = std::abs(uy * vz) + std::abs(uz * vy);
  r.nabs[1] = std::abs(uz * vx) + std::abs(ux * vz);
  r.nabs[2] = std::abs(ux * vy) + std::abs(uy * vx);
}

// Without short-circuits: six independent comparisons whose outcome is
// unpredictable cost less than six branches.
bool self_nodes_meet(const std::array<double, 6>& x, const std::array<double, 6>& y) noexcept {
  return (x[0] <= y[3]) & (y[0] <= x[3]) & (x[1] <= y[4]) & (y[1] <= x[4]) & (x[2] <= y[5]) & (y[2] <= x[5]);
}

/// The side of p against x's plane through a (filtered_plane_side).
inline int self_side(const SelfTri& x, const Vec3d& a, const Vec3d& p) noexcept {
  return filtered_plane_side(x.n, x.nabs, a, p);
}

/// The axis along which triangle x's rounded normal is longest: the
/// projection that keeps it best.
int self_axis(const SelfTri& x) noexcept {
  const double a = std::abs(x.n[0]), b = std::abs(x.n[1]), c = std::abs(x.n[2]);
  return a >= b ? (a >= c ? 0 : 2) : (b >= c ? 1 : 2);
}

/// True when triangles x and y of one net certainly meet at most in the
/// corners and edge they share; false means "not known" (triangles_cross
/// decides exactly).
/// - The other one's corners that are not shared strictly on one side of
///   one triangle's plane (the exact test's first rejection).
/// - An edge pair (a fold meets beyond the edge only when coplanar with the
///   third corners on the same side of it): third corners certainly on
///   opposite sides of the edge, seen along an axis where x is not flat,
///   whether or not the four corners are coplanar (the two triangles of a
///   planar quad are coplanar up to rounding, which no plane filter
///   certifies).
/// - A vertex pair (sharing only the vertex v): both triangles
///   project along one axis with a certain orientation and a line through
///   v's image holds one triangle's edge from v, with the other triangle's
///   two far corners strictly on the far side of it. Then the projections
///   meet only in v's image, and a projection that keeps a triangle is
///   one-to-one on it, so the triangles meet only in v (coplanar pairs of
///   a split planar polygon included).
bool self_apart(const std::vector<Vec3d>& p, const SelfTri& x, const SelfTri& y) noexcept {
  // Which corners are shared: bit k of in_y when x's corner k is one of y's.
  unsigned in_y = 0, in_x = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (x.v[i] == y.v[j]) {
        in_y |= 1u << i;
        in_x |= 1u << j;
      }
  auto one_side = [&](const SelfTri& a, const SelfTri& b, unsigned shared_of_b) {
    const Vec3d& a0 = p[a.v[0]];
    int side = 0;
    for (int k = 0; k < 3; ++k) {
      if (shared_of_b >> k & 1u) continue;
      const int s = self_side(a, a0, p[b.v[k]]);
      if (s == 0 || (side != 0 && s != side)) return false;
      side = s;
    }
    return side != 0;  // the same triangle twice is no certificate
  };
  if (one_side(x, y, in_x) || one_side(y, x, in_y)) return true;
  const int shared = std::popcount(in_y);
  if (shared == 2) {
    const int ox = std::countr_zero(~in_y & 7u), oy = std::countr_zero(~in_x & 7u);  // the third corners
    const int axis = self_axis(x);
    const Vec3d& u = p[x.v[(ox + 1) % 3]];
    const Vec3d& w = p[x.v[(ox + 2) % 3]];
    const int sx = certified_orient2(u, w, p[x.v[ox]], axis);
    const int sy = certified_orient2(u, w, p[y.v[oy]], axis);
    return sx != 0 && sy != 0 && sx != sy;
  }
  if (shared == 1) {
    const int ix = std::countr_zero(in_y), iy = std::countr_zero(in_x);  // v in x and in y
    const Vec3d& v = p[x.v[ix]];
    const Vec3d &x1 = p[x.v[(ix + 1) % 3]], &x2 = p[x.v[(ix + 2) % 3]];
    const Vec3d &y1 = p[y.v[(iy + 1) % 3]], &y2 = p[y.v[(iy + 2) % 3]];
    const int axis = self_axis(x);
    const int sx = certified_orient2(v, x1, x2, axis);
    if (sx == 0 || certified_orient2(v, y1, y2, axis) == 0) return false;
    // A line through v and e (an edge's far corner) with the own
    // triangle's other far corner o on side s: apart when both of the other
    // triangle's far corners lie on side -s.
    auto separates = [&](const Vec3d& e, int s, const Vec3d& q1, const Vec3d& q2) {
      const int s1 = certified_orient2(v, e, q1, axis);
      return s1 == -s && certified_orient2(v, e, q2, axis) == -s;
    };
    const int sy = certified_orient2(v, y1, y2, axis);
    return separates(x1, sx, y1, y2) || separates(x2, -sx, y1, y2) || separates(y1, sy, x1, x2) ||
           separates(y2, -sy, x1, x2);
  }
  if (shared == 0) {
    // Disjoint projections along x's axis (an edge line of one triangle
    // with its third corner strictly on one side and the other triangle's
    // corners strictly on the other): a common point would project into
    // both. Decides coplanar pairs of a split planar polygon, which no
    // plane filter can.
    const int axis = self_axis(x);
    auto separated_by_edges = [&](const SelfTri& a, const SelfTri& b) {
      for (int k = 0; k < 3; ++k) {
        const Vec3d &e0 = p[a.v[k]], &e1 = p[a.v[(k + 1) % 3]];
        const int s = certified_orient2(e0, e1, p[a.v[(k + 2) % 3]], axis);
        if (s != 0 && certified_orient2(e0, e1, p[b.v[0]], axis) == -s &&
            certified_orient2(e0, e1, p[b.v[1]], axis) == -s && certified_orient2(e0, e1, p[b.v[2]], axis) == -s)
          return true;
      }
      return false;
    };
    return separated_by_edges(x, y) || separated_by_edges(y, x);
  }
  return false;
}

}  // namespace

std::array<std::uint32_t, 2> first_self_crossing(const TriMesh& m, const Bvh& bvh, const ExecContext& ctx) {
  const std::size_t nt = m.tri.size();
  if (bvh.nodes.empty() || nt == 0) return {kNil, kNil};
  // Per triangle, in the net's order (reading the corners in order; the
  // hierarchy's order would scatter the reads of a large net).
  std::vector<SelfTri> rec(nt);
  par::for_each_n(ctx, nt, [&](std::size_t t) { self_tri(m, static_cast<std::uint32_t>(t), rec[t]); });
  // Patches certified embedded (self_check.cpp) are not walked inside:
  // only their seams with each other are.
  const std::vector<std::uint8_t> skip = embedded_nodes(m, bvh, ctx);
  if (skip[0]) return {kNil, kNil};
  // Most box-overlapping pairs of a fine net are neighbours (about 6 of 7
  // per triangle share a corner): the certified rules reject almost all of
  // them; only the pairs they cannot decide see the exact test.
  using Pair = std::array<std::uint32_t, 2>;
  auto visit = [&](Pair& best, std::uint32_t i, std::uint32_t j) {
    std::uint32_t ti = bvh.order[i], tj = bvh.order[j];
    if (ti > tj) std::swap(ti, tj);
    if (Pair{ti, tj} < best && !self_apart(m.p, rec[ti], rec[tj]) && triangles_cross(m, ti, tj)) best = {ti, tj};
  };
  using NodePair = std::array<std::uint32_t, 2>;
  auto leaf = [&](std::uint32_t n) { return bvh.nodes[n].left == kNil; };
  // Children to visit for a node pair (unordered pairs only).
  auto expand = [&](const NodePair& np, auto&& push) {
    const Bvh::Node& x = bvh.nodes[np[0]];
    const Bvh::Node& y = bvh.nodes[np[1]];
    if (np[0] == np[1]) {
      if (!skip[x.left]) push({x.left, x.left});
      push({x.left, x.left + 1});
      if (!skip[x.left + 1]) push({x.left + 1, x.left + 1});
      return;
    }
    // Split the node holding more triangles (a leaf never): halves the
    // boxes on both sides alike, so fewer node pairs overlap.
    // The order within a pair does not matter here (both are this net's).
    const bool split_x = x.left != kNil && (y.left == kNil || x.count >= y.count);
    const std::uint32_t half = split_x ? x.left : y.left, other = split_x ? np[1] : np[0];
    push({half, other});
    push({half + 1, other});
  };
  auto leaf_pairs = [&](const NodePair& np, Pair& best) {
    const Bvh::Node& x = bvh.nodes[np[0]];
    const Bvh::Node& y = bvh.nodes[np[1]];
    const bool same = np[0] == np[1];
    for (std::uint32_t i = x.first; i < x.first + x.count; ++i) {
      // A triangle whose box misses the other leaf's box meets none of its
      // triangles: one test instead of one per triangle there.
      if (!same && !self_nodes_meet(bvh.box[i], y.box)) continue;
      // The box tests first, into a mask (leaves hold at most 8 triangles;
      // inner nodes come here only when both are leaves): their outcomes
      // are unpredictable, so no branch per test.
      const std::uint32_t j0 = same ? i + 1 : y.first, j1 = y.first + y.count;
      std::uint32_t mask = 0;
      const std::array<double, 6>& bi = bvh.box[i];
      for (std::uint32_t j = j0; j < j1; ++j)
        mask |= static_cast<std::uint32_t>(self_nodes_meet(bi, bvh.box[j])) << (j - j0);
      for (; mask != 0; mask &= mask - 1) visit(best, i, j0 + static_cast<std::uint32_t>(std::countr_zero(mask)));
    }
  };
  auto both_leaves = [&](const NodePair& np) { return leaf(np[0]) && leaf(np[1]); };
  // One depth-first walk of the node pairs whose boxes overlap, handing
  // each pair of leaves to `at_leaves`.
  auto walk = [&](auto&& at_leaves) {
    std::vector<NodePair> stack{{0, 0}};
    while (!stack.empty()) {
      const NodePair np = stack.back();
      stack.pop_back();
      if (both_leaves(np)) {
        at_leaves(np);
        continue;
      }
      expand(np, [&](const NodePair& ch) {
        if (self_nodes_meet(bvh.nodes[ch[0]].box, bvh.nodes[ch[1]].box)) stack.push_back(ch);
      });
    }
  };
  Pair best{kNil, kNil};
  if (par::run_sequential(ctx, nt)) {
    // One thread: each pair of leaves as the walk meets it (a small net's
    // check is a fraction of a millisecond; a task list would only cost).
    walk([&](const NodePair& np) { leaf_pairs(np, best); });
    return best;
  }
  // Several threads: the pairs of leaves as a flat list, decided in
  // parallel, each with its own smallest crossing pair; their minimum is the
  // same for any thread count.
  std::vector<NodePair> leaves;
  walk([&](const NodePair& np) { leaves.push_back(np); });
  std::vector<Pair> found(leaves.size(), Pair{kNil, kNil});
  par::for_each_n(ctx, leaves.size(), [&](std::size_t k) { leaf_pairs(leaves[k], found[k]); });
  for (const Pair& f : found) best = std::min(best, f);
  return best;
}

}  // namespace atelier::net_detail
