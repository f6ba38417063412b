// Net Booleans (seed 004 sections 2-3): the entry point, the cut of each
// net along the intersection polygons and the choice of kept pieces. The
// exact kernel is boolean_exact.cpp; the nets' checks, the box hierarchy and
// the candidate pairs are net_mesh.cpp; paper mode is paper_mode.cpp; the
// prepared operands (step 1 done once per net) are prepared_net.cpp.
//
// Why this file is long: the cut and the choice of pieces share the
// per-net tables built here (pairs per triangle, refined triangles, piece
// components), and splitting them would pass a dozen arrays across files;
// unpinch (the result's edges of many faces) stays beside its one caller.
#include <atelier/engine/parallel.h>
#include <atelier/systems/net/boolean.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <sstream>

#include "boolean_detail.h"

namespace atelier {

using namespace net_detail;

namespace {

using Tri3 = std::array<std::uint32_t, 3>;

std::uint64_t edge_key(std::uint32_t u, std::uint32_t v) {
  return (std::uint64_t{std::min(u, v)} << 32) | std::max(u, v);
}

/// The faces of one edge u -> v (u < v) in their exact angular order about
/// the axis v - u, each face's half-plane named by its first vertex after
/// the edge not collinear with it: angle 0 is the first face's half-plane,
/// the angle grows with orient3d's positive side. Then each face traversing
/// v -> u (its solid side at larger angles) pairs with the next face, which
/// must traverse u -> v: the solid wedges between them stay apart, as two
/// solids touching along an edge stay apart. False (nothing paired) when
/// the edge has faces without such a vertex, coincident half-planes or
/// orientations that do not alternate about the edge.
template <class Half>
bool pair_about_edge(const PolygonSoup& out, std::span<const Half> half, std::span<const std::uint32_t> group,
                     std::span<std::uint32_t> twin) {
  const std::uint32_t iu = static_cast<std::uint32_t>(half[group[0]].key >> 32),
                      iv = static_cast<std::uint32_t>(half[group[0]].key);
  const Vec3d &u = out.positions[iu], &v = out.positions[iv];
  std::vector<Vec3d> w(group.size());
  for (std::size_t g = 0; g < group.size(); ++g) {
    const auto c = out.face(half[group[g]].face);
    bool found = false;
    for (std::size_t k = 2; k < c.size() && !found; ++k) {
      const Vec3d& p = out.positions[c[(half[group[g]].corner + k) % c.size()]];
      found = !collinear(u, v, p);
      w[g] = p;
    }
    if (!found) return false;
  }
  // A point off the plane of the first face, to tell its half-plane from the
  // opposite one among the faces coplanar with it.
  std::optional<Vec3d> off;
  for (int k = 0; k < 3 && !off; ++k)
    if (orient3d(u, v, w[0], u + Vec3d::Unit(k)) != 0) off = u + Vec3d::Unit(k);
  if (!off) return false;
  std::vector<int> lower(group.size());  // 0: angle in [0, pi), 1: [pi, 2 pi)
  for (std::size_t g = 0; g < group.size(); ++g) {
    const int s = orient3d(u, v, w[0], w[g]);
    lower[g] = s > 0 || (s == 0 && orient3d(u, v, *off, w[g]) == orient3d(u, v, *off, w[0])) ? 0 : 1;
  }
  std::vector<std::uint32_t> order(group.size());
  std::iota(order.begin(), order.end(), 0u);
  bool tie = false;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    if (lower[a] != lower[b]) return lower[a] < lower[b];
    if (a == b) return false;
    const int o = orient3d(u, v, w[a], w[b]);
    tie |= o == 0;
    return o != 0 ? o > 0 : a < b;
  });
  if (tie) return false;
  const std::size_t m = order.size();
  std::size_t start = 0;  // a face traversing v -> u
  while (start < m && half[group[order[start]]].forward) ++start;
  if (start == m) return false;
  for (std::size_t k = 0; k < m; ++k)
    if (half[group[order[(start + k) % m]]].forward != (k % 2 == 1)) return false;
  for (std::size_t k = 0; k < m; k += 2) {
    const std::uint32_t hb = group[order[(start + k) % m]], hf = group[order[(start + k + 1) % m]];
    twin[hb] = hf;
    twin[hf] = hb;
  }
  return true;
}

