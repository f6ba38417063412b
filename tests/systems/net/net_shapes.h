// Closed test nets for the net Booleans: boxes (quads), UV spheres (quads and
// triangle fans, from support/shapes.h), icospheres (triangles), and the
// checks every result must pass.
#pragma once

#include <atelier/storage/builder.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/net/boolean.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "support/shapes.h"

namespace atelier::net_test {

/// Axis-aligned box [lo, hi] as 6 outward quads.
/// The four Boolean operations, for tests that run them all.
inline constexpr BooleanOp kAllOps[] = {BooleanOp::kUnion, BooleanOp::kIntersection, BooleanOp::kAMinusB,
                                        BooleanOp::kBMinusA};

inline PolygonSoup box(const Vec3d& lo, const Vec3d& hi) {
  PolygonSoup s;
  for (int i = 0; i < 8; ++i)
    s.positions.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const std::uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) s.add_face(f);
  return s;
}

/// Box split into triangles (two per side).
inline PolygonSoup box_triangles(const Vec3d& lo, const Vec3d& hi) {
  const PolygonSoup q = box(lo, hi);
  PolygonSoup s;
  s.positions = q.positions;
  for (std::size_t f = 0; f < q.face_count(); ++f) {
    const auto c = q.face(f);
    s.add_face(std::array<std::uint32_t, 3>{c[0], c[1], c[2]});
    s.add_face(std::array<std::uint32_t, 3>{c[0], c[2], c[3]});
  }
  return s;
}

inline PolygonSoup from_shapes(const shapes::Soup& in) {
  PolygonSoup s;
  s.positions = in.p;
  s.face_offsets = in.off;
  s.face_nodes = in.idx;
  return s;
}

/// Icosphere: the icosahedron subdivided `level` times, projected on the sphere.
inline PolygonSoup icosphere(int level, double r, const Vec3d& centre) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3d> p = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<std::uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& x : p) x.normalize();
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto m = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back((p[a] + p[b]).normalized());
      return mid[key] = static_cast<std::uint32_t>(p.size() - 1);
    };
    std::vector<std::array<std::uint32_t, 3>> g;
    for (const auto& x : f) {
      const std::uint32_t a = m(x[0], x[1]), b = m(x[1], x[2]), c = m(x[2], x[0]);
      g.push_back({x[0], a, c});
      g.push_back({x[1], b, a});
      g.push_back({x[2], c, b});
      g.push_back({a, b, c});
    }
    f = std::move(g);
  }
  PolygonSoup s;
  for (const auto& x : p) s.positions.push_back(centre + r * x);
  for (const auto& x : f) s.add_face(x);
  return s;
}

/// Right prism over a regular n-gon of circumradius r about the z axis
/// through `centre`, from z0 to z1: n quads and two n-gon caps (split
/// around their centroid by the Booleans).
inline PolygonSoup prism(int n, double r, const Vec3d& centre, double z0, double z1) {
  PolygonSoup s;
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < n; ++i) {
      const double t = 2.0 * M_PI * i / n;
      s.positions.emplace_back(centre.x() + r * std::cos(t), centre.y() + r * std::sin(t), k ? z1 : z0);
    }
  const auto u = static_cast<std::uint32_t>(n);
  std::vector<std::uint32_t> bottom, top;
  for (std::uint32_t i = 0; i < u; ++i) {
    bottom.push_back(u - 1 - i);
    top.push_back(u + i);
    s.add_face(std::array<std::uint32_t, 4>{i, (i + 1) % u, u + (i + 1) % u, u + i});
  }
  s.add_face(bottom);
  s.add_face(top);
  return s;
}

/// Two random boxes on a coarse grid (steps of 0.5 in [0, 2.5]): faces
/// coplanar, edges collinear, vertices on faces all the time. `seed` is a
/// linear congruential state, advanced.
inline void grid_box_pair(std::uint64_t& seed, Vec3d (&lo)[2], Vec3d (&hi)[2]) {
  auto next = [&] {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<int>((seed >> 33) % 5);
  };
  for (int s = 0; s < 2; ++s)
    for (int k = 0; k < 3; ++k) {
      int x = next(), y = next();
      if (x == y) y = x + 1;
      lo[s][k] = 0.5 * std::min(x, y);
      hi[s][k] = 0.5 * std::max(x, y);
    }
}

/// A slab much larger than its cut, as Cray_right (corners at FLT_MAX as its
/// OBJ writes them, top at z = -100, square faces split along a diagonal).
inline PolygonSoup flt_max_slab() {
  const double big = 340282346999999984391321947108527833088.0;
  return box_triangles({-big, -big, -big}, {big, big, -100.0});
}

/// n icospheres (level 2, radius 2.5e4: Cray_left's size) at random
/// rotations and centres about the slab's top (seed 38: the placements of
/// NetRefineFast.ASlabMuchLargerThanItsCutTakesTheProjectedPath).
inline std::vector<PolygonSoup> spheres_across_the_slab(int n) {
  std::mt19937 rng(38);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<PolygonSoup> out;
  for (int trial = 0; trial < n; ++trial) {
    const Eigen::Quaterniond q(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized());
    const Vec3d centre(1000.0 * unit(rng), 1000.0 * unit(rng), -100.0 + 5000.0 * unit(rng));
    PolygonSoup s = icosphere(2, 2.5e4, {0, 0, 0});
    for (Vec3d& p : s.positions) p = q.toRotationMatrix() * p + centre;
    out.push_back(std::move(s));
  }
  return out;
}

/// x and y in one soup: y's ids follow x's.
inline PolygonSoup joined(const PolygonSoup& x, const PolygonSoup& y) {
  PolygonSoup s = x;
  const auto n = static_cast<std::uint32_t>(s.positions.size());
  for (const auto& p : y.positions) s.positions.push_back(p);
  for (std::size_t f = 0; f < y.face_count(); ++f) {
    std::vector<std::uint32_t> c(y.face(f).begin(), y.face(f).end());
    for (auto& v : c) v += n;
    s.add_face(c);
  }
  return s;
}

/// Two overlapping boxes in one net ([.5, 2]^3 and [1, 3]^3): closed,
/// oriented and manifold, but intersecting itself.
inline PolygonSoup two_boxes_in_one_net() { return joined(box({.5, .5, .5}, {2, 2, 2}), box({1, 1, 1}, {3, 3, 3})); }

/// Builds the result into a Model: closed (no boundary), consistently
/// oriented, 2-manifold (the builder refuses the rest), validate() clean.
inline ::testing::AssertionResult closed_model(const PolygonSoup& s) {
  Model m;
  auto surf = add_polygon_surface(m, "result", s);
  if (!surf) return ::testing::AssertionFailure() << surf.status().to_string();
  if (Status v = validate(m); !v) return ::testing::AssertionFailure() << v.to_string();
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e)
    if (m.alive(EdgeIdx{e}) && m.is_boundary(EdgeIdx{e})) return ::testing::AssertionFailure() << "open edge " << e;
  return ::testing::AssertionSuccess();
}

}  // namespace atelier::net_test
