// Shewchuk's exact arithmetic on doubles (Adaptive Precision Floating-Point
// Arithmetic and Fast Robust Geometric Predicates, 1997): Two-Sum
// (Theorem 7) and Grow-Expansion with zero elimination (Theorem 10), shared
// by the cofactor stage of orient3d (boolean_exact.cpp) and the level-plane
// rounding (round_exact.cpp).
#pragma once

#include <array>
#include <cstddef>

namespace atelier::net_detail {

/// a + b = s + e exactly, s the rounded sum.
inline void two_sum(double a, double b, double& s, double& e) noexcept {
  s = a + b;
  const double bv = s - a, av = s - bv;
  e = (a - av) + (b - bv);
}

/// An exact sum of doubles as a nonoverlapping expansion in increasing
/// magnitude, in room for N components; its sign is its last (largest)
/// component's. Adding to an m-component expansion gives at most m + 1.
/// The room is left uninitialised (components [0, n) are set before they
/// are read: zeroing it was a sixth of the cofactor's time on Cray).
template <std::size_t N>
struct GrowExpansion {
  std::array<double, N> e;
  std::size_t n = 0;
  bool full = false;  // more components than room: the caller gives up
  void add(double b) noexcept {
    if (b == 0.0) return;
    double q = b;
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) {
      double h;
      two_sum(q, e[i], q, h);
      if (h != 0.0) e[k++] = h;
    }
    if (q != 0.0) {
      if (k == e.size()) {
        full = true;
        return;
      }
      e[k++] = q;
    }
    n = k;
  }
};

}  // namespace atelier::net_detail
