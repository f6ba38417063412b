// Paper mode of the net Booleans (seed 004 section 3, Fig. 2): on the exact
// result, the points of A's intersection polygon (on A's edges) and of B's
// (on B's edges) along each intersection curve are paired by one of the
// paper's correspondences and each pair is merged at its midpoint; points
// without a partner stay (the paper inserts them into the merged polygon).
//
// Departures (docs/glossary.md): a pair must be adjacent on the curve (the
// exact result interleaves the two polygons along one curve, and merging
// non-adjacent points would pinch the points between them); a merge that
// would break the 2-manifold (link condition) or flip a face is skipped.
// Correspondences:
//   visual       mutual nearest neighbours along the curve (short edges);
//   topological  the most pairs (every point of the smaller polygon matched
//                where the interleaving allows), shortest total length among
//                those, by dynamic programming around each curve;
//   window2/4    the topological rule inside windows of 2 or 4 points of the
//                curve, the visual rule across windows.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>

#include "boolean_detail.h"

namespace atelier::net_detail {

namespace {

/// Curves as cyclic vertex sequences (vertices of degree 2 in the curve graph;
/// branching curves are split at their branch vertices into open chains).
std::vector<std::vector<std::uint32_t>> curves(std::span<const std::array<std::uint32_t, 2>> edges, std::size_t nv,
                                               std::vector<std::uint8_t>& cyclic) {
  std::vector<std::vector<std::uint32_t>> adj(nv);
  for (const auto& e : edges) {
    adj[e[0]].push_back(e[1]);
    adj[e[1]].push_back(e[0]);
  }
  for (auto& a : adj) std::sort(a.begin(), a.end());
  std::vector<std::uint8_t> seen(nv, 0);
  std::vector<std::vector<std::uint32_t>> out;
  for (std::uint32_t s = 0; s < nv; ++s) {
    if (seen[s] || adj[s].size() != 2) continue;
    std::vector<std::uint32_t> c{s};
    seen[s] = 1;
    std::uint32_t prev = s, cur = adj[s][0];
    bool closed = false;
    while (true) {
      if (cur == s) {
        closed = true;
        break;
      }
      if (seen[cur] || adj[cur].size() != 2) break;
      seen[cur] = 1;
      c.push_back(cur);
      const std::uint32_t next = adj[cur][0] == prev ? adj[cur][1] : adj[cur][0];
      prev = cur;
      cur = next;
    }
    out.push_back(std::move(c));
    cyclic.push_back(closed ? 1 : 0);
  }
  return out;
}

}  // namespace

Status apply_paper_mode(PolygonSoup& out, std::span<const std::array<std::uint32_t, 2>> curve_edges,
                        std::span<const std::uint8_t> from_a, std::span<const std::uint8_t> from_b, int corr,
                        std::size_t& merged, std::size_t& vertices, std::size_t& irregular, std::size_t& vmin,
                        std::size_t& vmax, double& vmean, std::vector<std::uint32_t>& seam) {
  const std::size_t nv = out.positions.size();
  std::vector<std::uint8_t> cyclic;
  const auto cs = curves(curve_edges, nv, cyclic);
  auto dist = [&](std::uint32_t x, std::uint32_t y) { return (out.positions[x] - out.positions[y]).norm(); };
  // A-point / B-point only: a point on edges of both nets is already shared.
  auto kind = [&](std::uint32_t v) { return from_a[v] && !from_b[v] ? 1 : (from_b[v] && !from_a[v] ? 2 : 0); };
  std::vector<std::array<std::uint32_t, 2>> pairs;
  for (std::size_t ci = 0; ci < cs.size(); ++ci) {
    const auto& c = cs[ci];
    const std::size_t n = c.size();
    if (n < 2) continue;
    const bool loop = cyclic[ci] != 0;
    // Candidate pair k joins c[k] and c[k+1] (an A-point and a B-point).
    const std::size_t links = loop ? n : n - 1;
    auto candidate = [&](std::size_t k) {
      const int x = kind(c[k]), y = kind(c[(k + 1) % n]);
      return x != 0 && y != 0 && x != y;
    };
    auto length = [&](std::size_t k) { return dist(c[k], c[(k + 1) % n]); };
    std::vector<std::uint8_t> take(links, 0);
    auto visual = [&](std::size_t k) {
      // Mutual nearest: no shorter candidate link at either end.
      if (!candidate(k)) return false;
      const std::size_t before = (k + links - 1) % links, after = (k + 1) % links;
      const bool has_before = loop || k > 0, has_after = loop || k + 1 < links;
      if (has_before && candidate(before) && length(before) < length(k)) return false;
      if (has_after && candidate(after) && length(after) <= length(k)) return false;
      return true;
    };
    // Max matching with min length on a path of links [b, e) (no two adjacent).
    auto matching = [&](std::size_t b, std::size_t e) {
      const std::size_t m = e - b;
      std::vector<std::pair<int, double>> best(m + 2, {0, 0.0});  // best over links [i, e)
      std::vector<std::uint8_t> pick(m + 2, 0);
      for (std::size_t i = m; i-- > 0;) {
        auto skip = best[i + 1];
        std::pair<int, double> use{-1, 0.0};
        if (candidate(b + i)) use = {best[i + 2].first + 1, best[i + 2].second + length(b + i)};
        const bool better =
            use.first > skip.first || (use.first == skip.first && use.first > 0 && use.second < skip.second);
        best[i] = better ? use : skip;
        pick[i] = better ? 1 : 0;
      }
      for (std::size_t i = 0; i < m;) {
        if (pick[i]) {
          take[b + i] = 1;
          i += 2;
        } else {
          ++i;
        }
      }
    };
    if (corr == 0) {
      for (std::size_t k = 0; k < links; ++k) take[k] = visual(k) ? 1 : 0;
    } else {
      const std::size_t window = corr == 1 ? links : (corr == 2 ? 2 : 4);
      // A cycle is cut at link 0 (left out, then the path; the cheap and
      // deterministic way to turn the cycle into paths).
      const std::size_t first = loop && window == links ? 1 : 0;
      for (std::size_t b = first; b < links; b += window) matching(b, std::min(links, b + window));
      if (window != links)
        for (std::size_t k = 0; k < links; ++k) {
          const std::size_t before = (k + links - 1) % links, after = (k + 1) % links;
          const bool free_ends = !(loop || k > 0 ? take[before] : 0) && !(loop || k + 1 < links ? take[after] : 0);
          if (!take[k] && free_ends && visual(k)) take[k] = 1;
        }
    }
    for (std::size_t k = 0; k < links; ++k) {
      // No two taken links may share a point (a cycle's last and first).
      if (take[k] && loop && k + 1 == links && take[0]) continue;
      if (take[k]) pairs.push_back({c[k], c[(k + 1) % n]});
    }
  }

  // Merge each pair at its midpoint (an edge collapse), keeping the net a
  // 2-manifold with no flipped face.
  std::vector<std::uint8_t> dead(out.face_count(), 0);
  std::vector<std::vector<std::uint32_t>> faces_of(nv);
  for (std::uint32_t f = 0; f < out.face_count(); ++f)
    for (std::uint32_t v : out.face(f)) faces_of[v].push_back(f);
  std::vector<std::vector<std::uint32_t>> corners(out.face_count());
  for (std::uint32_t f = 0; f < out.face_count(); ++f) corners[f].assign(out.face(f).begin(), out.face(f).end());
  auto neighbours = [&](std::uint32_t v) {
    std::vector<std::uint32_t> r;
    for (std::uint32_t f : faces_of[v]) {
      if (dead[f]) continue;
      const auto& c = corners[f];
      for (std::size_t k = 0; k < c.size(); ++k)
        if (c[k] == v) {
          r.push_back(c[(k + 1) % c.size()]);
          r.push_back(c[(k + c.size() - 1) % c.size()]);
        }
    }
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    return r;
  };
  auto normal = [&](const std::vector<std::uint32_t>& c, const std::vector<Vec3d>& p) {
    Vec3d n = Vec3d::Zero();
    for (std::size_t k = 0; k < c.size(); ++k) n += p[c[k]].cross(p[c[(k + 1) % c.size()]]);
    return n;
  };
  std::vector<std::uint8_t> moved(nv, 0);
  merged = 0;
  for (const auto& [x, y] : pairs) {
    if (moved[x] || moved[y]) continue;
    // Link condition: common neighbours are the opposite corners of the
    // triangles on edge xy (a polygon on xy just loses a corner).
    std::vector<std::uint32_t> nx = neighbours(x), ny = neighbours(y), common;
    std::set_intersection(nx.begin(), nx.end(), ny.begin(), ny.end(), std::back_inserter(common));
    std::vector<std::uint32_t> on_edge, opposite;
    for (std::uint32_t f : faces_of[x])
      if (!dead[f] && std::find(corners[f].begin(), corners[f].end(), y) != corners[f].end()) {
        on_edge.push_back(f);
        if (corners[f].size() == 3)
          for (std::uint32_t v : corners[f])
            if (v != x && v != y) opposite.push_back(v);
      }
    std::sort(opposite.begin(), opposite.end());
    if (on_edge.size() != 2 || common != opposite) continue;
    const Vec3d mid = 0.5 * (out.positions[x] + out.positions[y]);
    std::vector<Vec3d> trial = out.positions;
    trial[x] = mid;
    bool flips = false;
    std::vector<std::uint32_t> touched = faces_of[x];
    touched.insert(touched.end(), faces_of[y].begin(), faces_of[y].end());
    for (std::uint32_t f : touched) {
      if (dead[f] || std::find(on_edge.begin(), on_edge.end(), f) != on_edge.end()) continue;
      std::vector<std::uint32_t> after = corners[f];
      for (auto& v : after)
        if (v == y) v = x;
      if (normal(corners[f], out.positions).dot(normal(after, trial)) <= 0) flips = true;
    }
    if (flips) continue;
    out.positions[x] = mid;
    for (std::uint32_t f : on_edge) {
      auto& c = corners[f];
      if (c.size() == 3) {
        dead[f] = 1;
      } else {
        c.erase(std::find(c.begin(), c.end(), y));
      }
    }
    for (std::uint32_t f : faces_of[y]) {
      if (dead[f]) continue;
      for (auto& v : corners[f])
        if (v == y) v = x;
      faces_of[x].push_back(f);
    }
    faces_of[y].clear();
    moved[x] = moved[y] = 1;
    ++merged;
  }
  // Compact.
  PolygonSoup r;
  std::vector<std::uint32_t> index(nv, kNil);
  for (std::uint32_t f = 0; f < corners.size(); ++f) {
    if (dead[f]) continue;
    std::vector<std::uint32_t> c;
    for (std::uint32_t v : corners[f]) {
      if (index[v] == kNil) {
        index[v] = static_cast<std::uint32_t>(r.positions.size());
        r.positions.push_back(out.positions[v]);
      }
      c.push_back(index[v]);
    }
    r.add_face(c);
  }
  // Valences of the merged polygons' vertices.
  std::vector<std::set<std::uint32_t>> nb;
  nb.resize(r.positions.size());
  for (std::size_t f = 0; f < r.face_count(); ++f) {
    const auto c = r.face(f);
    for (std::size_t k = 0; k < c.size(); ++k) {
      nb[c[k]].insert(c[(k + 1) % c.size()]);
      nb[c[(k + 1) % c.size()]].insert(c[k]);
    }
  }
  std::vector<std::uint8_t> on_curve(nv, 0);
  for (const auto& e : curve_edges) on_curve[e[0]] = on_curve[e[1]] = 1;
  vertices = irregular = vmax = 0;
  vmin = std::numeric_limits<std::size_t>::max();
  double sum = 0;
  std::vector<std::uint8_t> counted(r.positions.size(), 0);
  for (std::uint32_t v = 0; v < nv; ++v) {
    if (!on_curve[v] || index[v] == kNil || counted[index[v]]) continue;
    counted[index[v]] = 1;
    const std::size_t val = nb[index[v]].size();
    ++vertices;
    irregular += val != 6;
    vmin = std::min(vmin, val);
    vmax = std::max(vmax, val);
    sum += static_cast<double>(val);
  }
  if (vertices == 0) vmin = 0;
  vmean = vertices ? sum / static_cast<double>(vertices) : 0.0;
  std::vector<std::uint32_t> kept;
  for (std::uint32_t v : seam)
    if (v < nv && index[v] != kNil) kept.push_back(index[v]);
  std::sort(kept.begin(), kept.end());
  kept.erase(std::unique(kept.begin(), kept.end()), kept.end());
  seam = std::move(kept);
  out = std::move(r);
  return {};
}

}  // namespace atelier::net_detail
