// Folds of the rounded result repaired by moving new points (issue 24,
// snap17). The cut is exact; each new point is rounded to a double, and on
// degenerate pairs (near-copies, shared faces, ulp-scale touches) a rounded
// point can carry a sliver through a neighbour. fold15's repair flips flat
// slivers away and collapses edges of at most 16 ulps; what it leaves was
// refused. Here, in the spirit of 3D snap rounding (Devillers, Lazard and
// Lenhardt, "Practical 3D snap rounding", 2018: a point is moved within
// its box, or snapped onto a vertex, until nothing crosses), each crossing
// pair's new points get:
//  1. another rounding: the doubles 1, 2, 4, 8, 16, then 64, 256, 1024
//     ulps away in each coordinate (the exact value is within 2 ulps of
//     the rounded one, so the first steps are its box's other corners; the
//     last ones leave the box, by at most ~2.3e-13 of the coordinates), 26
//     directions per step: the smallest step whose best direction lowers
//     the number of triangles the point's star crosses (counted exactly
//     with triangles_cross), never flat, never onto another corner, never
//     a position the point had before (moves undoing each other would
//     cycle to the budget);
//  2. else a snap: a short edge from it collapsed (fold15's collapse,
//     under the link condition; a move of at most 2^-24 of the
//     coordinates, far below the campaign's volume tolerance), unless the
//     collapse adds a flat triangle (the check leaves those out).
// After each move check_rounded_result runs again on the whole result (it
// alone decides): the repair ends when it finds no crossing, or refuses
// after a budget of rounds. Sequential, in a fixed order: the same bits for
// any thread count. Only on results the certificate and fold15's repair
// left folded, so it costs nothing on the certified path.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "boolean_detail.h"

