// The rounded result's repair and fold check (issue 24, round 19). The cut
// is exact, but its new points are rounded to doubles: a sliver of the
// exact result can round flat (its corners on one line), and a rounded
// point can carry a sliver over a neighbouring triangle, so the result
// crosses itself although the exact one does not.
//
// Repair: a flat triangle whose middle corner lies strictly between the
// other two is removed and the face across its long edge gets that corner
// (split as a fan from it): the same surface without the flat triangle
// (docs/glossary.md, "flat slivers flipped away").
//
// Certificate (fold16, fold_certificate.cpp): most results are shown by
// floating-point filters to need neither, and skip both.
//
// Check: only triangles with a rounded point can have moved, so the result's
// triangles with a new point are tested against each other and against the
// other kept triangles of both nets whose boxes meet theirs (triangles_cross,
// the self-check's exact pair test). Those others are the nets' own (tested
// with their net, or promised by the caller), so not among themselves.
#include <atelier/engine/parallel.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include "boolean_detail.h"

namespace atelier::net_detail {

namespace {

std::uint64_t fold_directed(std::uint32_t u, std::uint32_t v) {
  return (std::uint64_t{u} << 32) | v;
}

/// The corner of a flat (collinear) triangle strictly between the other
/// two, or 3 when two corners coincide.
int fold_middle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2) {
  const Vec3d* p[3] = {&p0, &p1, &p2};
  for (int m = 0; m < 3; ++m) {
    const Vec3d &a = *p[(m + 1) % 3], &b = *p[(m + 2) % 3], &x = *p[m];
    if (a == b || a == x || b == x) return 3;
    // On the line through a and b: strictly between them in any coordinate
    // where they differ (collinear, so one such coordinate decides).
    for (int k = 0; k < 3; ++k)
      if (a[k] != b[k]) {
        if ((a[k] < x[k] && x[k] < b[k]) || (b[k] < x[k] && x[k] < a[k])) return m;
        break;
      }
  }
  return 3;
}

// The mesh's ids renamed so that coincident positions are one corner (the
// first id of each exact position, in lexicographic order), mesh.p the
// distinct positions of the ids used, and the triangles' boxes made: a
// touch at coincident copies is then a shared corner, not a crossing.
template <class Position>
void merge_positions(TriMesh& mesh, const Position& pos) {
  std::vector<std::uint32_t> used;
  for (const auto& t : mesh.tri) used.insert(used.end(), t.begin(), t.end());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::vector<std::uint32_t> order(used.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  auto lex = [&](std::uint32_t x, std::uint32_t y) {
    const Vec3d &p = pos(used[x]), &q = pos(used[y]);
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return x < y;
  };
  std::sort(order.begin(), order.end(), lex);
  std::vector<std::uint32_t> local(used.size());
  mesh.p.clear();
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || pos(used[order[i]]) != pos(used[order[i - 1]])) mesh.p.push_back(pos(used[order[i]]));
    local[order[i]] = static_cast<std::uint32_t>(mesh.p.size() - 1);
  }
  mesh.box.resize(mesh.tri.size());
  for (std::size_t t = 0; t < mesh.tri.size(); ++t) {
    for (auto& x : mesh.tri[t])
      x = local[static_cast<std::size_t>(std::lower_bound(used.begin(), used.end(), x) - used.begin())];
    mesh.box[t] = tri_box(mesh, static_cast<std::uint32_t>(t));
  }
}

/// The kept triangles of the result near its moved points, in output
/// vertex ids merged by exact position (coincident copies count as one
/// corner: a pinch is not a crossing), with boxes.
struct FoldNet {
  TriMesh mesh;
  std::vector<std::uint32_t> face;                   // per triangle: output face, or kNil (a net's triangle)
  std::vector<std::array<std::uint32_t, 2>> origin;  // per net triangle: side, the side's triangle
  std::vector<Vec3d> extra;                          // positions of ids past the output's (centroids of whole n-gons)
  void finish(std::span<const Vec3d> out) {
    merge_positions(mesh,
                    [&](std::uint32_t v) -> const Vec3d& { return v < out.size() ? out[v] : extra[v - out.size()]; });
  }
};

}  // namespace

