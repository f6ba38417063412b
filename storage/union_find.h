// Disjoint sets over 0..n-1 (union by smallest root, path halving), shared by
// the topology counts, the sketch cut's pieces and the net Booleans' parts.
#pragma once

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace atelier {

/// The root of a set is its smallest member, so sets come out ordered and
/// independent of the order of unions (results never depend on scheduling).
struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  [[nodiscard]] std::uint32_t find(std::uint32_t x) noexcept {
    while (parent[x] != x) {
      parent[x] = parent[parent[x]];
      x = parent[x];
    }
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) noexcept {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace atelier