namespace atelier::net_detail {

namespace {

constexpr int kMaxRounds = 96;                             // whole checks per Boolean
constexpr int kSteps[] = {1, 2, 4, 8, 16, 64, 256, 1024};  // ulps per coordinate

using Tri = std::array<Vec3d, 3>;

std::array<double, 6> box_of(const Tri& t) {
  std::array<double, 6> b{};
  for (int k = 0; k < 3; ++k) {
    b[static_cast<std::size_t>(k)] = std::min({t[0][k], t[1][k], t[2][k]});
    b[static_cast<std::size_t>(k + 3)] = std::max({t[0][k], t[1][k], t[2][k]});
  }
  return b;
}

bool boxes_meet(const std::array<double, 6>& x, const std::array<double, 6>& y) {
  for (std::size_t k = 0; k < 3; ++k)
    if (x[k] > y[k + 3] || y[k] > x[k + 3]) return false;
  return true;
}

/// Exact: x and y meet beyond the corners they share (corners shared by
/// position, as check_rounded_result merges them). `m`: a scratch mesh
/// (degen19: reused, its p and tri cleared; triangles_cross reads nothing
/// else, which a fresh TriMesh leaves empty too).
bool cross(const Tri& x, const Tri& y, TriMesh& m) {
  m.p.clear();
  std::array<std::uint32_t, 3> ix{}, iy{};
  auto id = [&](const Vec3d& p) {
    for (std::uint32_t i = 0; i < m.p.size(); ++i)
      if (m.p[i] == p) return i;
    m.p.push_back(p);
    return static_cast<std::uint32_t>(m.p.size() - 1);
  };
  for (std::size_t k = 0; k < 3; ++k) ix[k] = id(x[k]);
  for (std::size_t k = 0; k < 3; ++k) iy[k] = id(y[k]);
  m.tri.assign({ix, iy});
  return triangles_cross(m, 0, 1);
}

/// One coordinate moved by `steps` ulps (signed).
double ulps(double x, int steps) {
  const double to = steps > 0 ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  for (int i = 0; i < std::abs(steps); ++i) x = std::nextafter(x, to);
  return x;
}

/// The output's faces around new point v (its star, triangles), and the
/// triangles near it (n-gons as fans from their first corner: a filter
/// only, the global check decides), given as positions.
struct Neighbourhood {
  std::vector<std::array<std::uint32_t, 3>> star;
  std::vector<Tri> near;
  std::vector<std::array<double, 6>> near_box;  // box_of(near[i]), once (degen19)
  TriMesh scratch;                              // cross()'s mesh, reused (degen19)
};

Neighbourhood neighbourhood(const PolygonSoup& out, std::uint32_t v, const FoldPair& pair) {
  Neighbourhood nb;
  std::array<double, 6> box{};
  for (std::uint32_t f = 0; f < out.face_count(); ++f) {
    const auto c = out.face(f);
    if (c.size() == 3 && (c[0] == v || c[1] == v || c[2] == v)) nb.star.push_back({c[0], c[1], c[2]});
  }
  if (nb.star.empty()) return nb;
  // The star's box grown by the largest move (16 ulps of its coordinates).
  box = box_of({out.positions[nb.star[0][0]], out.positions[nb.star[0][1]], out.positions[nb.star[0][2]]});
  for (const auto& s : nb.star) {
    const auto b = box_of({out.positions[s[0]], out.positions[s[1]], out.positions[s[2]]});
    for (std::size_t k = 0; k < 3; ++k) {
      box[k] = std::min(box[k], b[k]);
      box[k + 3] = std::max(box[k + 3], b[k + 3]);
    }
  }
  for (std::size_t k = 0; k < 3; ++k) {
    const double grow =
        4096 * std::numeric_limits<double>::epsilon() * std::max(std::abs(box[k]), std::abs(box[k + 3]));
    box[k] -= grow;
    box[k + 3] += grow;
  }
  for (std::uint32_t f = 0; f < out.face_count(); ++f) {
    const auto c = out.face(f);
    if (std::find(c.begin(), c.end(), v) != c.end()) continue;
    for (std::size_t k = 1; k + 1 < c.size(); ++k) {
      const Tri t{out.positions[c[0]], out.positions[c[k]], out.positions[c[k + 1]]};
      if (boxes_meet(box_of(t), box)) nb.near.push_back(t);
    }
  }
  // The crossing pair's triangles that are no output faces (pieces of a
  // whole n-gon about its centroid).
  for (std::size_t i = 0; i < 2; ++i)
    if (std::find(pair.v[i].begin(), pair.v[i].end(), v) == pair.v[i].end()) nb.near.push_back(pair.p[i]);
  nb.near_box.reserve(nb.near.size());
  for (const Tri& t : nb.near) nb.near_box.push_back(box_of(t));
  return nb;
}

/// v at q: the number of pairs its star crosses (star against the
/// triangles near it, and star against star), or -1 when the star is flat
/// there or q falls onto another corner.
/// degen19: the count stops once it reaches `limit` (the value returned is
/// then >= limit, not the whole count). The caller takes q only when its
/// count is below the best so far and passes that best as the limit: every
/// term is 0 or 1, so a partial count at the limit means a whole count at or
/// above it, a q the caller would reject anyway; below the limit the count
/// is the whole one. The -1 cases are decided before any pair is counted.
/// So the move chosen is the same as with whole counts (snap17's), with
/// most of a losing candidate's exact tests left out.
int star_crossings(const PolygonSoup& out, std::uint32_t v, const Vec3d& q, Neighbourhood& nb, int limit) {
  std::vector<Tri> moved;
  for (const auto& s : nb.star) {
    Tri t{};
    for (std::size_t k = 0; k < 3; ++k) {
      if (s[k] != v && out.positions[s[k]] == q) return -1;
      t[k] = s[k] == v ? q : out.positions[s[k]];
    }
    if (collinear(t[0], t[1], t[2])) return -1;
    moved.push_back(t);
  }
  for (const Tri& n : nb.near)
    for (const Vec3d& x : n)
      if (x == q) return -1;
  int n_cross = 0;
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const auto bi = box_of(moved[i]);
    for (std::size_t k = 0; k < nb.near.size(); ++k)
      if (boxes_meet(bi, nb.near_box[k]) && cross(moved[i], nb.near[k], nb.scratch) && ++n_cross >= limit)
        return n_cross;
    for (std::size_t j = i + 1; j < moved.size(); ++j)
      if (boxes_meet(bi, box_of(moved[j])) && cross(moved[i], moved[j], nb.scratch) && ++n_cross >= limit)
        return n_cross;
  }
  return n_cross;
}

/// Another rounding of v under which its star crosses fewer triangles
/// (exactly counted) than where it is: the smallest move that helps, and
/// among the 26 directions of that move the one leaving fewest crossings
/// (the first in a fixed order on ties).
/// `visited`: the (point, position) pairs the repair has had, never taken
/// again (two points' moves undoing each other would cycle to the budget).
bool reround(PolygonSoup& out, std::uint32_t v, const FoldPair& pair,
             std::vector<std::pair<std::uint32_t, Vec3d>>& visited) {
  Neighbourhood nb = neighbourhood(out, v, pair);
  if (nb.star.empty()) return false;
  const Vec3d p = out.positions[v];
  constexpr int kAll = std::numeric_limits<int>::max();
  const int now = star_crossings(out, v, p, nb, kAll);  // whole: the bar every move must pass
  if (now <= 0) return false;  // v's star is clean (or flat): another point's move
  const bool lean = fold_repair_lean().load(std::memory_order_relaxed);
  for (const int step : kSteps) {
    int best = now;
    Vec3d best_q = p;
    // Each coordinate `step` ulps down, as is, and up: ulps() of the same
    // arguments, computed once per step instead of once per direction
    // (degen19; the same doubles, nextafter being exact).
    std::array<std::array<double, 3>, 3> at{};
    if (lean)
      for (int k = 0; k < 3; ++k)
        at[static_cast<std::size_t>(k)] = {ulps(p[k], -step), p[k], ulps(p[k], step)};
    for (int d = 0; d < 27 && best > 0; ++d) {
      if (d == 13) continue;  // no move
      const int dx = d % 3 - 1, dy = d / 3 % 3 - 1, dz = d / 9 - 1;
      const Vec3d q = lean ? Vec3d(at[0][static_cast<std::size_t>(dx + 1)], at[1][static_cast<std::size_t>(dy + 1)],
                                   at[2][static_cast<std::size_t>(dz + 1)])
                           : Vec3d(ulps(p.x(), dx * step), ulps(p.y(), dy * step), ulps(p.z(), dz * step));
      if (!std::isfinite(q.x()) || !std::isfinite(q.y()) || !std::isfinite(q.z())) continue;
      if (std::find(visited.begin(), visited.end(), std::pair(v, q)) != visited.end()) continue;
      const int c = star_crossings(out, v, q, nb, lean ? best : kAll);
      if (c >= 0 && c < best) {
        best = c;
        best_q = q;
      }
    }
    if (best < now) {
      if (std::find(visited.begin(), visited.end(), std::pair(v, p)) == visited.end()) visited.push_back({v, p});
      visited.push_back({v, best_q});
      out.positions[v] = best_q;
      return true;
    }
  }
  return false;
}

/// Triangles with a suspect corner whose corners are collinear.
std::size_t flat_count(const PolygonSoup& out, std::span<const std::uint8_t> suspect) {
  std::size_t n = 0;
  for (std::uint32_t f = 0; f < out.face_count(); ++f) {
    const auto c = out.face(f);
    if (c.size() == 3 && (suspect[c[0]] || suspect[c[1]] || suspect[c[2]]))
      n += collinear(out.positions[c[0]], out.positions[c[1]], out.positions[c[2]]) ? 1 : 0;
  }
  return n;
}

}  // namespace