std::size_t repair_flat_triangles(PolygonSoup& out, std::vector<std::uint8_t>& face_side,
                                  std::span<const std::uint8_t> is_new, std::vector<std::uint64_t>& split_edges,
                                  std::span<const std::array<std::uint32_t, 2>> collapse,
                                  std::vector<std::uint8_t>* touched) {
  auto touch = [&](std::uint32_t v) {
    if (touched == nullptr) return;
    if (touched->size() < out.positions.size()) touched->resize(out.positions.size(), 0);
    (*touched)[v] = 1;
  };
  const std::size_t nf = out.face_count();
  auto flat_at = [&](std::uint32_t f) {
    const auto c = out.face(f);
    if (c.size() != 3 || !(is_new[c[0]] || is_new[c[1]] || is_new[c[2]])) return false;
    return collinear(out.positions[c[0]], out.positions[c[1]], out.positions[c[2]]);
  };
  std::vector<std::uint32_t> flats;
  for (std::uint32_t f = 0; f < nf; ++f)
    if (flat_at(f)) flats.push_back(f);
  if (flats.empty() && collapse.empty()) return 0;
  // Faces as lists (edited in place), and the directed edges' faces.
  std::vector<std::vector<std::uint32_t>> faces(nf);
  std::unordered_map<std::uint64_t, std::uint32_t> edge_face;
  for (std::uint32_t f = 0; f < nf; ++f) {
    const auto c = out.face(f);
    faces[f].assign(c.begin(), c.end());
    for (std::size_t k = 0; k < c.size(); ++k) edge_face[fold_directed(c[k], c[(k + 1) % c.size()])] = f;
  }
  auto add_edges = [&](std::uint32_t f) {
    const auto& c = faces[f];
    for (std::size_t k = 0; k < c.size(); ++k) edge_face[fold_directed(c[k], c[(k + 1) % c.size()])] = f;
  };
  std::vector<std::uint8_t> gone(nf, 0);
  std::size_t repaired = 0;
  // Two corners of f rounded to one point (distinct exact points): the edge
  // between them collapses, w into u, when its two triangles are its only
  // faces and u and w have no other common neighbour (the link condition:
  // the result stays a 2-manifold). No position moves.
  auto collapse_edge = [&](std::uint32_t u, std::uint32_t w) {
    if (is_new[u] && !is_new[w]) std::swap(u, w);  // keep a net's own vertex
    if (is_new[u] && is_new[w] && w < u) std::swap(u, w);
    if (!is_new[w]) return false;  // a net's own vertices never move
    std::vector<std::uint32_t> both, nu, nw;
    for (std::uint32_t g = 0; g < faces.size(); ++g) {
      if (gone[g]) continue;
      const auto& cg = faces[g];
      const bool hu = std::find(cg.begin(), cg.end(), u) != cg.end(),
                 hw = std::find(cg.begin(), cg.end(), w) != cg.end();
      if (hu && hw) both.push_back(g);
      for (std::size_t k = 0; k < cg.size(); ++k) {
        const std::uint32_t x = cg[k], y = cg[(k + 1) % cg.size()];
        if (x == u || y == u) nu.push_back(x == u ? y : x);
        if (x == w || y == w) nw.push_back(x == w ? y : x);
      }
    }
    if (both.size() != 2 || faces[both[0]].size() != 3 || faces[both[1]].size() != 3) return false;
    std::sort(nu.begin(), nu.end());
    nu.erase(std::unique(nu.begin(), nu.end()), nu.end());
    std::sort(nw.begin(), nw.end());
    nw.erase(std::unique(nw.begin(), nw.end()), nw.end());
    std::vector<std::uint32_t> common, opposite;
    std::set_intersection(nu.begin(), nu.end(), nw.begin(), nw.end(), std::back_inserter(common));
    for (std::uint32_t g : both)
      for (std::uint32_t x : faces[g])
        if (x != u && x != w) opposite.push_back(x);
    std::sort(opposite.begin(), opposite.end());
    if (common != opposite || opposite.size() != 2) return false;
    for (std::uint32_t g : both) {
      gone[g] = 1;
      const auto& cg = faces[g];
      for (std::size_t k = 0; k < 3; ++k) edge_face.erase(fold_directed(cg[k], cg[(k + 1) % 3]));
    }
    for (std::uint32_t g = 0; g < faces.size(); ++g) {
      if (gone[g] || std::find(faces[g].begin(), faces[g].end(), w) == faces[g].end()) continue;
      auto& cg = faces[g];
      for (std::size_t k = 0; k < cg.size(); ++k) edge_face.erase(fold_directed(cg[k], cg[(k + 1) % cg.size()]));
      std::replace(cg.begin(), cg.end(), w, u);
      add_edges(g);
    }
    touch(u);
    return true;
  };
  auto collapse_coincident = [&](std::uint32_t f) {
    const auto c = faces[f];
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t j = i + 1; j < 3; ++j)
        if (c[i] != c[j] && out.positions[c[i]] == out.positions[c[j]]) return collapse_edge(c[i], c[j]);
    return false;
  };
  for (const auto& e : collapse) repaired += collapse_edge(e[0], e[1]) ? 1 : 0;
  // Flips can make new flat triangles (then repaired in turn); bounded, so a
  // cycle of flips cannot run away (what is left is checked below).
  const std::size_t max_flats = 4 * flats.size() + 16;
  for (std::size_t i = 0; i < flats.size() && i < max_flats; ++i) {
    const std::uint32_t f = flats[i];
    if (gone[f] || faces[f].size() != 3) continue;
    const auto c = faces[f];
    const int m = fold_middle(out.positions[c[0]], out.positions[c[1]], out.positions[c[2]]);
    if (m == 3) {
      repaired += collapse_coincident(f) ? 1 : 0;
      continue;
    }
    // f runs a -> b -> x (x the middle corner); the face across a -> b runs b -> a.
    const std::uint32_t x = c[static_cast<std::size_t>(m)], a = c[static_cast<std::size_t>((m + 1) % 3)],
                        b = c[static_cast<std::size_t>((m + 2) % 3)];
    const auto it = edge_face.find(fold_directed(b, a));
    if (it == edge_face.end() || it->second == f || gone[it->second]) continue;
    const std::uint32_t n = it->second;
    // n from a round to b, as a fan from x: (x, a, y1), (x, y1, y2), ...
    std::vector<std::uint32_t> ring;
    const auto& cn = faces[n];
    const auto at = static_cast<std::size_t>(std::find(cn.begin(), cn.end(), a) - cn.begin());
    for (std::size_t k = 0; k < cn.size(); ++k) ring.push_back(cn[(at + k) % cn.size()]);
    if (std::find(ring.begin(), ring.end(), x) != ring.end()) continue;
    // The fan's inner edges must be new (an existing edge x - y would get a
    // third face: the flip would not leave a 2-manifold).
    bool fresh = true;
    for (std::size_t k = 1; k + 1 < ring.size() && fresh; ++k)
      fresh = !edge_face.contains(fold_directed(x, ring[k])) && !edge_face.contains(fold_directed(ring[k], x));
    if (!fresh) continue;
    gone[f] = 1;
    gone[n] = 1;
    touch(x);
    split_edges.push_back(fold_directed(std::min(a, b), std::max(a, b)));
    edge_face.erase(fold_directed(b, a));
    for (std::size_t k = 0; k + 1 < ring.size(); ++k) {
      faces.push_back({x, ring[k], ring[k + 1]});
      gone.push_back(0);
      face_side.push_back(face_side[n]);
      add_edges(static_cast<std::uint32_t>(faces.size() - 1));
      // A new triangle may itself be flat (x on a line with a ring edge).
      const auto& t = faces.back();
      if (collinear(out.positions[t[0]], out.positions[t[1]], out.positions[t[2]]))
        flats.push_back(static_cast<std::uint32_t>(faces.size() - 1));
    }
    ++repaired;
  }
  if (repaired == 0) return 0;
  PolygonSoup r;
  r.positions = std::move(out.positions);
  std::vector<std::uint8_t> sides;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (gone[f]) continue;
    r.add_face(faces[f]);
    sides.push_back(face_side[f]);
  }
  out = std::move(r);
  face_side = std::move(sides);
  return repaired;
}

