// New points rounded to nearest without Mpzf, where their closed form is
// short enough for Shewchuk's exact expansions (issue 24, cray16): an edge
// through a triangle lying in a plane of constant coordinate (Cray's slab,
// CAD boxes). The answer is the exact value rounded to nearest, ties to
// even, +0 for a zero: the same doubles as round 11's Mpzf rounding
// (boolean_exact.cpp, rounded_point), which stays the path for every other
// point and for the cases refused here. A separate file because it needs
// no CGAL (boolean_exact.cpp is the only file that sees it).
#include <array>
#include <cmath>

#include "boolean_detail.h"
#include "expansion.h"

namespace atelier::net_detail {

namespace {

// Shewchuk's expansions (expansion.h), with Two-Product by a fused
// multiply-add.
struct Sum : GrowExpansion<24> {
  /// x y exactly (head and tail), both factors in the range checked below.
  void add_product(double x, double y) noexcept {
    const double h = x * y;
    add(std::fma(x, y, -h));
    add(h);
  }
  [[nodiscard]] int sign() const noexcept { return n == 0 ? 0 : (e[n - 1] > 0.0 ? 1 : -1); }
  [[nodiscard]] double approx() const noexcept {
    double s = 0.0;
    for (std::size_t i = 0; i < n; ++i) s += e[i];
    return s;
  }
};

/// Zero, or a magnitude in [2^-400, 2^400]: then no product or tail below
/// over- or underflows (products of two such numbers and of their Two-Sum
/// tails stay within [2^-910, 2^802]).
bool tame(double x) noexcept {
  const double a = std::abs(x);
  return x == 0.0 || (a >= 0x1p-400 && a <= 0x1p400);
}

/// n / d rounded to nearest (ties to even), n and d exact expansions, d > 0:
/// the guess moves by one ulp until n / d lies between the midpoints to its
/// neighbours, as round_quotient does in Mpzf. A midpoint c + h (h half the
/// gap to a neighbour, a power of two) is compared exactly as the sign of
/// n - d c - d h. False when the guess is zero, tiny, huge or wanders.
bool round_ratio(const Sum& n, const Sum& d, double& out) noexcept {
  double c = n.approx() / d.approx();
  for (int step = 0; step < 16; ++step) {
    if (!std::isfinite(c) || std::abs(c) < 0x1p-400 || std::abs(c) > 0x1p400) return false;
    const double lo = std::nextafter(c, -HUGE_VAL), hi = std::nextafter(c, HUGE_VAL);
    // n - d c, exact.
    Sum r = n;
    for (std::size_t i = 0; i < d.n; ++i) r.add_product(-d.e[i], c);
    auto against = [&](double h) {  // sign of n / d - (c + h)
      Sum s = r;
      for (std::size_t i = 0; i < d.n; ++i) s.add(-d.e[i] * h);  // h a power of two: exact
      return s.full ? 2 : s.sign();
    };
    if (r.full) return false;
    const int below = against(0.5 * (lo - c));  // lo - c exact (Sterbenz), halved exactly (c is normal)
    if (below == 2) return false;
    if (below < 0) {
      c = lo;
      continue;
    }
    if (below == 0) {
      out = lo + 0.5 * (c - lo) + 0.0;  // a tie: centre() rounds it to even
      return true;
    }
    const int above = against(0.5 * (hi - c));
    if (above == 2) return false;
    if (above > 0) {
      c = hi;
      continue;
    }
    if (above == 0) {
      out = c + 0.5 * (hi - c) + 0.0;
      return true;
    }
    out = c + 0.0;
    return true;
  }
  return false;
}

}  // namespace

bool round_edge_through_level_plane(const Vec3d& p, const Vec3d& q, int k, double level, Vec3d& out) noexcept {
  // With the triangle's normal (0, 0, n_k) along k, the orientations of the
  // edge's ends are o_p = n_k (p_k - level), o_q = n_k (q_k - level), and
  // round 11's closed form x_j = (o_p q_j - o_q p_j) / (o_p - o_q) loses
  // n_k: x_j = ((p_k - level) q_j - (q_k - level) p_j) / (p_k - q_k), a
  // quotient of degree 2 over degree 1 in the input doubles.
  for (int j = 0; j < 3; ++j)
    if (!tame(p[j]) || !tame(q[j])) return false;
  if (!tame(level)) return false;
  double ah, al, bh, bl, dh, dl;
  two_sum(p[k], -level, ah, al);
  two_sum(q[k], -level, bh, bl);
  two_sum(p[k], -q[k], dh, dl);
  if (dh == 0.0) return false;  // the edge lies in the plane: not this formula
  const double s = dh > 0.0 ? 1.0 : -1.0;  // d > 0 after the sign is moved to n
  Sum d;
  d.add(s * dl);
  d.add(s * dh);
  Vec3d x;
  for (int j = 0; j < 3; ++j) {
    if (j == k) {
      x[j] = level + 0.0;  // (p_k - level) q_k - (q_k - level) p_k = level (p_k - q_k)
      continue;
    }
    Sum n;
    n.add_product(s * ah, q[j]);
    n.add_product(s * al, q[j]);
    n.add_product(-s * bh, p[j]);
    n.add_product(-s * bl, p[j]);
    if (n.full || !round_ratio(n, d, x[j])) return false;
  }
  out = x;
  return true;
}

}  // namespace atelier::net_detail
