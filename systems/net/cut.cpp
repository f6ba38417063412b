// The cut of two nets along their intersection (seed 004 sections 2-3):
// candidate pairs, exact intersection points named by simplex keys, the
// exact re-triangulation of every cut triangle with both nets' points (so
// the intersection polygons are edges of both), and the pieces between the
// intersection polygons. Shared by the Booleans (boolean.cpp) and trimming
// (trim.cpp).
#include <atelier/engine/parallel.h>

#include <algorithm>
#include <array>
#include <bit>
#include <numeric>
#include <sstream>

#include "boolean_detail.h"

namespace atelier::net_detail {

namespace {

std::uint64_t edge_key(std::uint32_t u, std::uint32_t v) {
  return (std::uint64_t{std::min(u, v)} << 32) | std::max(u, v);
}

bool in_closure(const TriMesh& m, std::uint64_t s, std::uint32_t g) {
  switch (dim_of(s)) {
    case kDimFace:
      return idx_of(s) == g;
    case kDimEdge:
      return std::find(m.tri_edge[g].begin(), m.tri_edge[g].end(), idx_of(s)) != m.tri_edge[g].end();
    case kDimVertex:
      return std::find(m.tri[g].begin(), m.tri[g].end(), idx_of(s)) != m.tri[g].end();
    default:
      return false;
  }
}

/// LSD radix sort (8-bit digits) of keys below 2^bits: the order of
/// std::sort, in a few linear passes (cray16: the cut's edge sorts were 5-8%
/// of the prepared Cray Boolean).
void radix_sort(std::vector<std::uint64_t>& v, int bits, std::vector<std::uint64_t>& tmp) {
  tmp.resize(v.size());
  for (int shift = 0; shift < bits; shift += 8) {
    std::array<std::uint32_t, 257> count{};
    for (const std::uint64_t x : v) ++count[((x >> shift) & 0xff) + 1];
    for (std::size_t d = 1; d < count.size(); ++d) count[d] += count[d - 1];
    for (const std::uint64_t x : v) tmp[count[(x >> shift) & 0xff]++] = x;
    v.swap(tmp);
  }
}

/// Bits to hold every value below n (at least 1).
int bits_below(std::size_t n) {
  return std::max(1, static_cast<int>(std::bit_width(n > 0 ? n - 1 : 0)));
}

/// Sorts edge keys (u << 32 | w, u < w < n_ids) as std::sort would: packed
/// into 2 bits_below(n_ids) bits and radix sorted when that fits.
void sort_edge_keys_packed(std::vector<std::uint64_t>& e, std::size_t n_ids, std::vector<std::uint64_t>& tmp) {
  const int b = bits_below(n_ids);
  if (2 * b > 64 || e.size() < 64) {
    std::sort(e.begin(), e.end());
    return;
  }
  for (std::uint64_t& x : e) x = ((x >> 32) << b) | (x & 0xffffffffu);
  radix_sort(e, 2 * b, tmp);
  const std::uint64_t low = (std::uint64_t{1} << b) - 1;
  for (std::uint64_t& x : e) x = ((x >> b) << 32) | (x & low);
}

}  // namespace

Status cut_nets(const TriMesh& A, const Bvh& bvh_a, const TriMesh& B, const Bvh& bvh_b, const ExecContext& ctx,
                Cut& out, bool exact_only) {
  using Tri3 = std::array<std::uint32_t, 3>;
  new_orient3d_memo_generation();
  // ---- pairs and their intersection points
  const auto pairs = overlapping_pairs(A, bvh_a, B, bvh_b, ctx);
  out.candidate_pairs = pairs.size();
  std::vector<PairHit> hits(pairs.size());
  if (ctx.cancelled()) return {ErrorCode::kCancelled, "cut: cancelled"};
  par::for_each_n(ctx, pairs.size(), [&](std::size_t i) { intersect_pair(A, pairs[i][0], B, pairs[i][1], hits[i]); });
  if (ctx.cancelled()) return {ErrorCode::kCancelled, "cut: cancelled"};
  std::vector<std::uint32_t> met;
  for (std::uint32_t i = 0; i < pairs.size(); ++i)
    if (!hits[i].points.empty()) met.push_back(i);
  out.intersecting_pairs = met.size();

  const auto nA = static_cast<std::uint32_t>(A.p.size()), nB = static_cast<std::uint32_t>(B.p.size());
  PointIds ids;
  for (std::uint32_t i : met) ids.keys.insert(ids.keys.end(), hits[i].points.begin(), hits[i].points.end());
  par::sort(ctx, ids.keys.begin(), ids.keys.end(), std::less<>());
  ids.keys.erase(std::unique(ids.keys.begin(), ids.keys.end()), ids.keys.end());
  ids.id.resize(ids.keys.size());
  std::vector<PointKey> new_keys;
  for (std::size_t i = 0; i < ids.keys.size(); ++i) {
    const PointKey& k = ids.keys[i];
    if (dim_of(k.a) == kDimVertex) {
      ids.id[i] = idx_of(k.a);
    } else if (dim_of(k.b) == kDimVertex) {
      ids.id[i] = nA + idx_of(k.b);
    } else {
      ids.id[i] = nA + nB + static_cast<std::uint32_t>(new_keys.size());
      new_keys.push_back(k);
    }
  }

  const std::size_t n_ids = std::size_t{nA} + nB + new_keys.size();
  UnionFind merge(n_ids);
  for (const PointKey& k : ids.keys)
    if (dim_of(k.a) == kDimVertex && dim_of(k.b) == kDimVertex) merge.unite(idx_of(k.a), nA + idx_of(k.b));
  std::vector<std::uint32_t> canon(n_ids);
  for (std::uint32_t i = 0; i < n_ids; ++i) canon[i] = merge.find(i);
  // Which simplex of each net holds a (canonical) id; none when off that net.
  std::vector<std::uint64_t> on_a(n_ids, kNoSimplex), on_b(n_ids, kNoSimplex);
  for (std::uint32_t v = 0; v < nA; ++v) on_a[v] = simplex(kDimVertex, v);
  for (std::uint32_t v = 0; v < nB; ++v) on_b[canon[nA + v]] = simplex(kDimVertex, v);
  for (std::size_t i = 0; i < ids.keys.size(); ++i) {
    const std::uint32_t c = canon[ids.id[i]];
    on_a[c] = ids.keys[i].a;
    on_b[c] = ids.keys[i].b;
  }

  // ---- per net: cut triangles, their points and segments
  auto& sides = out.sides;
  sides[0].m = &A;
  sides[1].m = &B;
  sides[1].side = 1;
  sides[1].offset = nA;
  for (CutSide& s : sides) {
    s.slot.assign(s.m->tri.size(), kNil);
    for (std::uint32_t i : met) {
      const std::uint32_t t = pairs[i][static_cast<std::size_t>(s.side)];
      if (s.slot[t] == kNil) {
        s.slot[t] = 0;
      }
    }
    for (std::uint32_t t = 0; t < s.m->tri.size(); ++t)
      if (s.slot[t] != kNil) {
        s.slot[t] = static_cast<std::uint32_t>(s.cut.size());
        s.cut.push_back(t);
      }
    s.points.resize(s.cut.size());
    s.segments.resize(s.cut.size());
    s.coplanar_with.resize(s.cut.size());
    s.refined.resize(s.cut.size());
  }
  for (std::uint32_t i : met) {
    const std::uint32_t ta = pairs[i][0], tb = pairs[i][1];
    const PairHit& h = hits[i];
    const std::uint32_t ca = sides[0].slot[ta], cb = sides[1].slot[tb];
    sides[0].points[ca].insert(sides[0].points[ca].end(), h.points.begin(), h.points.end());
    sides[1].points[cb].insert(sides[1].points[cb].end(), h.points.begin(), h.points.end());
    if (!h.coplanar) {
      // The points of a non-coplanar pair are collinear (on the line of the
      // two planes): every pair of them is a cut segment of both triangles
      // (the triangulation splits a segment at the points on it).
      for (std::size_t x = 0; x < h.points.size(); ++x)
        for (std::size_t y = x + 1; y < h.points.size(); ++y) {
          sides[0].segments[ca].push_back({h.points[x], h.points[y]});
          sides[1].segments[cb].push_back({h.points[x], h.points[y]});
        }
      continue;
    }
    sides[0].coplanar_with[ca].push_back(tb);
    sides[1].coplanar_with[cb].push_back(ta);
    // Coplanar pair: the other triangle's edges, clipped, cut this one.
    for (CutSide& s : sides) {
      const TriMesh& other = s.side == 0 ? B : A;
      const std::uint32_t to = s.side == 0 ? tb : ta;
      const std::uint32_t c = s.slot[s.side == 0 ? ta : tb];
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t e = other.tri_edge[to][k];
        const std::uint32_t u = other.tri[to][k], w = other.tri[to][(k + 1) % 3];
        std::vector<PointKey> on;
        for (const PointKey& p : h.points) {
          const std::uint64_t so = s.side == 0 ? p.b : p.a;
          if (so == simplex(kDimEdge, e) || so == simplex(kDimVertex, u) || so == simplex(kDimVertex, w))
            on.push_back(p);
        }
        for (std::size_t x = 0; x < on.size(); ++x)
          for (std::size_t y = x + 1; y < on.size(); ++y) s.segments[c].push_back({on[x], on[y]});
      }
    }
  }

