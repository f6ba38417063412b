// Private to the collision body's sources (collision_body.cpp and
// collision_body_embree.cpp): the best triangle of one query and its bound,
// shared so that both backends apply the same tie rule to the same numbers.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>

#include <atelier/systems/spatial/collision_body.h>

namespace atelier {

namespace collision_detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// A squared bound in float for the lane tests, rounded up with a relative
// margin (2e-6, far above float rounding): a lane is opened when its
// conservative box distance is at most the bound, so every box the exact
// test would open is opened (ties included).
inline float float_bound(double b2) noexcept {
  return static_cast<float>(std::min(b2 * (1.0 + 2e-6), static_cast<double>(std::numeric_limits<float>::max())));
}

}  // namespace collision_detail

// The best triangle so far: smallest squared distance (exact, double), ties
// to the smaller triangle index, so the answer does not depend on the order
// in which a backend visits the triangles nor on the hint.
struct CollisionBody::Best {
  double d2 = collision_detail::kInf;
  float d2f = std::numeric_limits<float>::max();
  std::uint32_t t = kNoTriangle;
  TrianglePoint r;
  bool take(double d, std::uint32_t tri, const TrianglePoint& at) noexcept {
    if (d < d2 || (d == d2 && tri < t)) {
      d2 = d;
      d2f = collision_detail::float_bound(d);
      t = tri;
      r = at;
      return true;
    }
    return false;
  }
};

}  // namespace atelier
