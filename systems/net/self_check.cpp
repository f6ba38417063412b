// The self-intersection check's embedded patches: nodes of a net's box
// hierarchy whose triangles certainly do not cross one another, so the
// pair traversal of first_self_crossing (self_check_pairs.cpp) skips the node's
// pairs with itself and only walks the seams between such patches.
//
// The certificate (Volino and Magnenat-Thalmann's self-collision culling by
// normal cones and contours, made exact): a patch that is a topological
// disk, whose triangles all project along one coordinate axis with the same
// certain orientation, and whose boundary loop projects to a certainly
// simple polygon, projects one-to-one. Proof: the projection is a branched
// covering with positive local degree on the open disk; the number of
// preimages of a generic point counted with degree is the winding number
// of the projected boundary about it, 0 or 1 for a simple polygon, so no
// point has two preimages and there is no branching; near the boundary the
// image stays on the polygon's inner side, so a boundary point shares its
// image with no other point either. A one-to-one projection means the
// patch is embedded: two of its triangles meet exactly in the corners and
// edge they share, which is triangles_cross's "no". Every sign is a
// certified floating-point filter (Shewchuk's orient2d bound); where one
// cannot decide, the node is not certified and its pairs are tested as
// before, so the check's verdict (the smallest crossing pair) is unchanged.
#include <atelier/engine/parallel.h>

#include <algorithm>

#include "boolean_detail.h"

