// Math aliases over Eigen.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace atelier {

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

[[nodiscard]] inline bool is_finite(const Vec3d& p) noexcept { return p.allFinite(); }

}  // namespace atelier
