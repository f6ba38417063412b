// Math aliases over Eigen.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <numbers>

namespace atelier {

/// A quiet NaN: "no value" in double columns (unset profile samples, no
/// depth).
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kPi = std::numbers::pi;
/// "No index" in uint32 index columns (no neighbour, no loop, unset). One
/// definition: the unity build puts several sources in one unit.
inline constexpr std::uint32_t kNone = 0xffffffffu;

using Vec2d = Eigen::Vector2d;
using Vec3d = Eigen::Vector3d;
using Vec4d = Eigen::Vector4d;
using Vec3f = Eigen::Vector3f;
using Mat3d = Eigen::Matrix3d;
using Mat4d = Eigen::Matrix4d;

/// Axis-aligned bounding box.
struct Box3d {
  Vec3d lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
           std::numeric_limits<double>::infinity()};
  Vec3d hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
           -std::numeric_limits<double>::infinity()};
  void extend(const Vec3d& p) noexcept {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  [[nodiscard]] bool empty() const noexcept { return !(lo.array() <= hi.array()).all(); }
};

/// The z component of the cross product of two plane vectors: twice the
/// signed area of the triangle (0, a, b), positive when counter-clockwise.
[[nodiscard]] inline double cross2(const Vec2d& a, const Vec2d& b) noexcept { return a.x() * b.y() - a.y() * b.x(); }

[[nodiscard]] inline bool is_finite(const Vec3d& p) noexcept { return p.allFinite(); }

/// x rounded to the nearest float, as a double (what a float file or column
/// stores). Not `double(float(x))` alone: GCC 12's SLP vectorizer at -O2/-O3
/// may drop a double -> float -> double round trip in loops (seen on
/// `p.cast<float>().cast<double>()` of Vec3d in a range-for: x and y came
/// back unrounded), so the float is pinned in a register by an empty asm.
[[nodiscard]] inline double round_to_float(double x) noexcept {
  float f = static_cast<float>(x);
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  __asm__("" : "+x"(f));
#endif
  return static_cast<double>(f);
}
[[nodiscard]] inline Vec3d round_to_float(const Vec3d& p) noexcept {
  return {round_to_float(p.x()), round_to_float(p.y()), round_to_float(p.z())};
}

}  // namespace atelier