namespace atelier::net_detail {

namespace {

/// Nodes below this many triangles are not certified: their pairs cost
/// less than the certificate.
constexpr std::uint32_t kMinPatch = 64;
/// A node whose triangles have more boundary loops is not certified.
constexpr std::size_t kMaxLoops = 16;

/// Bit 2k: the triangle certainly projects along axis k counter-clockwise;
/// bit 2k + 1: certainly clockwise.
std::uint8_t sign_mask(const TriMesh& m, std::uint32_t t) noexcept {
  const auto& v = m.tri[t];
  std::uint8_t mask = 0;
  for (int k = 0; k < 3; ++k) {
    const int s = certified_orient2(m.p[v[0]], m.p[v[1]], m.p[v[2]], k);
    if (s != 0) mask |= static_cast<std::uint8_t>(1u << (2 * k + (s > 0 ? 0 : 1)));
  }
  return mask;
}

/// Boundary loops of a node's triangles (`pos`: each triangle's place in
/// the hierarchy's order), as corners in order (loop k is corners
/// [start[k], start[k + 1])), when the triangles form disks touching at
/// most at vertices. A vertex where the triangles form k > 1 fans (k
/// outgoing boundary edges: pinched) counts as k vertices, one per fan,
/// and a loop entering it leaves along its own fan (found by turning about
/// the vertex inside the node). Then, with V counted so, V - E + F must
/// equal the number of loops, and no loop may pass a vertex twice. Each
/// component is then a disk: none is closed (a closed surface cannot
/// project with one orientation, which the caller requires), so each has a
/// loop, and with c components, b >= c loops and total genus g,
/// V - E + F = 2c - 2g - b = b forces g = 0 and b = c.
bool disk_loops(const TriMesh& m, const Bvh& bvh, std::span<const std::uint32_t> pos,
                std::span<const std::uint32_t> first_tri, const Bvh::Node& node, std::vector<std::uint32_t>& loop,
                std::vector<std::uint32_t>& start) {
  const std::uint32_t lo = node.first, hi = node.first + node.count;
  auto inside = [&](std::uint32_t t) { return t != kNil && pos[t] >= lo && pos[t] < hi; };
  struct Edge {
    std::uint32_t tail, head, tri;
  };
  std::vector<Edge> bnd;  // as the node's triangle runs it
  for (std::uint32_t i = lo; i < hi; ++i) {
    const std::uint32_t t = bvh.order[i];
    for (std::size_t k = 0; k < 3; ++k) {
      const auto& et = m.edge_tri[m.tri_edge[t][k]];
      if (!inside(et[0] == t ? et[1] : et[0])) bnd.push_back({m.tri[t][k], m.tri[t][(k + 1) % 3], t});
    }
  }
  if (bnd.size() < 3) return false;
  auto by_tail = [](const Edge& x, const Edge& y) { return x.tail != y.tail ? x.tail < y.tail : x.head < y.head; };
  std::sort(bnd.begin(), bnd.end(), by_tail);
  auto find = [&](std::uint32_t tail, std::uint32_t head) {
    const auto it = std::lower_bound(bnd.begin(), bnd.end(), Edge{tail, head, 0}, by_tail);
    return it != bnd.end() && it->tail == tail && it->head == head ? static_cast<std::size_t>(it - bnd.begin())
                                                                   : bnd.size();
  };
  // The boundary edge leaving v after the one entering it in triangle t:
  // turn about v through the node's triangles (each turn crosses the edge
  // from v to the next corner) until that edge is on the boundary.
  auto leave = [&](std::uint32_t v, std::uint32_t t) {
    for (std::size_t turns = 0; turns <= m.tri.size(); ++turns) {
      const auto& c = m.tri[t];
      const std::size_t kv = c[0] == v ? 0 : (c[1] == v ? 1 : 2);
      const auto& et = m.edge_tri[m.tri_edge[t][kv]];
      const std::uint32_t other = et[0] == t ? et[1] : et[0];
      if (!inside(other)) return find(v, c[(kv + 1) % 3]);
      t = other;
    }
    return bnd.size();
  };
  loop.clear();
  start.assign(1, 0);
  std::vector<std::uint8_t> used(bnd.size(), 0);
  for (std::size_t first = 0; first < bnd.size(); ++first) {
    if (used[first]) continue;
    std::size_t at = first;
    do {
      used[at] = 1;
      loop.push_back(bnd[at].tail);
      at = leave(bnd[at].head, bnd[at].tri);
      if (at == bnd.size()) return false;
    } while (!used[at]);
    if (at != first) return false;
    start.push_back(static_cast<std::uint32_t>(loop.size()));
    if (start.size() > kMaxLoops + 1) return false;  // the nesting test is quadratic in the loops
  }
  for (std::size_t l = 0; l + 1 < start.size(); ++l) {  // no loop passes a vertex twice
    std::vector<std::uint32_t> c(loop.begin() + start[l], loop.begin() + start[l + 1]);
    std::sort(c.begin(), c.end());
    if (std::adjacent_find(c.begin(), c.end()) != c.end()) return false;
  }
  // Vertices, a pinched one once per fan: one per boundary edge (its
  // tail), and the inner ones (no boundary edge leaves them), each counted
  // at its first triangle in the net, which is in the node with all the
  // others around it.
  std::int64_t v = static_cast<std::int64_t>(bnd.size());
  for (std::uint32_t i = lo; i < hi; ++i) {
    const std::uint32_t t = bvh.order[i];
    for (std::uint32_t c : m.tri[t]) {
      if (first_tri[c] != t) continue;
      const auto it = std::lower_bound(bnd.begin(), bnd.end(), Edge{c, 0, 0}, by_tail);
      v += it == bnd.end() || it->tail != c;
    }
  }
  const auto f = static_cast<std::int64_t>(node.count), b = static_cast<std::int64_t>(bnd.size());
  const auto loops = static_cast<std::int64_t>(start.size() - 1);
  return (3 * f + b) % 2 == 0 && v - (3 * f + b) / 2 + f == loops;
}

/// True when q (projected along `axis`) is certainly inside the projected
/// loop: crossings of the ray from q along the first projected coordinate,
/// each edge taken over the half-open span of the second (exact
/// comparisons), the side of the crossing by a certified orientation.
/// `inside` is set only when every crossing is certified.
bool certified_inside(const TriMesh& m, std::span<const std::uint32_t> loop, const Vec3d& q, int axis, bool& inside) {
  const int cy = (axis + 2) % 3;
  const std::size_t n = loop.size();
  bool odd = false;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d &a = m.p[loop[i]], &b = m.p[loop[(i + 1) % n]];
    if ((a[cy] > q[cy]) == (b[cy] > q[cy])) continue;
    // The edge crosses q's line; it is on the ray's side when q is on its
    // left going upwards (or its right going downwards).
    const int s = certified_orient2(a, b, q, axis);
    if (s == 0) return false;
    if ((s > 0) == (b[cy] > a[cy])) odd = !odd;
  }
  inside = odd;
  return true;
}

/// True when the angle at v between v -> a and v -> b (projected along
/// `axis`) is certainly obtuse: the two edges then meet only at v even when
/// they are collinear (a boundary running straight on, as along a meridian
/// seen from its pole). (a - v) . (b - v) < 0 by the orient2d bound: the
/// same two products of rounded differences, added instead of subtracted.
bool certified_obtuse(const Vec3d& v, const Vec3d& a, const Vec3d& b, int axis) noexcept {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const double left = (a[i] - v[i]) * (b[i] - v[i]), right = (a[j] - v[j]) * (b[j] - v[j]);
  const double dot = left + right, sum = std::abs(left) + std::abs(right);
  constexpr double kBound = 3.3306690738754716e-16;  // (3 + 16 eps) eps
  if (!(sum > 1e-280) || !(sum < std::numeric_limits<double>::infinity())) return false;
  return -dot > kBound * sum;
}

/// True when direction v -> x lies certainly strictly inside the angle
/// swept counter-clockwise from v -> p to v -> q (p, q not collinear with v).
bool in_angle(const Vec3d& v, const Vec3d& p, const Vec3d& q, const Vec3d& x, int axis, bool& certain) {
  const int pq = certified_orient2(v, p, q, axis), px = certified_orient2(v, p, x, axis),
            xq = certified_orient2(v, x, q, axis);
  certain = pq != 0 && px != 0 && xq != 0;
  return pq > 0 ? (px > 0 && xq > 0) : (px > 0 || xq > 0);
}

/// True when the loops projected along `axis` bound certainly disjoint
/// regions (each component's image, on the left of its loop when `sign` is
/// +1): consecutive edges turn certainly or go certainly on (an obtuse
/// angle); edges sharing a corner otherwise
/// (loops touching at a pinched vertex) are not collinear there, and each
/// loop's angle at the vertex holds neither edge of the other; every two
/// other edges have disjoint boxes or one's ends lie certainly on one side
/// of the other's line (edges swept in order of their lower end along the
/// first projected coordinate); and of two loops that do not touch, neither
/// holds the other's first corner.
bool simple_projection(const TriMesh& m, std::span<const std::uint32_t> loop, std::span<const std::uint32_t> start,
                       int axis, int sign) {
  const std::size_t n = loop.size(), loops = start.size() - 1;
  std::vector<std::uint32_t> next(n), prev(n), of(n);  // the corner after and before each, its loop
  for (std::size_t l = 0; l < loops; ++l)
    for (std::uint32_t i = start[l]; i < start[l + 1]; ++i) {
      next[i] = i + 1 < start[l + 1] ? i + 1 : start[l];
      prev[next[i]] = i;
      of[i] = static_cast<std::uint32_t>(l);
    }
  auto at = [&](std::size_t i) -> const Vec3d& { return m.p[loop[i]]; };
  for (std::size_t i = 0; i < n; ++i)
    if (certified_orient2(at(i), at(next[i]), at(next[next[i]]), axis) == 0 &&
        !certified_obtuse(at(next[i]), at(i), at(next[next[i]]), axis))
      return false;
  // Corners shared by two loops: the loops touch there.
  std::vector<std::uint8_t> touch(loops * loops, 0);
  {
    std::vector<std::uint32_t> by(n);
    for (std::uint32_t i = 0; i < n; ++i) by[i] = i;
    std::sort(by.begin(), by.end(), [&](std::uint32_t x, std::uint32_t y) { return loop[x] < loop[y]; });
    for (std::size_t r = 0; r < n;) {
      std::size_t e = r;
      while (e < n && loop[by[e]] == loop[by[r]]) ++e;
      for (std::size_t x = r; x < e; ++x)
        for (std::size_t y = r; y < e; ++y) {
          if (x == y) continue;
          const std::uint32_t i = by[x], j = by[y];  // the same vertex in loops of i and j
          touch[of[i] * loops + of[j]] = 1;
          // Loop i's region at the vertex: counter-clockwise from the edge
          // leaving it to the edge entering it (mirrored for sign -1).
          const Vec3d& out = at(next[i]);
          const Vec3d& in = at(prev[i]);
          for (const Vec3d* x2 : {&at(next[j]), &at(prev[j])}) {
            bool certain = false;
            const bool held =
                sign > 0 ? in_angle(at(i), out, in, *x2, axis, certain) : in_angle(at(i), in, out, *x2, axis, certain);
            if (!certain || held) return false;
          }
        }
      r = e;
    }
  }
  const int cx = (axis + 1) % 3, cy = (axis + 2) % 3;
  struct Seg {
    double x0, x1, y0, y1;
    std::uint32_t i;
  };
  std::vector<Seg> seg(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d &a = at(i), &b = at(next[i]);
    seg[i] = {std::min(a[cx], b[cx]), std::max(a[cx], b[cx]), std::min(a[cy], b[cy]), std::max(a[cy], b[cy]),
              static_cast<std::uint32_t>(i)};
  }
  std::sort(seg.begin(), seg.end(), [](const Seg& x, const Seg& y) { return x.x0 < y.x0; });
  for (std::size_t s = 0; s < n; ++s)
    for (std::size_t u = s + 1; u < n && seg[u].x0 <= seg[s].x1; ++u) {
      if (seg[u].y0 > seg[s].y1 || seg[s].y0 > seg[u].y1) continue;
      const std::uint32_t i = seg[s].i, j = seg[u].i;
      if (next[i] == j || next[j] == i) continue;  // consecutive: checked by the turns
      const std::uint32_t a0 = loop[i], a1 = loop[next[i]], b0 = loop[j], b1 = loop[next[j]];
      if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) {
        // One shared corner (a pinched vertex; two would be one edge, on
        // one side only): the edges meet only there unless collinear.
        const std::uint32_t v = (a0 == b0 || a0 == b1) ? a0 : a1;
        const std::uint32_t p = v == a0 ? a1 : a0, q = v == b0 ? b1 : b0;
        if (certified_orient2(m.p[v], m.p[p], m.p[q], axis) == 0) return false;
        continue;
      }
      const Vec3d &a = at(i), &b = at(next[i]), &c = at(j), &e = at(next[j]);
      const int s1 = certified_orient2(a, b, c, axis), s2 = certified_orient2(a, b, e, axis);
      if (s1 != 0 && s1 == s2) continue;
      const int s3 = certified_orient2(c, e, a, axis), s4 = certified_orient2(c, e, b, axis);
      if (s3 != 0 && s3 == s4) continue;
      return false;
    }
  for (std::size_t l = 0; l < loops; ++l)
    for (std::size_t k = 0; k < loops; ++k) {
      if (k == l || touch[l * loops + k]) continue;
      bool inside = false;
      if (!certified_inside(m, loop.subspan(start[l], start[l + 1] - start[l]), at(start[k]), axis, inside) || inside)
        return false;
    }
  return true;
}

}  // namespace