std::atomic<std::size_t>& fold_repair_count() noexcept {
  static std::atomic<std::size_t> count{0};
  return count;
}

std::atomic<bool>& fold_repair_lean() noexcept {
  static std::atomic<bool> lean{true};
  return lean;
}

Status repair_folds(const Cut& cut, const TriMesh& a, const Bvh& bvh_a, const TriMesh& b, const Bvh& bvh_b,
                    PolygonSoup& out, std::vector<std::uint8_t>& face_side, std::span<const std::uint32_t> out_index,
                    std::span<const std::uint8_t> is_new, std::vector<std::uint64_t>& split_edges,
                    std::vector<std::uint8_t>& suspect, Status st, FoldPair pair, const ExecContext& ctx) {
  std::vector<std::pair<std::uint32_t, Vec3d>> visited;
  for (int round = 0; round < kMaxRounds && !st; ++round) {
    // The pair's new points, each once, in corner order.
    std::vector<std::uint32_t> points;
    for (const auto& t : pair.v)
      for (const std::uint32_t v : t)
        if (v != kNil && v < is_new.size() && is_new[v] && std::find(points.begin(), points.end(), v) == points.end())
          points.push_back(v);
    bool moved = false;
    for (const std::uint32_t v : points)
      if ((moved = reround(out, v, pair, visited))) break;
    if (!moved) {
      // Snap: the edge from a new point of the pair to its nearest
      // neighbour, collapsed (fold15's collapse: the link condition holds,
      // a net's own vertex stays), when short.
      for (const std::uint32_t v : points) {
        std::vector<std::pair<double, std::uint32_t>> by_length;
        for (std::uint32_t f = 0; f < out.face_count(); ++f) {
          const auto c = out.face(f);
          for (std::size_t k = 0; k < c.size(); ++k)
            if (c[k] == v)
              for (const std::uint32_t w : {c[(k + 1) % c.size()], c[(k + c.size() - 1) % c.size()]}) {
                const Vec3d &p = out.positions[v], &q = out.positions[w];
                const double len = (p - q).cwiseAbs().maxCoeff(),
                             scale = std::max(p.cwiseAbs().maxCoeff(), q.cwiseAbs().maxCoeff());
                if (len <= 0x1p-24 * scale) by_length.push_back({len, w});
              }
        }
        std::sort(by_length.begin(), by_length.end());
        by_length.erase(std::unique(by_length.begin(), by_length.end()), by_length.end());
        for (const auto& [len, w] : by_length) {
          PolygonSoup trial = out;
          std::vector<std::uint8_t> sides = face_side;
          std::vector<std::uint64_t> split = split_edges;
          std::vector<std::uint8_t> marks = suspect;
          const std::array<std::uint32_t, 2> e{v, w};
          if (repair_flat_triangles(trial, sides, is_new, split, std::span(&e, 1), &marks) == 0) continue;
          // The check leaves flat triangles out: a collapse must not add any.
          if (flat_count(trial, marks) > flat_count(out, suspect)) continue;
          out = std::move(trial);
          face_side = std::move(sides);
          split_edges = std::move(split);
          suspect = std::move(marks);
          moved = true;
          break;
        }
        if (moved) break;
      }
    }
    if (!moved) return st;
    std::array<std::uint32_t, 2> short_edge{};
    st = check_rounded_result(cut, a, bvh_a, b, bvh_b, out, out_index, suspect, split_edges, short_edge, ctx, &pair);
  }
  if (st) ++fold_repair_count();
  return st;
}

}  // namespace atelier::net_detail