Status check_rounded_result(const Cut& cut, const TriMesh& a, const Bvh& bvh_a, const TriMesh& b, const Bvh& bvh_b,
                            const PolygonSoup& out, std::span<const std::uint32_t> out_index,
                            std::span<const std::uint8_t> is_new, std::span<const std::uint64_t> split_edges,
                            std::array<std::uint32_t, 2>& short_edge, const ExecContext& ctx, FoldPair* pair) {
  short_edge = {kNil, kNil};
  FoldNet fn;
  // Suspects: the result's triangles with a new point (a repaired face's
  // triangles among them).
  for (std::uint32_t f = 0; f < out.face_count(); ++f) {
    const auto c = out.face(f);
    if (c.size() != 3 || !(is_new[c[0]] || is_new[c[1]] || is_new[c[2]])) continue;
    fn.mesh.tri.push_back({c[0], c[1], c[2]});
    fn.face.push_back(f);
    fn.origin.push_back({kNil, kNil});
  }
  const auto suspects = static_cast<std::uint32_t>(fn.mesh.tri.size());
  if (suspects == 0) return {};
  fn.finish(out.positions);
  TriMesh suspect_mesh = fn.mesh;
  Bvh sb;
  build_bvh(suspect_mesh, sb, ctx);
  std::vector<std::array<std::uint32_t, 2>> pairs;  // suspect - neighbour, then suspect - suspect
  // Neighbours: the kept pieces of the nets' triangles near a suspect that
  // have no new point (the others are suspects), in output ids; the
  // centroid of a whole n-gon (not in the output) gets an id past them.
  fn.mesh.tri.resize(suspects);
  std::vector<std::array<std::uint32_t, 3>> neighbour_ids;  // output ids (before finish's merge)
  const std::unordered_set<std::uint64_t> split(split_edges.begin(), split_edges.end());
  std::unordered_map<std::uint32_t, std::uint32_t> past;  // canonical id -> id past the output's
  for (int side = 0; side < 2; ++side) {
    const CutSide& s = cut.sides[side];
    const TriMesh& m = side == 0 ? a : b;
    std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> added;  // the side's triangle -> fold triangles
    for (const auto& [i, t] : overlapping_pairs(suspect_mesh, sb, m, side == 0 ? bvh_a : bvh_b, ctx)) {
      auto [it, fresh] = added.try_emplace(t);
      if (fresh)
        for (std::uint32_t p = s.piece_begin[t]; p < s.piece_begin[t + 1]; ++p) {
          if (!s.keep[p]) continue;
          std::array<std::uint32_t, 3> v{};
          bool ok = true;
          for (std::size_t k = 0; k < 3; ++k) {
            const std::uint32_t id = cut.canon[s.piece[p][k]];
            v[k] = out_index[id];
            if (v[k] == kNil) {
              const auto [pt, first] =
                  past.try_emplace(id, static_cast<std::uint32_t>(out.positions.size() + fn.extra.size()));
              if (first) fn.extra.push_back(cut.position(a, b, id));
              v[k] = pt->second;
            }
            ok = ok && (v[k] >= is_new.size() || !is_new[v[k]]);
          }
          // A face the repair split is among the suspects already.
          for (std::size_t k = 0; k < 3 && ok; ++k)
            ok = !split.contains(fold_directed(std::min(v[k], v[(k + 1) % 3]), std::max(v[k], v[(k + 1) % 3])));
          if (!ok) continue;
          it->second.push_back(static_cast<std::uint32_t>(fn.mesh.tri.size()));
          neighbour_ids.push_back(v);
          fn.mesh.tri.push_back(v);
          fn.face.push_back(kNil);
          fn.origin.push_back({static_cast<std::uint32_t>(side), t});
        }
      for (std::uint32_t j : it->second) pairs.push_back({i, j});
    }
  }
  // The suspects' corners were renamed by finish(); rename all again.
  for (std::uint32_t t = 0; t < suspects; ++t) {
    const auto c = out.face(fn.face[t]);
    fn.mesh.tri[t] = {c[0], c[1], c[2]};
  }
  fn.finish(out.positions);
  // A triangle whose corners rounded onto one line (or point) and was not
  // repaired is flat: the next operand's checks name it (degenerate); not a
  // crossing here (nor for CGAL's self-intersection test).
  std::vector<std::uint8_t> flat(fn.mesh.tri.size(), 0);
  par::for_each_n(ctx, flat.size(), [&](std::size_t t) {
    const auto& v = fn.mesh.tri[t];
    flat[t] = collinear(fn.mesh.p[v[0]], fn.mesh.p[v[1]], fn.mesh.p[v[2]]) ? 1 : 0;
  });
  // The fold net as an open net through the self-check's
  // first_self_crossing: its certified rules and embedded patches decide
  // almost every pair without exact arithmetic (the pieces of one cut
  // triangle are nearly coplanar, where orient3d's filter fails). Where the
  // fold net is no 2-manifold with boundary (merged copies of a pinched
  // vertex), the listed pairs are tested one by one instead.
  std::array<std::uint32_t, 2> pr{kNil, kNil};
  bool decided = false;
  {
    PolygonSoup soup;
    soup.positions = fn.mesh.p;
    std::vector<std::uint32_t> back;
    for (std::uint32_t t = 0; t < fn.mesh.tri.size(); ++t)
      if (!flat[t]) {
        soup.add_face(fn.mesh.tri[t]);
        back.push_back(t);
      }
    TriMesh m;
    if (!back.empty() && build_tri_mesh(soup, "result", m, ctx, true)) {
      Bvh bvh;
      build_bvh(m, bvh, ctx);
      const auto c = first_self_crossing(m, bvh, ctx);
      decided = true;
      if (c[0] != kNil) pr = {back[c[0]], back[c[1]]};
    }
  }
  if (!decided) {
    for (const auto& [i, j] : overlapping_pairs(suspect_mesh, sb, suspect_mesh, sb, ctx))
      if (i < j) pairs.push_back({i, j});
    // Decided in parallel, the first crossing pair in list order reported:
    // the same answer for any thread count.
    std::vector<std::uint8_t> crosses(pairs.size(), 0);
    par::for_each_n(ctx, pairs.size(), [&](std::size_t k) {
      if (flat[pairs[k][0]] || flat[pairs[k][1]]) return;
      crosses[k] = triangles_cross(fn.mesh, pairs[k][0], pairs[k][1]) ? 1 : 0;
    });
    const auto hit = std::find(crosses.begin(), crosses.end(), std::uint8_t{1});
    if (hit != crosses.end()) pr = pairs[static_cast<std::size_t>(hit - crosses.begin())];
  }
  if (pr[0] == kNil) return {};
  // A fold net triangle's corners as the result's vertex ids.
  auto corners_of = [&](std::uint32_t t) -> std::array<std::uint32_t, 3> {
    if (t >= suspects) return neighbour_ids[t - suspects];
    const auto c = out.face(fn.face[t]);
    return {c[0], c[1], c[2]};
  };
  if (pair != nullptr)
    for (std::size_t i = 0; i < 2; ++i) {
      const std::uint32_t t = pr[i];
      const std::array<std::uint32_t, 3> v = corners_of(t);
      for (std::size_t k = 0; k < 3; ++k) {
        pair->v[i][k] = v[k] < out.positions.size() ? v[k] : kNil;
        pair->p[i][k] = fn.mesh.p[fn.mesh.tri[t][k]];
      }
    }
  // The shortest edge of the two triangles within a few ulps, with a new
  // point: the caller collapses it and checks again (the sliver's points
  // snapped together, a move of a few ulps).
  double best = HUGE_VAL;
  for (const std::uint32_t t : pr) {
    const std::array<std::uint32_t, 3> v = corners_of(t);
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t x = v[k], y = v[(k + 1) % 3];
      if (x >= is_new.size() || y >= is_new.size() || !(is_new[x] || is_new[y])) continue;
      const Vec3d &p = out.positions[x], &q = out.positions[y];
      const double len = (p - q).cwiseAbs().maxCoeff(),
                   scale = std::max(p.cwiseAbs().maxCoeff(), q.cwiseAbs().maxCoeff());
      if (len <= 16 * std::numeric_limits<double>::epsilon() * scale && len < best) {
        best = len;
        short_edge = {x, y};
      }
    }
  }
  auto name = [&](std::uint32_t t) {
    if (t < suspects) {
      const Vec3d& p = out.positions[out.face(fn.face[t])[0]];
      std::ostringstream o;
      o.precision(17);
      o << "the cut's triangle at (" << p.x() << ", " << p.y() << ", " << p.z() << ")";
      return o.str();
    }
    const TriMesh& m = fn.origin[t][0] == 0 ? a : b;
    return "face " + std::to_string(m.face_of[fn.origin[t][1]]) + " of " + m.name;
  };
  return fail(ErrorCode::kTopology,
              "net boolean: the result crosses itself once its new points are rounded to doubles: ", name(pr[0]),
              " crosses ", name(pr[1]));
}