/// Solids that touch along an edge or at a vertex (a union of two boxes
/// sharing an edge) leave edges in four faces and vertices with several
/// fans. The result stays a 2-manifold: at such an edge the faces pair by
/// their angular order about it (pair_about_edge; failing that, each net's
/// faces with their own net's), and a vertex with several fans gets one copy
/// per fan (coincident vertices).
Status unpinch(PolygonSoup& out, std::span<const std::uint8_t> face_side) {
  const std::size_t nf = out.face_count();
  struct Half {
    std::uint64_t key;
    std::uint32_t face, corner;
    bool forward;
  };
  std::vector<Half> half;
  half.reserve(out.face_nodes.size());
  for (std::uint32_t f = 0; f < nf; ++f) {
    const auto c = out.face(f);
    for (std::uint32_t k = 0; k < c.size(); ++k) {
      const std::uint32_t u = c[k], v = c[(k + 1) % c.size()];
      half.push_back({edge_key(u, v), f, k, u < v});
    }
  }
  std::vector<std::uint64_t> keys(half.size());
  for (std::size_t h = 0; h < half.size(); ++h) keys[h] = half[h].key;
  std::vector<std::uint32_t> id;
  sort_edge_keys(keys, out.positions.size(), id);
  std::vector<std::uint32_t> twin(half.size(), kNil);
  bool pinched = false;
  std::vector<std::pair<std::size_t, std::size_t>> many;  // [i, j) of id: the edges of more than two faces
  for (std::size_t i = 0; i < id.size();) {
    std::size_t j = i;
    while (j < id.size() && half[id[j]].key == half[id[i]].key) ++j;
    pinched |= j - i != 2;
    if (j - i > 2) many.emplace_back(i, j);
    if (j - i > 2 && pair_about_edge<Half>(out, half, std::span(id).subspan(i, j - i), twin)) {
      i = j;
      continue;
    }
    // Pair forward with backward halfedges, a net's with its own first.
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t x = i; x < j; ++x) {
        const std::uint32_t hx = id[x];
        if (twin[hx] != kNil || !half[hx].forward) continue;
        for (std::size_t y = i; y < j; ++y) {
          const std::uint32_t hy = id[y];
          if (twin[hy] != kNil || half[hy].forward) continue;
          if (pass == 0 && face_side[half[hx].face] != face_side[half[hy].face]) continue;
          twin[hx] = hy;
          twin[hy] = hx;
          break;
        }
      }
    for (std::size_t x = i; x < j; ++x)
      if (twin[id[x]] == kNil) return {ErrorCode::kInternal, "net boolean: the result has an unmatched edge"};
    i = j;
  }
  // Fans: rotate about a vertex through the previous halfedge's twin.
  std::vector<std::uint32_t> half_begin(nf + 1, 0);
  for (std::uint32_t f = 0; f < nf; ++f)
    half_begin[f + 1] = half_begin[f] + static_cast<std::uint32_t>(out.face(f).size());
  auto prev_in_face = [&](std::uint32_t h) {
    const std::uint32_t f = half[h].face, n = half_begin[f + 1] - half_begin[f];
    return half_begin[f] + (half[h].corner + n - 1) % n;
  };
  auto next_in_face = [&](std::uint32_t h) {
    const std::uint32_t f = half[h].face, n = half_begin[f + 1] - half_begin[f];
    return half_begin[f] + (half[h].corner + 1) % n;
  };
  const std::size_t nv = out.positions.size();
  std::vector<std::uint32_t> fans(nv, 0);
  std::vector<std::uint32_t> fan_of(half.size(), kNil);  // per outgoing halfedge (its tail's fan)
  std::vector<std::uint64_t> ends;
  std::vector<std::uint32_t> forward, backward;
  for (int attempt = 0;; ++attempt) {
    std::fill(fans.begin(), fans.end(), 0u);
    std::fill(fan_of.begin(), fan_of.end(), kNil);
    for (std::uint32_t h = 0; h < half.size(); ++h) {
      if (fan_of[h] != kNil) continue;
      const std::uint32_t v = out.face_nodes[out.face_offsets[half[h].face] + half[h].corner];
      const std::uint32_t fan = fans[v]++;
      std::uint32_t x = h;
      do {
        fan_of[x] = fan;
        x = twin[prev_in_face(x)];
      } while (x != h && fan_of[x] == kNil);
    }
    // An edge of many faces stays in them all when two of its face pairs
    // end in the same fans at both ends (each end one fan: the sheets meet
    // elsewhere about both). Rounded constructed points can leave such an
    // edge without a consistent angular order (pair_about_edge declines and
    // the net-by-net pairing is taken); its halfedges are then re-paired,
    // each backward one with the next's partner, until the fans split it.
    bool again = false;
    for (const auto& [i, j] : many) {
      ends.clear();
      forward.clear();
      for (std::size_t x = i; x < j; ++x) {
        const std::uint32_t h = id[x];
        if (!half[h].forward) continue;
        ends.push_back((std::uint64_t{fan_of[h]} << 32) | fan_of[next_in_face(h)]);
        forward.push_back(h);
      }
      std::sort(ends.begin(), ends.end());
      if (std::adjacent_find(ends.begin(), ends.end()) == ends.end() || attempt >= 8) continue;
      backward.clear();
      for (std::uint32_t hf : forward) backward.push_back(twin[hf]);
      for (std::size_t k = 0; k < forward.size(); ++k) {
        const std::uint32_t hb = backward[k], hf = forward[(k + 1) % forward.size()];
        twin[hb] = hf;
        twin[hf] = hb;
      }
      again = true;
    }
    if (!again) break;
  }
  for (std::uint32_t v = 0; v < nv; ++v) pinched |= fans[v] > 1;
  if (!pinched) return {};
  std::vector<std::uint32_t> copy_base(nv, kNil);
  for (std::uint32_t v = 0; v < nv; ++v) {
    if (fans[v] <= 1) continue;
    copy_base[v] = static_cast<std::uint32_t>(out.positions.size());
    for (std::uint32_t k = 1; k < fans[v]; ++k) out.positions.push_back(out.positions[v]);
  }
  for (std::uint32_t h = 0; h < half.size(); ++h) {
    std::uint32_t& v = out.face_nodes[out.face_offsets[half[h].face] + half[h].corner];
    if (copy_base[v] != kNil && fan_of[h] > 0) v = copy_base[v] + fan_of[h] - 1;
  }
  return {};
}

