// Zero-length edges of a pinched result merged away (issue 24, flat19).
//
// Rounding a Boolean's new points to doubles can put two ids at one
// position (two exact points rounded together, or a new point rounded onto
// a net's vertex). fold15's collapse removes such an edge under the link
// condition before unpinch; where it could not, the result keeps a face
// with two corners at one position (a flat face; seed 1 case 43's chain of
// the degenerate campaign, the union of two icospheres sharing vertices),
// which CGAL's exact self-intersection test counts as crossing.
//
// The two ids are at one position, so identifying them moves nothing: the
// faces using the edge lose the repeated corner (a triangle disappears, it
// had no area), every other face keeps its geometry, and the volume is the
// same. The merge is taken when the result stays a 2-manifold about the
// kept id: every edge at it in exactly two faces, one each way, and its
// faces one fan (else the copies are a pinch unpinch made on purpose, or
// the link condition fails). Otherwise the edge is left and the Boolean's
// final guard (pinched_self_crossing with flat faces refused) refuses the
// result: re-triangulating the neighbours of such a flat face is not done
// (docs/glossary.md, "A pinched result's self-test").
#include <algorithm>
#include <numeric>

#include "boolean_detail.h"

namespace atelier::net_detail {

namespace {

using Face = std::vector<std::uint32_t>;

/// The face with every w renamed u and repeated consecutive corners
/// dropped (cyclically); fewer than 3 corners when it had no area left.
Face renamed(const Face& c, std::uint32_t w, std::uint32_t u) {
  Face r;
  r.reserve(c.size());
  for (std::uint32_t x : c) {
    const std::uint32_t y = x == w ? u : x;
    if (r.empty() || r.back() != y) r.push_back(y);
  }
  while (r.size() > 1 && r.front() == r.back()) r.pop_back();
  return r;
}

/// Whether faces (all the faces with corner u, as they would be) leave u a
/// 2-manifold vertex: u once per face, each edge at u in exactly one face
/// each way, and the faces one fan about u.
bool manifold_at(std::span<const Face> faces, std::uint32_t u) {
  std::vector<std::array<std::uint32_t, 2>> in_out;  // per face: the corner before u, after u
  for (const Face& c : faces) {
    if (std::count(c.begin(), c.end(), u) != 1) return false;
    const auto k = static_cast<std::size_t>(std::find(c.begin(), c.end(), u) - c.begin());
    in_out.push_back({c[(k + c.size() - 1) % c.size()], c[(k + 1) % c.size()]});
  }
  if (in_out.empty()) return false;
  std::vector<std::uint32_t> before, after;
  for (const auto& [a, b] : in_out) {
    before.push_back(a);
    after.push_back(b);
  }
  std::sort(before.begin(), before.end());
  std::sort(after.begin(), after.end());
  // Each edge z -> u once and u -> z once: the same neighbours both ways, none twice.
  if (before != after || std::adjacent_find(before.begin(), before.end()) != before.end()) return false;
  // One fan: from a face with u -> b, the next about u has b -> u.
  std::size_t f = 0, seen = 0;
  do {
    const std::uint32_t b = in_out[f][1];
    f = static_cast<std::size_t>(std::find_if(in_out.begin(), in_out.end(), [&](const auto& e) { return e[0] == b; }) -
                                 in_out.begin());
    ++seen;
  } while (f != 0 && seen <= in_out.size());
  return seen == in_out.size();
}

}  // namespace

std::atomic<std::size_t>& flat_merge_count() noexcept {
  static std::atomic<std::size_t> n{0};
  return n;
}

FlatMerge merge_flat_edges(PolygonSoup& out, std::vector<std::uint8_t>& face_side, std::vector<std::uint32_t>& remap) {
  FlatMerge done;
  remap.clear();
  const std::size_t nv = out.positions.size();
  auto zero_edges = [&](const std::vector<Face>& faces, const std::vector<std::uint8_t>& gone) {
    std::vector<std::array<std::uint32_t, 2>> e;
    for (std::size_t f = 0; f < faces.size(); ++f) {
      if (gone[f]) continue;
      const Face& c = faces[f];
      for (std::size_t k = 0; k < c.size(); ++k) {
        const std::uint32_t u = c[k], w = c[(k + 1) % c.size()];
        if (u != w && out.positions[u] == out.positions[w]) e.push_back({std::min(u, w), std::max(u, w)});
      }
    }
    std::sort(e.begin(), e.end());
    e.erase(std::unique(e.begin(), e.end()), e.end());
    return e;
  };
  std::vector<Face> faces(out.face_count());
  for (std::size_t f = 0; f < faces.size(); ++f) faces[f].assign(out.face(f).begin(), out.face(f).end());
  std::vector<std::uint8_t> gone(faces.size(), 0);
  auto edges = zero_edges(faces, gone);
  if (edges.empty()) return done;
  // Faces per vertex (kept current as faces change: few edges, small stars).
  std::vector<std::vector<std::uint32_t>> star(nv);
  for (std::uint32_t f = 0; f < faces.size(); ++f)
    for (std::uint32_t x : faces[f]) star[x].push_back(f);
  auto unstar = [&](std::uint32_t f) {
    for (std::uint32_t x : faces[f]) {
      auto& s = star[x];
      s.erase(std::remove(s.begin(), s.end(), f), s.end());
    }
  };
  auto restar = [&](std::uint32_t f) {
    for (std::uint32_t x : faces[f])
      if (std::find(star[x].begin(), star[x].end(), f) == star[x].end()) star[x].push_back(f);
  };
  std::vector<std::uint32_t> alias(nv);
  std::iota(alias.begin(), alias.end(), 0u);
  // Each pass takes the zero-length edges left by the last; a merge removes
  // at least one face (the flat one), and the passes are capped at 8.
  for (int pass = 0; pass < 8 && !edges.empty(); ++pass) {
    for (const auto& [u, w] : edges) {
      if (alias[u] != u || alias[w] != w) continue;  // one of them merged in this pass: next pass
      // The faces about u or w, as they would be with w renamed u.
      std::vector<std::uint32_t> about;
      for (std::uint32_t x : {u, w})
        for (std::uint32_t f : star[x])
          if (!gone[f]) about.push_back(f);
      std::sort(about.begin(), about.end());
      about.erase(std::unique(about.begin(), about.end()), about.end());
      std::vector<Face> after;
      std::vector<std::uint32_t> kept;
      for (std::uint32_t f : about) {
        Face r = renamed(faces[f], w, u);
        if (r.size() >= 3) {
          after.push_back(std::move(r));
          kept.push_back(f);
        }
      }
      if (manifold_at(after, u)) {
        for (std::uint32_t f : about) unstar(f);
        for (std::uint32_t f : about) gone[f] = 1;
        for (std::size_t i = 0; i < kept.size(); ++i) {
          faces[kept[i]] = std::move(after[i]);
          gone[kept[i]] = 0;
          restar(kept[i]);
        }
        alias[w] = u;
        ++done.merged;
      }
    }
    edges = zero_edges(faces, gone);
  }
  done.left = edges.size();
  // Compact: the merged ids and any id no face uses are dropped.
  std::vector<std::uint8_t> used(nv, 0);
  for (std::size_t f = 0; f < faces.size(); ++f)
    if (!gone[f])
      for (std::uint32_t x : faces[f]) used[x] = 1;
  remap.assign(nv, kNil);
  PolygonSoup r;
  for (std::uint32_t v = 0; v < nv; ++v)
    if (used[v]) {
      remap[v] = static_cast<std::uint32_t>(r.positions.size());
      r.positions.push_back(out.positions[v]);
    }
  for (std::uint32_t v = 0; v < nv; ++v) {
    std::uint32_t a = v;
    while (alias[a] != a) a = alias[a];
    if (!used[v] && used[a]) remap[v] = remap[a];
  }
  std::vector<std::uint8_t> sides;
  Face c;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (gone[f]) continue;
    c.clear();
    for (std::uint32_t x : faces[f]) c.push_back(remap[x]);
    r.add_face(c);
    sides.push_back(face_side[f]);
  }
  out = std::move(r);
  face_side = std::move(sides);
  return done;
}

}  // namespace atelier::net_detail
