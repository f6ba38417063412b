#include <atelier/systems/curvenet/quadrangulate.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <unordered_set>

namespace atelier {

namespace {


std::uint64_t key(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t{a} << 32) | b : (std::uint64_t{b} << 32) | a;
}

struct Front {
  std::vector<Vec3d>& pos;
  QuadPatch& out;
  std::uint32_t b;
  std::unordered_set<std::uint64_t> edges;

  std::uint32_t add_vertex(const Vec3d& p) {
    pos.push_back(p);
    out.interior.push_back(p);
    return static_cast<std::uint32_t>(pos.size() - 1);
  }
  void add_quad(std::uint32_t a, std::uint32_t c, std::uint32_t d, std::uint32_t e) {
    out.quads.push_back({a, c, d, e});
    edges.insert(key(a, c));
    edges.insert(key(c, d));
    edges.insert(key(d, e));
    edges.insert(key(e, a));
  }
  const ChordFilter* forbidden = nullptr;
  /// The edge exists already, or is a chord the caller forbids.
  [[nodiscard]] bool has(std::uint32_t a, std::uint32_t c) const {
    if (edges.count(key(a, c)) != 0) return true;
    return a < b && c < b && forbidden && *forbidden && (*forbidden)(a, c);
  }
  /// Quads (centre, f[s+2i], f[s+2i+1], f[s+2i+2]) around a new centroid.
  void fan(const std::vector<std::uint32_t>& f, std::size_t s) {
    Vec3d c = Vec3d::Zero();
    for (std::uint32_t v : f) c += pos[v];
    const std::uint32_t centre = add_vertex(c / static_cast<double>(f.size()));
    const std::size_t n = f.size();
    for (std::size_t i = 0; i < n / 2; ++i)
      add_quad(centre, f[(s + 2 * i) % n], f[(s + 2 * i + 1) % n], f[(s + 2 * i + 2) % n]);
    ++out.fans;
  }
};

}  // namespace