  // ---- re-triangulate the cut triangles, in parallel: the certified fast
  // path on the points' interval boxes first, the exact triangulation for
  // the triangles it cannot certify (docs/glossary.md, "certified fast path")
  const auto first_new = nA + nB;
  std::vector<PointBox> boxes(new_keys.size());
  par::for_each_n(ctx, new_keys.size(), [&](std::size_t i) { boxes[i] = point_box(A, B, new_keys[i]); });
  std::array<std::vector<std::uint8_t>, 2> slow;  // per side and cut triangle: left to the exact path
  for (CutSide& s : sides) {
    if (ctx.cancelled()) return {ErrorCode::kCancelled, "cut: cancelled"};
    auto& to_exact = slow[static_cast<std::size_t>(s.side)];
    to_exact.assign(s.cut.size(), 0);
    par::for_each_n(ctx, s.cut.size(), [&](std::size_t c) {
      auto& pts = s.points[c];
      std::sort(pts.begin(), pts.end());
      pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
      auto& seg = s.segments[c];
      for (auto& sg : seg)
        if (sg[1] < sg[0]) std::swap(sg[0], sg[1]);
      std::sort(seg.begin(), seg.end());
      seg.erase(std::unique(seg.begin(), seg.end()), seg.end());
      const std::uint32_t t = s.cut[c];
      bool trivial = true;  // only the triangle's own corners: nothing to cut
      for (const PointKey& k : pts) trivial &= dim_of(s.side == 0 ? k.a : k.b) == kDimVertex;
      auto& out = s.refined[c];
      if (trivial) {
        const auto& v = s.m->tri[t];
        out.push_back({v[0] + s.offset, v[1] + s.offset, v[2] + s.offset});
      } else if (exact_only || !refine_triangle_fast(A, B, s.side, t, pts, seg, ids, boxes, first_new, out)) {
        to_exact[c] = 1;
      }
    });
  }
  // Second try for the triangles left: their points' boxes narrowed to the
  // neighbours of the exactly rounded coordinates (rounded_box: Mpzf, no
  // lazy kernel; the same doubles point_coordinates gives, kept for it),
  // the triangulation on the projected centres first (a triangle much
  // larger than its cut, Cray's 3.4e38 slab against cut points of size 1e4,
  // whose interval boxes are ~1e23 wide and whose frame would merge them),
  // then in the frame. The certificates are the same.
  std::vector<std::uint8_t> rounded(new_keys.size(), 0);  // 1: rounded_box done, 2: also narrowed
  std::vector<Vec3d> rounded_at(new_keys.size());
  std::vector<PointBox> narrow;
  for (CutSide& s : sides)
    for (std::size_t c = 0; c < s.cut.size(); ++c) {
      if (!slow[static_cast<std::size_t>(s.side)][c]) continue;
      for (const PointKey& k : s.points[c]) {
        const std::uint32_t id = ids.find(k);
        if (id != kNil && id >= first_new) rounded[id - first_new] = 1;
      }
    }
  if (!exact_only && std::find(rounded.begin(), rounded.end(), std::uint8_t{1}) != rounded.end()) {
    narrow = boxes;
    par::for_each_n(ctx, new_keys.size(), [&](std::size_t i) {
      if (rounded[i]) rounded[i] = rounded_box(A, B, new_keys[i], narrow[i], rounded_at[i]) ? 2 : 0;
    });
    for (CutSide& s : sides) {
      auto& to_exact = slow[static_cast<std::size_t>(s.side)];
      par::for_each_n(ctx, s.cut.size(), [&](std::size_t c) {
        if (!to_exact[c]) return;
        const std::uint32_t t = s.cut[c];
        auto& out = s.refined[c];
        if (refine_triangle_fast(A, B, s.side, t, s.points[c], s.segments[c], ids, narrow, first_new, out, true) ||
            refine_triangle_fast(A, B, s.side, t, s.points[c], s.segments[c], ids, narrow, first_new, out))
          to_exact[c] = 0;
      });
    }
  }
  // The lazy exact points of the new points the exact path will use
  // (point_coordinates makes its own for a point its box does not pin).
  std::vector<std::uint8_t> need(new_keys.size(), 0);
  for (CutSide& s : sides)
    for (std::size_t c = 0; c < s.cut.size(); ++c) {
      if (!slow[static_cast<std::size_t>(s.side)][c]) continue;
      ++out.refined_exact;
      for (const PointKey& k : s.points[c]) {
        const std::uint32_t id = ids.find(k);
        if (id != kNil && id >= first_new) need[id - first_new] = 1;
      }
    }
  const ExactPointsPtr exact = make_exact_points(A, B, new_keys, need, ctx);
  for (CutSide& s : sides) {
    if (ctx.cancelled()) return {ErrorCode::kCancelled, "cut: cancelled"};
    const auto& to_exact = slow[static_cast<std::size_t>(s.side)];
    std::vector<Status> status(s.cut.size());
    par::for_each_n(ctx, s.cut.size(), [&](std::size_t c) {
      auto& out = s.refined[c];
      if (to_exact[c])
        status[c] = refine_triangle(A, B, s.side, s.cut[c], s.points[c], s.segments[c], ids, *exact, out);
      for (auto& tri : out)
        for (auto& v : tri) v = canon[v];
    });
    for (const Status& st : status)
      if (!st) return explain_by_crossing(st, A, bvh_a, B, bvh_b, ctx, 1 - s.side);
  }
  std::vector<Vec3d> new_points(new_keys.size());
  par::for_each_n(ctx, new_keys.size(), [&](std::size_t i) {
    new_points[i] = rounded[i] == 2 ? rounded_at[i] : point_coordinates(A, B, new_keys[i], boxes[i], *exact, i);
  });