std::array<std::uint32_t, 2> pinched_self_crossing(const PolygonSoup& out, const ExecContext& ctx, bool flat_refused) {
  // The result's triangles as build_tri_mesh makes them: each n-gon split
  // by build_tri_mesh itself (alone, as an open net), so the fan or the
  // rounded centroid is the one every later test and the next operand see.
  TriMesh m;
  std::vector<std::uint32_t> face;  // per triangle: the output face
  std::vector<Vec3d> pos(out.positions.begin(), out.positions.end());
  const ExecContext one = [&] {
    ExecContext c = ctx;
    c.threads = 1;
    return c;
  }();
  for (std::uint32_t f = 0; f < out.face_count(); ++f) {
    const auto c = out.face(f);
    if (c.size() == 3) {
      m.tri.push_back({c[0], c[1], c[2]});
      face.push_back(f);
      continue;
    }
    PolygonSoup poly;
    std::vector<std::uint32_t> local(c.size());
    for (std::uint32_t k = 0; k < c.size(); ++k) {
      poly.positions.push_back(out.positions[c[k]]);
      local[k] = k;
    }
    poly.add_face(local);
    TriMesh pm;
    if (!build_tri_mesh(poly, "face", pm, one, true)) return {f, f};  // degenerate: named as it is
    const auto centroid = static_cast<std::uint32_t>(pos.size());
    if (pm.p.size() > c.size()) pos.push_back(pm.p[c.size()]);
    for (const auto& t : pm.tri) {
      std::array<std::uint32_t, 3> v{};
      for (std::size_t k = 0; k < 3; ++k) v[k] = t[k] < c.size() ? c[t[k]] : centroid;
      m.tri.push_back(v);
      face.push_back(f);
    }
  }
  merge_positions(m, [&](std::uint32_t v) -> const Vec3d& { return pos[v]; });
  std::vector<std::uint8_t> flat(m.tri.size(), 0);
  for (std::size_t t = 0; t < m.tri.size(); ++t) {
    const auto& v = m.tri[t];
    flat[t] = collinear(m.p[v[0]], m.p[v[1]], m.p[v[2]]) ? 1 : 0;
    if (flat[t] && flat_refused) return {face[t], face[t]};
  }
  Bvh bvh;
  build_bvh(m, bvh, ctx);
  std::vector<std::array<std::uint32_t, 2>> pairs;
  for (const auto& [i, j] : overlapping_pairs(m, bvh, m, bvh, ctx))
    if (i < j && !flat[i] && !flat[j]) pairs.push_back({i, j});
  // Decided in parallel, the first crossing pair in list order reported:
  // the same answer for any thread count.
  std::vector<std::uint8_t> crosses(pairs.size(), 0);
  par::for_each_n(ctx, pairs.size(),
                  [&](std::size_t k) { crosses[k] = triangles_cross(m, pairs[k][0], pairs[k][1]) ? 1 : 0; });
  const auto hit = std::find(crosses.begin(), crosses.end(), std::uint8_t{1});
  if (hit == crosses.end()) return {kNil, kNil};
  const auto& pr = pairs[static_cast<std::size_t>(hit - crosses.begin())];
  return {face[pr[0]], face[pr[1]]};
}

}  // namespace atelier::net_detail
