// The benchmarks' synthetic input: an n x n grid of cells, two triangles per
// cell (2 n^2 faces), gently waved in z, as flat arrays for add_polygon_surface.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <atelier/engine/math.h>

namespace atelier::bench {

struct GridArrays {
  std::vector<Vec3d> positions;
  std::vector<std::uint32_t> offsets, nodes;
};

inline GridArrays wavy_grid(int n) {
  GridArrays a;
  a.positions.reserve(static_cast<std::size_t>(n + 1) * (n + 1));
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) a.positions.emplace_back(i, j, 0.05 * std::sin(0.1 * i) * std::cos(0.1 * j));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  a.offsets.push_back(0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      for (auto v : {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)})
        a.nodes.push_back(v);
      a.offsets.push_back(static_cast<std::uint32_t>(a.nodes.size() - 3));
      a.offsets.push_back(static_cast<std::uint32_t>(a.nodes.size()));
    }
  return a;
}

}  // namespace atelier::bench