std::vector<std::uint8_t> embedded_nodes(const TriMesh& m, const Bvh& bvh, const ExecContext& ctx) {
  const std::size_t nn = bvh.nodes.size(), nt = m.tri.size();
  std::vector<std::uint8_t> out(nn, 0);
  if (nt < kMinPatch || nn == 0) return out;
  // Per triangle (in leaf order) its certain projected orientations; per
  // node the orientations all its triangles share.
  std::vector<std::uint8_t> tmask(nt);
  std::vector<std::uint32_t> pos(nt);
  par::for_each_n(ctx, nt, [&](std::size_t i) {
    tmask[i] = sign_mask(m, bvh.order[i]);
    pos[bvh.order[i]] = static_cast<std::uint32_t>(i);
  });
  std::vector<std::uint32_t> first_tri(m.p.size(), kNil);
  for (std::uint32_t t = static_cast<std::uint32_t>(nt); t-- > 0;)
    for (std::uint32_t c : m.tri[t]) first_tri[c] = t;
  std::vector<std::uint8_t> nmask(nn);
  for (std::size_t n = nn; n-- > 0;) {
    const Bvh::Node& node = bvh.nodes[n];
    if (node.left != kNil) {
      nmask[n] = nmask[node.left] & nmask[node.left + 1];
      continue;
    }
    std::uint8_t x = 0x3f;
    for (std::uint32_t i = node.first; i < node.first + node.count; ++i) x &= tmask[i];
    nmask[n] = x;
  }
  // Candidates top-down: the largest nodes with one orientation along an
  // axis; a candidate that fails hands on its children.
  std::vector<std::uint32_t> cand, stack;
  auto descend = [&](std::uint32_t root) {
    stack.assign(1, root);
    while (!stack.empty()) {
      const std::uint32_t x = stack.back();
      stack.pop_back();
      const Bvh::Node& node = bvh.nodes[x];
      if (node.count < kMinPatch) continue;
      if (nmask[x] != 0) {
        cand.push_back(x);
      } else if (node.left != kNil) {
        stack.push_back(node.left);
        stack.push_back(node.left + 1);
      }
    }
  };
  descend(0);
  ExecContext c = ctx;
  c.sequential_threshold = 2;
  c.grain = 1;
  while (!cand.empty()) {
    std::vector<std::uint8_t> ok(cand.size(), 0);
    par::for_each_n(c, cand.size(), [&](std::size_t k) {
      std::vector<std::uint32_t> loop, start;
      const Bvh::Node& node = bvh.nodes[cand[k]];
      if (!disk_loops(m, bvh, pos, first_tri, node, loop, start)) return;
      for (int axis = 0; axis < 3 && !ok[k]; ++axis)
        if (const unsigned bits = nmask[cand[k]] >> (2 * axis) & 3u;
            bits != 0 && simple_projection(m, loop, start, axis, bits == 1 ? 1 : -1))
          ok[k] = 1;
    });
    const std::vector<std::uint32_t> tried = std::move(cand);
    cand.clear();
    for (std::size_t k = 0; k < tried.size(); ++k) {
      const Bvh::Node& node = bvh.nodes[tried[k]];
      if (ok[k]) {
        out[tried[k]] = 1;
      } else if (node.left != kNil) {
        descend(node.left);
        descend(node.left + 1);
      }
    }
  }
  return out;
}

}  // namespace atelier::net_detail