/// Section 4: the gaps left by the dropped cut polygons are closed by
/// connecting meshes. Boundary loops of the kept parts (along their free
/// sides) are paired by nearest centroids, A's with B's; a loop facing
/// several is split (branching).
Status connect_gaps(PolygonSoup& out, std::vector<std::uint8_t>& face_side, ConnectRule rule, BooleanReport& rep) {
  const std::size_t nf = out.face_count();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> directed;  // (u << 32 | v, face)
  for (std::uint32_t f = 0; f < nf; ++f) {
    const auto c = out.face(f);
    for (std::size_t k = 0; k < c.size(); ++k)
      directed.emplace_back((std::uint64_t{c[k]} << 32) | c[(k + 1) % c.size()], f);
  }
  std::sort(directed.begin(), directed.end());
  auto has = [&](std::uint32_t u, std::uint32_t v) {
    const std::uint64_t k = (std::uint64_t{u} << 32) | v;
    const auto it = std::lower_bound(directed.begin(), directed.end(), std::pair{k, 0u});
    return it != directed.end() && it->first == k;
  };
  std::vector<std::uint32_t> valence(out.positions.size(), 0);
  // Free halfedges v -> u (the twin of a used u -> v is missing), by tail.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> free;  // (tail, head)
  for (const auto& [k, f] : directed) {
    const auto u = static_cast<std::uint32_t>(k >> 32), v = static_cast<std::uint32_t>(k);
    if (!has(v, u)) {
      free.emplace_back(v, u);
      ++valence[u];
      ++valence[v];
    } else if (u < v) {
      ++valence[u];
      ++valence[v];
    }
  }
  std::sort(free.begin(), free.end());
  std::vector<std::uint8_t> side_of_tail(out.positions.size(), 2);
  for (const auto& [k, f] : directed) side_of_tail[static_cast<std::uint32_t>(k >> 32)] = face_side[f];
  std::vector<std::uint8_t> used(free.size(), 0);
  struct Loop {
    BoundaryPolygon poly;
    Vec3d centre = Vec3d::Zero();
    int side = 0;
  };
  std::vector<Loop> loops;
  for (std::size_t i = 0; i < free.size(); ++i) {
    if (used[i]) continue;
    Loop l;
    std::size_t h = i;
    while (!used[h]) {
      used[h] = 1;
      l.poly.vertices.push_back(free[h].first);
      const std::uint32_t next = free[h].second;
      const auto it = std::lower_bound(free.begin(), free.end(), std::pair{next, 0u});
      std::size_t pick = free.size();
      for (auto j = it; j != free.end() && j->first == next; ++j)
        if (!used[static_cast<std::size_t>(j - free.begin())]) {
          pick = static_cast<std::size_t>(j - free.begin());
          break;
        }
      if (pick == free.size()) break;
      h = pick;
    }
    for (std::uint32_t v : l.poly.vertices) {
      l.centre += out.positions[v];
      l.poly.valence.push_back(valence[v]);
    }
    l.centre /= static_cast<double>(l.poly.vertices.size());
    l.side = side_of_tail[l.poly.vertices[0]];
    loops.push_back(std::move(l));
  }
  if (loops.empty()) return {};
  // Each loop's nearest loop of the other net.
  auto nearest = [&](std::size_t i) {
    std::size_t best = loops.size();
    for (std::size_t j = 0; j < loops.size(); ++j)
      if (loops[j].side != loops[i].side &&
          (best == loops.size() ||
           (loops[j].centre - loops[i].centre).squaredNorm() < (loops[best].centre - loops[i].centre).squaredNorm()))
        best = j;
    return best;
  };
  std::vector<std::size_t> near(loops.size());
  for (std::size_t i = 0; i < loops.size(); ++i) {
    near[i] = nearest(i);
    if (near[i] == loops.size())
      return {ErrorCode::kUnsupported,
              "net boolean: a gap of the connecting meshes has a boundary polygon on one net only"};
  }
  ConnectOptions co;
  co.rule = rule;
  std::vector<std::uint8_t> done(loops.size(), 0);
  for (std::size_t i = 0; i < loops.size(); ++i) {
    if (done[i]) continue;
    // Loops whose nearest is i: if i faces several, i branches.
    std::vector<std::size_t> facing;
    for (std::size_t j = 0; j < loops.size(); ++j)
      if (!done[j] && near[j] == i) facing.push_back(j);
    if (facing.empty()) continue;
    std::vector<BoundaryPolygon> qs;
    for (std::size_t j : facing) qs.push_back(loops[j].poly);
    auto r = connect_branching(out.positions, loops[i].poly, qs, co);
    if (!r) return r.status();
    for (std::size_t f = 0; f < r->faces.face_count(); ++f) {
      out.add_face(r->faces.face(f));
      face_side.push_back(2);
    }
    rep.connecting.triangles += r->triangles;
    rep.connecting.quads += r->quads;
    rep.connecting.other += r->other;
    rep.connecting.irregular_vertices += r->irregular_vertices;
    rep.connecting.new_edge_length += r->new_edge_length;
    ++rep.gaps;
    done[i] = 1;
    for (std::size_t j : facing) done[j] = 1;
  }
  for (std::size_t i = 0; i < loops.size(); ++i)
    if (!done[i])
      return {ErrorCode::kUnsupported, "net boolean: a boundary polygon of the connecting meshes could not be paired"};
  return {};
}

}  // namespace