  // ---- pieces, coplanar overlaps, components
  std::vector<std::uint64_t> sort_tmp;
  for (CutSide& s : sides) {
    for (const auto& r : s.refined)
      for (const Tri3& t : r)
        for (int k = 0; k < 3; ++k)
          s.edges.push_back(edge_key(t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)]));
    sort_edge_keys_packed(s.edges, n_ids, sort_tmp);
    s.edges.erase(std::unique(s.edges.begin(), s.edges.end()), s.edges.end());
  }
  for (CutSide& s : sides) {
    const TriMesh& m = *s.m;
    const TriMesh& other = s.side == 0 ? B : A;
    const std::vector<std::uint64_t>& on_other = s.side == 0 ? on_b : on_a;
    const std::vector<std::uint64_t>& other_edges = sides[1 - s.side].edges;
    const std::size_t nt = m.tri.size();
    s.piece_begin.resize(nt + 1);
    std::uint32_t count = 0;
    for (std::size_t t = 0; t < nt; ++t) {
      s.piece_begin[t] = count;
      count += s.slot[t] == kNil ? 1u : static_cast<std::uint32_t>(s.refined[s.slot[t]].size());
    }
    s.piece_begin[nt] = count;
    s.piece.resize(count);
    s.coplanar.assign(count, 0);
    par::for_each_n(ctx, nt, [&](std::size_t t) {
      const std::uint32_t p0 = s.piece_begin[t];
      if (s.slot[t] == kNil) {
        const auto& v = m.tri[t];
        s.piece[p0] = {canon[v[0] + s.offset], canon[v[1] + s.offset], canon[v[2] + s.offset]};
        return;
      }
      const std::uint32_t c = s.slot[t];
      const auto& r = s.refined[c];
      for (std::size_t i = 0; i < r.size(); ++i) {
        s.piece[p0 + i] = r[i];
        for (std::uint32_t g : s.coplanar_with[c]) {
          if (in_closure(other, on_other[r[i][0]], g) && in_closure(other, on_other[r[i][1]], g) &&
              in_closure(other, on_other[r[i][2]], g)) {
            s.coplanar[p0 + i] =
                static_cast<std::int8_t>(s.side == 0 ? coplanar_orientation(A, static_cast<std::uint32_t>(t), B, g)
                                                     : coplanar_orientation(B, static_cast<std::uint32_t>(t), A, g));
            break;
          }
        }
      }
    });
    // Components of pieces not separated by an edge of the other net.
    UnionFind uf(count);
    for (std::uint32_t t = 0; t < nt; ++t) {
      if (s.slot[t] != kNil) continue;
      for (std::uint32_t e : m.tri_edge[t]) {
        const std::uint32_t n = m.edge_tri[e][0] == t ? m.edge_tri[e][1] : m.edge_tri[e][0];
        if (n != kNil && s.slot[n] == kNil) uf.unite(s.piece_begin[t], s.piece_begin[n]);
      }
    }
    std::vector<std::pair<std::uint64_t, std::uint32_t>> local;  // (edge, piece) of cut triangles
    for (std::uint32_t t : s.cut)
      for (std::uint32_t p = s.piece_begin[t]; p < s.piece_begin[t + 1]; ++p)
        for (int k = 0; k < 3; ++k)
          local.emplace_back(
              edge_key(s.piece[p][static_cast<std::size_t>(k)], s.piece[p][static_cast<std::size_t>((k + 1) % 3)]), p);
    {
      // (edge, piece) pairs are distinct: any sort gives std::sort's order.
      // Packed as (u, w, piece) in one key and radix sorted when that fits.
      const int bi = bits_below(n_ids), bp = bits_below(count);
      if (2 * bi + bp <= 64 && local.size() >= 64) {
        std::vector<std::uint64_t> packed(local.size());
        for (std::size_t i = 0; i < local.size(); ++i)
          packed[i] = (((local[i].first >> 32) << (bi + bp)) | ((local[i].first & 0xffffffffu) << bp)) | local[i].second;
        radix_sort(packed, 2 * bi + bp, sort_tmp);
        const std::uint64_t lo_i = (std::uint64_t{1} << bi) - 1, lo_p = (std::uint64_t{1} << bp) - 1;
        for (std::size_t i = 0; i < local.size(); ++i) {
          const std::uint64_t x = packed[i];
          local[i] = {((x >> (bi + bp)) << 32) | ((x >> bp) & lo_i), static_cast<std::uint32_t>(x & lo_p)};
        }
      } else {
        std::sort(local.begin(), local.end());
      }
    }
    auto piece_tri = [&](std::uint32_t p) {
      return static_cast<std::uint32_t>(std::upper_bound(s.piece_begin.begin(), s.piece_begin.end(), p) -
                                        s.piece_begin.begin() - 1);
    };
    for (std::size_t i = 0; i < local.size();) {
      std::size_t j = i;
      while (j < local.size() && local[j].first == local[i].first) ++j;
      const std::uint64_t e = local[i].first;
      const bool cut_edge = std::binary_search(other_edges.begin(), other_edges.end(), e);
      std::uint32_t p = local[i].second, q = kNil;
      bool border = false;
      if (j - i == 2) {
        q = local[i + 1].second;
      } else if (j - i == 1) {
        // A whole edge of a cut triangle whose neighbour is not cut.
        const std::uint32_t t = piece_tri(p);
        for (std::uint32_t k = 0; k < 3; ++k) {
          const std::uint32_t u = canon[m.tri[t][k] + s.offset], w = canon[m.tri[t][(k + 1) % 3] + s.offset];
          if (edge_key(u, w) != e) continue;
          const std::uint32_t ed = m.tri_edge[t][k];
          const std::uint32_t n = m.edge_tri[ed][0] == t ? m.edge_tri[ed][1] : m.edge_tri[ed][0];
          if (n == kNil)
            border = true;  // the net's own boundary (open nets: trimming)
          else if (s.slot[n] == kNil)
            q = s.piece_begin[n];
        }
        if (border) {
          i = j;
          continue;
        }
        if (q == kNil)
          return explain_by_crossing(
              fail(ErrorCode::kInternal, "net boolean: refined net ", m.name, " has an unmatched edge"), A, bvh_a, B,
              bvh_b, ctx, 1 - s.side);
      } else {
        return explain_by_crossing(
            fail(ErrorCode::kInternal, "net boolean: refined net ", m.name, " has an edge in ", j - i, " triangles"), A,
            bvh_a, B, bvh_b, ctx, 1 - s.side);
      }
      if (!cut_edge && s.coplanar[p] == 0 && s.coplanar[q] == 0) uf.unite(p, q);
      i = j;
    }
    s.component.resize(count);
    for (std::uint32_t p = 0; p < count; ++p) s.component[p] = uf.find(p);
  }

  out.nA = nA;
  out.nB = nB;
  out.canon = std::move(canon);
  out.on_a = std::move(on_a);
  out.on_b = std::move(on_b);
  out.new_keys = std::move(new_keys);
  out.new_points = std::move(new_points);
  out.new_boxes = std::move(boxes);
  out.ids = std::move(ids);
  return {};
}

