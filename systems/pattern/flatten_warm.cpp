// The warm start of phase 2 for made-to-measure patterns (flatten_detail.h):
// another body's pattern of the same piece, fitted by one affine map to
// this body's rest lengths before phase 2 starts from it.
#include <Eigen/Dense>
#include <cmath>

#include "flatten_detail.h"

namespace atelier::pattern_detail {

void fit_warm_start(const PieceTopology& t, const RestState& rest, std::vector<Vec2d>& uv) {
  if (uv.empty() || t.spring.empty()) return;
  Vec2d centroid = Vec2d::Zero();
  for (const Vec2d& q : uv) centroid += q;
  centroid /= static_cast<double>(uv.size());
  // The uniform scale first: argmin_s sum 1/2 C (s r - l)^2, in closed form.
  double num = 0, den = 0;
  for (std::size_t s = 0; s < t.spring.size(); ++s) {
    const double r = (uv[t.spring[s][0]] - uv[t.spring[s][1]]).norm();
    num += rest.stiffness[s] * rest.length[s] * r;
    den += rest.stiffness[s] * r * r;
  }
  if (!(den > 0) || !(num > 0)) return;
  Eigen::Matrix2d A = (num / den) * Eigen::Matrix2d::Identity();
  // Then Gauss-Newton on A = [a b; b c] (a rotation would not change E):
  // r_ij = |A d_ij|, dr/d(a, b, c) = (u_x d_x, u_x d_y + u_y d_x, u_y d_y)
  // with u = A d / r. A step that would make det A <= 0 (a reflection or a
  // collapse) ends the fit, so every accepted A keeps the orientation.
  for (int it = 0; it < 8; ++it) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (std::size_t s = 0; s < t.spring.size(); ++s) {
      const Vec2d d = uv[t.spring[s][0]] - uv[t.spring[s][1]];
      const Vec2d ad = A * d;
      const double r = ad.norm();
      if (!(r > 0)) continue;
      const Vec2d u = ad / r;
      const Eigen::Vector3d J(u.x() * d.x(), u.x() * d.y() + u.y() * d.x(), u.y() * d.y());
      H += rest.stiffness[s] * J * J.transpose();
      g += rest.stiffness[s] * (r - rest.length[s]) * J;
    }
    const Eigen::Vector3d step = H.ldlt().solve(-g);
    Eigen::Matrix2d next = A;
    next(0, 0) += step[0];
    next(0, 1) += step[1];
    next(1, 0) += step[1];
    next(1, 1) += step[2];
    if (!next.allFinite() || !(next.determinant() > 0)) break;
    A = next;
    if (step.norm() <= 1e-12 * A.norm()) break;
  }
  for (Vec2d& q : uv) q = centroid + A * (q - centroid);
}

}  // namespace atelier::pattern_detail