Expected<BooleanOp> parse_boolean_op(std::string_view s) {
  if (s == "union") return BooleanOp::kUnion;
  if (s == "intersection") return BooleanOp::kIntersection;
  if (s == "difference" || s == "a-b" || s == "a_minus_b") return BooleanOp::kAMinusB;
  if (s == "b-a" || s == "b_minus_a") return BooleanOp::kBMinusA;
  return Status(ErrorCode::kInvalidArgument,
                "unknown Boolean operation '" + std::string(s) + "' (union, intersection, difference, b-a)");
}

Expected<BooleanMode> parse_boolean_mode(std::string_view s) {
  if (s == "exact") return BooleanMode::kExact;
  if (s == "paper") return BooleanMode::kPaper;
  return Status(ErrorCode::kInvalidArgument, "unknown Boolean mode '" + std::string(s) + "' (exact, paper)");
}

Expected<BooleanJoin> parse_boolean_join(std::string_view s) {
  if (s == "cut") return BooleanJoin::kCut;
  if (s == "meshes") return BooleanJoin::kMeshes;
  return Status(ErrorCode::kInvalidArgument, "unknown join '" + std::string(s) + "' (cut, meshes)");
}

Expected<Correspondence> parse_correspondence(std::string_view s) {
  if (s == "visual") return Correspondence::kVisual;
  if (s == "topological") return Correspondence::kTopological;
  if (s == "window2") return Correspondence::kWindowSmall;
  if (s == "window4") return Correspondence::kWindowLarge;
  return Status(ErrorCode::kInvalidArgument,
                "unknown correspondence '" + std::string(s) + "' (visual, topological, window2, window4)");
}

PolygonSoup net_polygons(const Model& m) {
  PolygonSoup s;
  const auto source = m.nodes.props.find<std::int32_t>("source_vertex");
  std::vector<std::uint32_t> index(m.nodes.slots.capacity(), kNil);
  std::vector<std::uint32_t> by_source;  // source vertex -> the first soup vertex made from it
  std::vector<NodeIdx> corners;
  std::vector<std::uint32_t> poly;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    m.face_nodes(FaceIdx{f}, corners);
    poly.clear();
    for (NodeIdx v : corners) {
      if (index[v.value] == kNil) {
        std::uint32_t id = kNil;
        const std::int32_t src = source.valid() ? source[v] : -1;
        if (src >= 0 && static_cast<std::size_t>(src) < by_source.size() && by_source[src] != kNil &&
            s.positions[by_source[src]] == m.position(v))
          id = by_source[src];
        if (id == kNil) {
          id = static_cast<std::uint32_t>(s.positions.size());
          s.positions.push_back(m.position(v));
          if (src >= 0) {
            if (static_cast<std::size_t>(src) >= by_source.size())
              by_source.resize(static_cast<std::size_t>(src) + 1, kNil);
            if (by_source[src] == kNil) by_source[src] = id;
          }
        }
        index[v.value] = id;
      }
      poly.push_back(index[v.value]);
    }
    s.add_face(poly);
  }
  return s;
}