Status explain_by_crossing(Status st, const TriMesh& a, const Bvh& bvh_a, const TriMesh& b, const Bvh& bvh_b,
                           const ExecContext& ctx, int first) {
  if (st || st.code() != ErrorCode::kInternal) return st;
  for (int k = 0; k < 2; ++k) {
    const bool use_b = (k == 0) == (first == 1);
    const TriMesh& m = use_b ? b : a;
    if (m.tri.empty()) continue;
    const auto bad = first_self_crossing(m, use_b ? bvh_b : bvh_a, ctx);
    if (bad[0] != kNil)
      return fail(ErrorCode::kTopology, "net ", m.name, " intersects itself: faces ", m.face_of[bad[0]], " and ",
                  m.face_of[bad[1]], " cross (the cut failed: it is not defined for a net that crosses itself; ",
                  "check_self_intersection = false skips the test that refuses such a net up front)");
  }
  return st;
}

void emit_side(const Cut& cut, const TriMesh& a, const TriMesh& b, int side, const PolygonSoupView& soup, bool reverse,
               PolygonSoup& out, std::vector<std::uint32_t>& out_index, std::vector<std::uint8_t>& face_side) {
  const CutSide& s = cut.sides[side];
  const TriMesh& m = *s.m;
  auto use = [&](std::uint32_t id) {
    if (out_index[id] == kNil) {
      out_index[id] = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(cut.position(a, b, id));
    }
    return out_index[id];
  };
  std::vector<std::uint32_t> poly;
  for (std::size_t f = 0; f + 1 < m.face_tri_begin.size(); ++f) {
    const std::uint32_t t0 = m.face_tri_begin[f], t1 = m.face_tri_begin[f + 1];
    bool whole = t1 - t0 > 1;
    for (std::uint32_t t = t0; t < t1 && whole; ++t) whole = s.slot[t] == kNil;
    if (whole) {
      if (!s.keep[s.piece_begin[t0]]) continue;
      poly.clear();
      for (std::uint32_t i = soup.face_offsets[f]; i < soup.face_offsets[f + 1]; ++i)
        poly.push_back(use(cut.canon[soup.face_nodes[i] + s.offset]));
      if (reverse) std::reverse(poly.begin(), poly.end());
      out.add_face(poly);
      face_side.push_back(static_cast<std::uint8_t>(side));
      continue;
    }
    for (std::uint32_t t = t0; t < t1; ++t)
      for (std::uint32_t p = s.piece_begin[t]; p < s.piece_begin[t + 1]; ++p) {
        if (!s.keep[p]) continue;
        std::array<std::uint32_t, 3> tri{use(s.piece[p][0]), use(s.piece[p][1]), use(s.piece[p][2])};
        if (reverse) std::swap(tri[1], tri[2]);
        out.add_face(tri);
        face_side.push_back(static_cast<std::uint8_t>(side));
      }
  }
}

}  // namespace atelier::net_detail