Expected<QuadPatch> quadrangulate_cycle(std::span<const Vec3d> boundary, const QuadrangulateOptions& opt,
                                        const ChordFilter& forbidden) {
  const std::size_t nb = boundary.size();
  if (nb < 4 || nb % 2 != 0)
    return Status(ErrorCode::kInvalidArgument, "quadrangulate: a cycle of " + std::to_string(nb) +
                                                   " vertices cannot be all quads (needs an even count >= 4)");
  for (std::size_t i = 0; i < nb; ++i)
    if (!boundary[i].allFinite())
      return Status(ErrorCode::kInvalidArgument,
                    "quadrangulate: boundary vertex " + std::to_string(i) + " is not finite");
  QuadPatch out;
  std::vector<Vec3d> pos(boundary.begin(), boundary.end());
  Front fr{pos, out, static_cast<std::uint32_t>(nb), {}, &forbidden};
  // Newell normal of the boundary: the plane angles are measured in.
  Vec3d c0 = Vec3d::Zero();
  for (const Vec3d& p : boundary) c0 += p;
  c0 /= static_cast<double>(nb);
  Vec3d normal = Vec3d::Zero();
  for (std::size_t i = 0; i < nb; ++i) normal += (boundary[i] - c0).cross(boundary[(i + 1) % nb] - c0);
  normal = normal.norm() > 0 ? normal.normalized() : Vec3d::UnitZ();

  std::vector<std::uint32_t> front(nb);
  for (std::uint32_t i = 0; i < nb; ++i) {
    front[i] = i;
    fr.edges.insert(key(i, static_cast<std::uint32_t>((i + 1) % nb)));
  }
  const double corner_max = opt.corner_angle_degrees * kPi / 180.0;
  std::vector<double> angle;
  std::vector<std::size_t> corners;
  while (front.size() > 4) {
    const std::size_t n = front.size();
    auto at = [&](std::size_t i) { return front[i % n]; };
    // Interior angle at each front vertex, measured about the normal.
    angle.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3d& p = pos[front[i]];
      Vec3d u = pos[at(i + 1)] - p, w = pos[at(i + n - 1)] - p;
      u -= u.dot(normal) * normal;
      w -= w.dot(normal) * normal;
      double a = std::atan2(u.cross(w).dot(normal), u.dot(w));
      if (a < 0) a += 2 * kPi;
      angle[i] = a;
    }
    corners.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (angle[i] <= corner_max) corners.push_back(i);
    if (corners.size() < 4 && n >= 8) {
      // Too few corners (a round or lens-shaped front): the sharpest other
      // vertices join them, never next to a corner, until there are four.
      std::vector<std::size_t> order(n);
      for (std::size_t i = 0; i < n; ++i) order[i] = i;
      std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return angle[x] < angle[y]; });
      std::vector<std::uint8_t> is_corner(n, 0);
      for (std::size_t c : corners) is_corner[c] = 1;
      for (std::size_t i : order) {
        if (corners.size() >= 4) break;
        if (is_corner[i] || is_corner[(i + 1) % n] || is_corner[(i + n - 1) % n]) continue;
        is_corner[i] = 1;
        corners.push_back(i);
      }
      std::sort(corners.begin(), corners.end());
    }
    if (corners.size() < 2) {
      corners.clear();
      for (std::size_t j = 0; j < 4; ++j) corners.push_back((j * n) / 4);
    }
    const std::size_t nc = corners.size();
    // Centre fill: every chain has two edges (corners at alternate vertices).
    bool alternate = opt.centre_fill && nc >= 3 && nc * 2 == n;
    for (std::size_t j = 0; alternate && j < nc; ++j) alternate = (corners[(j + 1) % nc] + n - corners[j]) % n == 2;
    if (alternate) {
      fr.fan(front, corners[0] + 1);
      front.clear();
      break;
    }
    // The best chain between consecutive corners: one taking at most half
    // the front, fewest edges, sharpest ends, first in the front.
    using Score = std::tuple<bool, std::size_t, double, std::size_t>;
    bool found = false;
    Score best{};
    std::size_t best_start = 0, best_len = 0;
    for (std::size_t j = 0; j < nc; ++j) {
      const std::size_t i0 = corners[j];
      const std::size_t len = (corners[(j + 1) % nc] + n - i0) % n == 0 ? n : (corners[(j + 1) % nc] + n - i0) % n;
      if (len < 1 || len + 3 > n) continue;  // the row's two sides must be distinct front edges
      const bool closing = 2 * len + 2 == n;
      bool ok = true;
      if (closing) {
        for (std::size_t i = 1; i < len && ok; ++i) ok = !fr.has(at(i0 + i), at(i0 + 2 * len + 1 - i));
      } else if (len == 1) {
        ok = !fr.has(at(i0 + n - 1), at(i0 + 2));
      }
      if (!ok) continue;
      const Score s{len + 1 > n / 2, len, angle[i0] + angle[(i0 + len) % n], i0};
      if (!found || s < best) {
        found = true;
        best = s;
        best_start = i0;
        best_len = len;
      }
    }
    if (!found) {
      fr.fan(front, 0);
      front.clear();
      break;
    }
    const std::size_t i0 = best_start, len = best_len;
    if (2 * len + 2 == n) {
      // Closing row: the opposite side has as many edges as the chain.
      for (std::size_t i = 0; i < len; ++i)
        fr.add_quad(at(i0 + i), at(i0 + i + 1), at(i0 + 2 * len + 1 - (i + 1)), at(i0 + 2 * len + 1 - i));
      ++out.closing_rows;
      front.clear();
      break;
    }
    // A row along the chain p_0 .. p_len: eq. (3) for its inner vertices.
    std::vector<std::uint32_t> q(len + 1);
    q[0] = at(i0 + n - 1);
    q[len] = at(i0 + len + 1);
    const Vec3d v0 = pos[q[0]] - pos[at(i0)];
    const Vec3d vn = pos[q[len]] - pos[at(i0 + len)];
    std::vector<double> arc(len + 1, 0.0);
    for (std::size_t i = 0; i < len; ++i) arc[i + 1] = arc[i] + (pos[at(i0 + i + 1)] - pos[at(i0 + i)]).norm();
    for (std::size_t i = 1; i < len; ++i) {
      const double s = arc[len] > 0 ? arc[i] / arc[len] : static_cast<double>(i) / static_cast<double>(len);
      q[i] = fr.add_vertex(pos[at(i0 + i)] + (1.0 - s) * v0 + s * vn);
    }
    for (std::size_t i = 0; i < len; ++i) fr.add_quad(at(i0 + i), at(i0 + i + 1), q[i + 1], q[i]);
    ++out.rows;
    std::vector<std::uint32_t> next;
    next.reserve(n - 2);
    for (std::size_t i = 1; i < len; ++i) next.push_back(q[i]);
    for (std::size_t k = i0 + len + 1; k < i0 + n; ++k) next.push_back(at(k));  // q_len ... q_0 and the rest
    front = std::move(next);
  }
  if (front.size() == 4) fr.add_quad(front[0], front[1], front[2], front[3]);
  return out;
}

}  // namespace atelier