namespace {

/// ctx with another thread count: the result's certificate is a few hundred
/// cut triangles of microseconds each, worth two threads on small pairs
/// too (its verdict does not depend on them).
ExecContext with_threads(const ExecContext& ctx, int threads) {
  ExecContext c = ctx;
  c.threads = threads;
  return c;
}

/// Steps 2-5 of the Boolean on two prepared nets (checked), reported to
/// ctx.progress as stages first_stage .. first_stage + 2 of `stages`.
/// caller_threads: the caller's thread count before the small-pair rule
/// (ctx.threads is 1 for small pairs), for the result's certificate.
Expected<BooleanReport> boolean_of(const PreparedData& pa, const PreparedData& pb, const BooleanOptions& opt,
                                   const ExecContext& ctx, int caller_threads, std::size_t first_stage,
                                   std::size_t stages) {
  BooleanReport rep;
  const TriMesh &A = pa.mesh, &B = pb.mesh;
  const Bvh &bvh_a = pa.bvh, &bvh_b = pb.bvh;
  const PolygonSoupView &sa = pa.soup, &sb = pb.soup;
  rep.volume_a = pa.volume;
  rep.volume_b = pb.volume;
  rep.area_a = pa.area;
  rep.area_b = pb.area;

  Cut cut;
  if (Status st = cut_nets(A, bvh_a, B, bvh_b, ctx, cut, opt.exact_refinement); !st) return st;
  if (Status s = stage_done(ctx, "boolean: cut", first_stage, stages); !s) return s;
  rep.candidate_pairs = cut.candidate_pairs;
  rep.intersecting_pairs = cut.intersecting_pairs;
  rep.intersection_points = cut.new_keys.size();
  rep.cut_triangles = cut.sides[0].cut.size() + cut.sides[1].cut.size();
  rep.refined_exact = cut.refined_exact;
  auto& sides = cut.sides;
  const auto& canon = cut.canon;
  const auto& on_a = cut.on_a;
  const auto& on_b = cut.on_b;
  const auto& new_keys = cut.new_keys;
  const std::uint32_t nA = cut.nA, nB = cut.nB;
  const std::size_t n_ids = canon.size();

  // ---- winding number of the other net about each component (exact)
  auto key_of = [&](std::uint32_t id) -> PointKey {
    if (id < nA) return {simplex(kDimVertex, id), kNoSimplex};
    if (id < nA + nB) return {kNoSimplex, simplex(kDimVertex, id - nA)};
    return new_keys[id - nA - nB];
  };
  for (CutSide& s : sides) {
    const TriMesh& other = s.side == 0 ? B : A;
    const Bvh& other_bvh = s.side == 0 ? bvh_b : bvh_a;
    const std::vector<std::uint64_t>& on_other = s.side == 0 ? on_b : on_a;
    const std::uint32_t count = static_cast<std::uint32_t>(s.piece.size());
    std::vector<std::uint32_t> roots;
    std::vector<std::uint32_t> probe(count, kNil);  // per root: a vertex off the other net, or kNil
    std::vector<std::uint32_t> first_piece(count, kNil);
    for (std::uint32_t p = 0; p < count; ++p) {
      if (s.coplanar[p] != 0) continue;
      const std::uint32_t r = s.component[p];
      if (first_piece[r] == kNil) {
        first_piece[r] = p;
        roots.push_back(r);
      }
      if (probe[r] != kNil) continue;
      for (std::uint32_t v : s.piece[p])
        if (v >= s.offset && v < s.offset + s.m->p.size() && on_other[v] == kNoSimplex) {
          probe[r] = v;
          break;
        }
    }
    std::vector<int> wind(roots.size(), 0);
    std::vector<Status> st(roots.size());
    ExecContext c = ctx;
    c.sequential_threshold = 2;
    c.grain = 1;
    par::for_each_n(c, roots.size(), [&](std::size_t i) {
      const std::uint32_t r = roots[i];
      try {
        if (probe[r] != kNil) {
          wind[i] = winding_number(other, other_bvh, s.m->p[probe[r] - s.offset]);
        } else {
          const Tri3& t = s.piece[first_piece[r]];
          auto box_of = [&](std::uint32_t id) -> const PointBox* {
            return id >= nA + nB ? &cut.new_boxes[id - nA - nB] : nullptr;
          };
          wind[i] = winding_number_centroid(other, other_bvh, A, B, {key_of(t[0]), key_of(t[1]), key_of(t[2])},
                                            {box_of(t[0]), box_of(t[1]), box_of(t[2])});
        }
      } catch (const Error& e) {
        st[i] = e.status();
      }
    });
    for (const Status& x : st)
      if (!x) return x;
    std::vector<std::uint8_t> inside(count, 0);
    for (std::size_t i = 0; i < roots.size(); ++i) inside[roots[i]] = wind[i] != 0;
    s.keep.assign(count, 0);
    for (std::uint32_t p = 0; p < count; ++p) {
      const int cp = s.coplanar[p];
      bool keep = false;
      if (cp != 0) {
        // A coplanar overlap is kept once, as A's triangles: with the same
        // orientation in a union or an intersection, with opposite ones in
        // a difference (touching from outside: the face stays).
        if (s.side == 0) keep = (opt.op == BooleanOp::kUnion || opt.op == BooleanOp::kIntersection) ? cp > 0 : cp < 0;
      } else {
        const bool in = inside[s.component[p]] != 0;
        switch (opt.op) {
          case BooleanOp::kUnion:
            keep = !in;
            break;
          case BooleanOp::kIntersection:
            keep = in;
            break;
          case BooleanOp::kAMinusB:
            keep = s.side == 0 ? !in : in;
            break;
          case BooleanOp::kBMinusA:
            keep = s.side == 0 ? in : !in;
            break;
        }
      }
      s.keep[p] = keep ? 1 : 0;
    }
  }

  if (Status s = stage_done(ctx, "boolean: classify", first_stage + 1, stages); !s) return s;

  // ---- intersection polygons: components of the edges both nets share
  std::vector<std::uint64_t> common;
  {
    std::set_intersection(sides[0].edges.begin(), sides[0].edges.end(), sides[1].edges.begin(), sides[1].edges.end(),
                          std::back_inserter(common));
    std::vector<std::uint32_t> verts;
    for (std::uint64_t e : common) {
      verts.push_back(static_cast<std::uint32_t>(e >> 32));
      verts.push_back(static_cast<std::uint32_t>(e));
    }
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    UnionFind uf(verts.size());
    auto at = [&](std::uint32_t v) {
      return static_cast<std::uint32_t>(std::lower_bound(verts.begin(), verts.end(), v) - verts.begin());
    };
    for (std::uint64_t e : common) uf.unite(at(static_cast<std::uint32_t>(e >> 32)), at(static_cast<std::uint32_t>(e)));
    for (std::uint32_t i = 0; i < verts.size(); ++i) rep.intersection_polygons += uf.find(i) == i;
  }

  // ---- the result: kept pieces (whole polygons where untouched)
  const bool reverse_b = opt.op == BooleanOp::kAMinusB;
  std::vector<std::uint32_t> out_index(n_ids, kNil);
  PolygonSoup& out = rep.result;
  std::vector<std::uint8_t> from_a, from_b;  // per output vertex
  std::vector<std::uint8_t> face_side;       // per output face: 0 from A, 1 from B
  if (opt.join == BooleanJoin::kMeshes) {
    // Section 4: every polygon with a point of intersection is left out.
    for (CutSide& s : sides) {
      const TriMesh& m = *s.m;
      for (std::size_t f = 0; f + 1 < m.face_tri_begin.size(); ++f) {
        bool cut_polygon = false;
        for (std::uint32_t t = m.face_tri_begin[f]; t < m.face_tri_begin[f + 1]; ++t) cut_polygon |= s.slot[t] != kNil;
        if (!cut_polygon) continue;
        for (std::uint32_t p = s.piece_begin[m.face_tri_begin[f]]; p < s.piece_begin[m.face_tri_begin[f + 1]]; ++p)
          s.keep[p] = 0;
      }
    }
  }
  for (CutSide& s : sides) {
    const bool reverse = s.side == 0 ? opt.op == BooleanOp::kBMinusA : reverse_b;
    emit_side(cut, A, B, s.side, s.side == 0 ? sa : sb, reverse, out, out_index, face_side);
  }
  Status moved_refusal;       // the check's refusal when repair_folds moved points (snap17)
  bool full_checked = false;  // the certificate failed: the repair and the fold check ran
  if (opt.join == BooleanJoin::kMeshes) {
    if (Status st = connect_gaps(out, face_side, opt.rule, rep); !st) return st;
  } else if (opt.mode == BooleanMode::kExact && opt.check_result &&
             !certify_rounded_result(cut, A, bvh_a, B, bvh_b, with_threads(ctx, caller_threads))) {
    // The exact result does not cross itself; rounding its new points can
    // flatten a sliver or fold it over a neighbour (issue 24, fold15): flat
    // ones are flipped away, and a folded result is never returned. Not in
    // paper mode, whose merge moves the points again (and pairs them by
    // out_index, which a collapse would leave stale). Only when the
    // certificate cannot show that no triangle with a new point is flat or
    // meets another beyond their shared corners (fold16: the repair and the
    // check would then leave the result as it is, at 1.2-2.3x a Boolean's
    // cost; the certificate costs 1.07-1.15x on the spheres, 1.3-1.6x on
    // the CAD pairs, docs/performance.md, fold16).
    full_checked = true;
    std::vector<std::uint8_t> is_new(out.positions.size(), 0);
    for (std::uint32_t id = nA + nB; id < n_ids; ++id)
      if (out_index[id] != kNil) is_new[out_index[id]] = 1;
    std::vector<std::uint64_t> split_edges;
    std::array<std::uint32_t, 2> collapse{kNil, kNil};
    FoldPair pair;
    // The check's suspects: the new points, and the vertices a repair
    // collapsed into or fanned from (snap17: the faces they changed).
    std::vector<std::uint8_t> suspect = is_new;
    for (int round = 0;; ++round) {
      const std::size_t fixed = repair_flat_triangles(out, face_side, is_new, split_edges,
                                                      std::span(&collapse, collapse[0] == kNil ? 0 : 1), &suspect);
      Status st =
          check_rounded_result(cut, A, bvh_a, B, bvh_b, out, out_index, suspect, split_edges, collapse, ctx, &pair);
      if (st) break;
      if (collapse[0] == kNil || round == 16 || (round > 0 && fixed == 0)) {
        // A net not tested for self-intersection (the caller's promise)
        // that crosses itself where the check looks: that crossing is the
        // error, as for the cut's own failures (explain_by_crossing).
        if (!(pa.self_checked && pb.self_checked))
          if (Status why = explain_by_crossing(Status(ErrorCode::kInternal, st.message()), A, bvh_a, B, bvh_b, ctx, 0);
              why.code() != ErrorCode::kInternal)
            return why;
        // What fold15's repair leaves folded: the crossing pairs' new points
        // moved to other roundings or snapped onto a neighbour, each move
        // checked exactly (snap17, fold_repair.cpp); refused only when that
        // fails too.
        Status refusal = st;
        st = repair_folds(cut, A, bvh_a, B, bvh_b, out, face_side, out_index, is_new, split_edges, suspect,
                          std::move(st), pair, ctx);
        if (!st) return st;
        moved_refusal = std::move(refusal);
        break;
      }
    }
  }
  if (Status st = unpinch(out, face_side); !st) return st;
  if (full_checked) {
    // flat19: a zero-length edge fold15's collapse left (its link condition
    // failed before unpinch split the pinched vertex into copies) is merged
    // away now, where the result stays a 2-manifold: no position moves, the
    // faces on the edge lose the repeated corner (a flat triangle
    // vanishes). What is left is refused below as a flat face.
    std::vector<std::uint32_t> remap;
    flat_merge_count() += merge_flat_edges(out, face_side, remap).merged;
    if (!remap.empty())
      for (std::uint32_t& x : out_index)
        if (x != kNil) x = remap[x];
  }
  // A result the certificate could not pass is self-tested whole
  // (prepare_result: exact triangles_cross over all pairs; the degenerate
  // path only, never on a certified result). The fold check looks at the
  // faces of new and moved points and, where two ids share a position,
  // merges them: the campaign's pinched oracle found crossings it passed
  // (seed 1 case 43's chain; after snap17's moves, seed 1 cases 15 and 49).
  // A result repair_folds moved must pass it (else refused with the check's
  // own error, as before the repair); any other is refused when it
  // certainly crosses itself or has a flat face. prepare_result also
  // refuses two ids rounded to one position (duplicate vertices) before it
  // tests crossings: such a result is tested by pinched_self_crossing.
  PreparedNet self_tested;  // kept for opt.prepare_result: the same test on the same result
  Status why;
  if (full_checked) {
    self_tested = prepare_result(out, A.name, ctx, why);
    if (self_tested.empty() || !why) {
      // cross18: a result with coincident vertex copies (two ids rounded to
      // one position, a pinch) is self-tested whole with the copies merged
      // (pinched_self_crossing): refused when two faces cross beyond the
      // pinch, otherwise returned, moved or not.
      const bool pinched = why.message().find("(duplicate vertices)") != std::string::npos;
      if (pinched) {
        // No result keeps a flat face (flat19): the zero-length edges were
        // merged away above where the result stays a 2-manifold (seed 1
        // case 43's chain, the union of NetBoolean.SpheresWithSharedVertices),
        // and a flat triangle left (a merge that would not be manifold, or
        // corners on one line) is refused, moved or not, as CGAL's exact
        // test counts it as crossing itself.
        const auto c = pinched_self_crossing(out, ctx, true);
        if (c[0] != kNil && !moved_refusal) return moved_refusal;
        if (c[0] != kNil && c[0] == c[1])
          return fail(ErrorCode::kTopology,
                      "net boolean: the result crosses itself once its new points are rounded to doubles: face ",
                      c[0], " of the result is flat (its corners on one line)");
        if (c[0] != kNil)
          return fail(ErrorCode::kTopology,
                      "net boolean: the result crosses itself once its new points are rounded to doubles: faces ",
                      c[0], " and ", c[1], " of the result cross");
      } else {
        if (!moved_refusal) return moved_refusal;
        // flat19: a flat triangle without copies (corners on one line) is
        // refused too, as in a pinched result.
        if (why.message().find("is degenerate") != std::string::npos)
          return Status(
              ErrorCode::kTopology,
              "net boolean: the result crosses itself once its new points are rounded to doubles: " + why.message());
        if (why.message().find("intersects itself") != std::string::npos) {
          // Reached only by a crossing the fold check does not look at
          // (it tests every triangle with a new point against all kept
          // triangles near it): an operand not tested for self-intersection
          // (the caller's promise) crossing itself away from the cut
          // (crossing_test.cpp). Named in that operand when it is so.
          if (!(pa.self_checked && pb.self_checked))
            if (Status in = explain_by_crossing(Status(ErrorCode::kInternal, why.message()), A, bvh_a, B, bvh_b, ctx, 0);
                in.code() != ErrorCode::kInternal)
              return in;
          return Status(
              ErrorCode::kTopology,
              "net boolean: the result crosses itself once its new points are rounded to doubles: " + why.message());
        }
      }
    }
  }
  for (std::uint64_t e : common)
    for (std::uint32_t id : {static_cast<std::uint32_t>(e >> 32), static_cast<std::uint32_t>(e)})
      if (out_index[id] != kNil) rep.seam.push_back(out_index[id]);
  std::sort(rep.seam.begin(), rep.seam.end());
  rep.seam.erase(std::unique(rep.seam.begin(), rep.seam.end()), rep.seam.end());
  rep.volume = soup_volume(out);
  rep.area = soup_area(out);
  if (opt.mode == BooleanMode::kPaper) {
    // Which output vertices are points of A's intersection polygon (on A's
    // edges) and of B's (on B's edges): seed 004 section 3 pairs them.
    from_a.assign(out.positions.size(), 0);
    from_b.assign(out.positions.size(), 0);
    for (std::uint32_t id = 0; id < n_ids; ++id) {
      if (out_index[id] == kNil || canon[id] != id || on_a[id] == kNoSimplex || on_b[id] == kNoSimplex) continue;
      from_a[out_index[id]] = dim_of(on_a[id]) != kDimFace;
      from_b[out_index[id]] = dim_of(on_b[id]) != kDimFace;
    }
    std::vector<std::array<std::uint32_t, 2>> curve;
    for (std::uint64_t e : common) {
      const std::uint32_t u = out_index[static_cast<std::uint32_t>(e >> 32)],
                          w = out_index[static_cast<std::uint32_t>(e)];
      if (u != kNil && w != kNil) curve.push_back({u, w});
    }
    if (Status s = apply_paper_mode(out, curve, from_a, from_b, static_cast<int>(opt.correspondence), rep.merged_pairs,
                                    rep.valence.vertices, rep.valence.irregular, rep.valence.min, rep.valence.max,
                                    rep.valence.mean, rep.seam);
        !s)
      return s;
    rep.volume = soup_volume(out);
    rep.area = soup_area(out);
  }
  if (opt.prepare_result) {
    if (full_checked) {  // exact mode: the result is as self-tested above
      rep.prepared = std::move(self_tested);
      rep.prepared_status = std::move(why);
    } else {
      rep.prepared = prepare_result(rep.result, A.name, ctx, rep.prepared_status);
    }
  }
  if (Status s = stage_done(ctx, "boolean: result", first_stage + 2, stages); !s) return s;
  return rep;
}

/// An internal error of a Boolean on a net not checked for self-intersection
/// (its caller's promise): the crossing faces when it crosses itself.
Expected<BooleanReport> explained_by_crossing(Expected<BooleanReport> r, const PreparedData& pa, const PreparedData& pb,
                                              const ExecContext& ctx) {
  if (r || (pa.self_checked && pb.self_checked)) return r;
  return explain_by_crossing(r.status(), pa.mesh, pa.bvh, pb.mesh, pb.bvh, ctx, 0);
}

}  // namespace

