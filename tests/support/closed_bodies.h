// Closed triangle bodies of revolution (a capsule) and grid garments
// around them, for the collision pass and edge transfer tests.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include "support/shapes.h"
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/garment/collision_pass.h>

namespace atelier::test_bodies {

struct TriBody {
  std::vector<Vec3d> p;
  std::vector<Triangle> t;
};

inline TriBody triangulate(const shapes::Soup& s) {
  TriBody b;
  b.p = s.p;
  for (std::size_t f = 0; f + 1 < s.off.size(); ++f)
    for (std::uint32_t k = s.off[f] + 1; k + 1 < s.off[f + 1]; ++k)
      b.t.push_back({s.idx[s.off[f]], s.idx[k], s.idx[k + 1]});
  return b;
}

/// Surface of revolution about z: profile (rho, z) from south to north pole
/// (rho = 0 at both ends), nu segments around; outward orientation.
inline TriBody revolution(const std::vector<std::array<double, 2>>& prof, int nu) {
  TriBody b;
  const int m = static_cast<int>(prof.size());
  b.p.push_back({0, 0, prof[0][1]});
  for (int j = 1; j + 1 < m; ++j)
    for (int i = 0; i < nu; ++i) {
      const double ph = 2 * M_PI * i / nu;
      b.p.push_back({prof[j][0] * std::cos(ph), prof[j][0] * std::sin(ph), prof[j][1]});
    }
  b.p.push_back({0, 0, prof[m - 1][1]});
  auto at = [&](int j, int i) { return static_cast<std::uint32_t>(1 + (j - 1) * nu + (i % nu)); };
  const auto north = static_cast<std::uint32_t>(b.p.size() - 1);
  for (int i = 0; i < nu; ++i) b.t.push_back({0, at(1, i + 1), at(1, i)});
  for (int j = 1; j + 2 < m; ++j)
    for (int i = 0; i < nu; ++i) {
      b.t.push_back({at(j, i), at(j, i + 1), at(j + 1, i + 1)});
      b.t.push_back({at(j, i), at(j + 1, i + 1), at(j + 1, i)});
    }
  for (int i = 0; i < nu; ++i) b.t.push_back({north, at(m - 2, i), at(m - 2, i + 1)});
  return b;
}

/// Capsule about z: cylinder radius r, |z| <= half, hemispherical caps.
inline TriBody capsule(double r, double half, int nu, int ncap, int nlen) {
  std::vector<std::array<double, 2>> prof;
  for (int k = 0; k <= ncap; ++k) {
    const double a = -M_PI / 2 + (M_PI / 2) * k / ncap;
    prof.push_back({r * std::cos(a), -half + r * std::sin(a)});
  }
  for (int k = 1; k < nlen; ++k) prof.push_back({r, -half + 2 * half * k / nlen});
  for (int k = 0; k <= ncap; ++k) {
    const double a = (M_PI / 2) * k / ncap;
    prof.push_back({r * std::cos(a), half + r * std::sin(a)});
  }
  prof.front()[0] = prof.back()[0] = 0;
  return revolution(prof, nu);
}

/// A garment: an nu x nv grid of points f(i, j), with edges along both
/// directions (wrapping around in i when `wrap`).
struct Patch {
  std::vector<Vec3d> p;
  std::vector<std::array<std::uint32_t, 2>> e;
  NodeAdjacency adj;
};
template <class F>
Patch grid_patch(int nu, int nv, bool wrap, F f) {
  Patch g;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) g.p.push_back(f(i, j));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * nu + (i % nu)); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      if (wrap || i + 1 < nu) g.e.push_back({id(i, j), id(i + 1, j)});
      if (j + 1 < nv) g.e.push_back({id(i, j), id(i, j + 1)});
    }
  auto adj = adjacency_from_edges(g.p.size(), g.e);
  if (!adj) throw Error(adj.status());
  g.adj = std::move(*adj);
  return g;
}

}  // namespace atelier::test_bodies