Expected<BooleanReport> net_boolean(const PolygonSoupView& sa, const PolygonSoupView& sb, const BooleanOptions& opt,
                                    const ExecContext& ctx_in) {
  // Small pairs run on the calling thread: below ctx.sequential_threshold
  // polygons (10^4 by default) the start-up of parallel tasks costs more
  // than the work (a CAD pair of 200 triangles takes a few milliseconds).
  ExecContext ctx = ctx_in;
  if (sa.face_count() + sb.face_count() < ctx.sequential_threshold) ctx.threads = 1;
  // prepare + prepare + the prepared Boolean, without copying the soups:
  // the two nets are built, checked and given their hierarchies side by
  // side (two tasks; each is parallel inside). A's error is reported first.
  // The two tasks run on two threads whenever the caller allows them, small
  // pairs too (each task then sequential inside): a CAD net's preparation
  // is a few hundred microseconds, well above a task's start-up, and it is
  // 30-40% of a small pair's one-call.
  PreparedData pa, pb;
  pa.soup = sa;
  pb.soup = sb;
  std::array<PrepareSteps, 2> steps;
  {
    ExecContext two = ctx;
    two.threads = ctx_in.threads;
    two.sequential_threshold = 2;
    two.grain = 1;
    par::for_each_n(two, 2, [&](std::size_t k) {
      prepare_data(k == 0 ? pa : pb, k == 0 ? "A" : "B", opt.check_self_intersection, ctx, steps[k]);
    });
  }
  // Five stages reported to ctx.progress, each ending in a cancellation check.
  constexpr std::size_t kStages = 5;
  for (const PrepareSteps& st : steps)
    if (!st.built) return st.built;
  if (Status s = stage_done(ctx, "boolean: input", 1, kStages); !s) return s;
  for (const PrepareSteps& st : steps)
    if (!st.volume) return st.volume;
  for (const PrepareSteps& st : steps)
    if (!st.crossing) return st.crossing;
  if (Status s = stage_done(ctx, "boolean: self-intersection check", 2, kStages); !s) return s;
  return explained_by_crossing(boolean_of(pa, pb, opt, ctx, ctx_in.threads, 3, kStages), pa, pb, ctx);
}

Expected<BooleanReport> net_boolean(const PreparedNet& a, const PreparedNet& b, const BooleanOptions& opt,
                                    const ExecContext& ctx_in) {
  const PreparedData *pa = PreparedAccess::get(a), *pb = PreparedAccess::get(b);
  if (pa == nullptr || pb == nullptr)
    return Status(ErrorCode::kInvalidArgument, "net boolean: an operand is an empty PreparedNet (not prepared)");
  if (opt.check_self_intersection)
    for (const PreparedData* d : {pa, pb})
      if (!d->self_checked)
        return fail(ErrorCode::kInvalidArgument, "net ", d->mesh.name,
                    " was prepared without the self-intersection test: prepare it with the test, or set "
                    "check_self_intersection = false");
  ExecContext ctx = ctx_in;
  if (pa->soup.face_count() + pb->soup.face_count() < ctx.sequential_threshold) ctx.threads = 1;
  return explained_by_crossing(boolean_of(*pa, *pb, opt, ctx, ctx_in.threads, 1, 3), *pa, *pb, ctx);
}

}  // namespace atelier
