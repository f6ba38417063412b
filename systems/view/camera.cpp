#include <atelier/systems/view/camera.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace atelier {

namespace {


}  // namespace

void CameraFrame::ray(double px, double py, std::uint32_t width, std::uint32_t height, Vec3d& origin,
                      Vec3d& dir) const noexcept {
  // Image plane coordinates in [-aspect, aspect] x [-1, 1], y up.
  const double aspect = static_cast<double>(width) / static_cast<double>(height);
  const double u = (2.0 * px / width - 1.0) * aspect;
  const double v = 1.0 - 2.0 * py / height;
  if (projection == Projection::kOrthographic) {
    origin = eye + (u * half_height) * right + (v * half_height) * up;
    dir = forward;
  } else {
    origin = eye;
    dir = (forward + (u * tan_half_fov) * right + (v * tan_half_fov) * up).normalized();
  }
}

Vec3d Camera::project(const Vec3d& p) const {
  const Vec4d c = projection * (view * Vec4d(p.x(), p.y(), p.z(), 1.0));
  if (!(c.w() > 0)) return Vec3d(kNaN, kNaN, kNaN);
  const Vec3d ndc = c.head<3>() / c.w();
  return Vec3d((ndc.x() + 1.0) * 0.5 * width, (1.0 - ndc.y()) * 0.5 * height, ndc.z());
}

std::pair<Vec3d, Vec3d> Camera::ray(const Vec2d& px) const {
  const Mat4d inv = (projection * view).inverse();
  const double x = 2.0 * px.x() / width - 1.0, y = 1.0 - 2.0 * px.y() / height;
  // The near plane and NDC depth 0 (not the far plane): with a large
  // far/near ratio the far point is badly conditioned.
  const Vec4d n = inv * Vec4d(x, y, -1.0, 1.0), f = inv * Vec4d(x, y, 0.0, 1.0);
  const Vec3d pn = n.head<3>() / n.w(), pf = f.head<3>() / f.w();
  return {pn, (pf - pn).normalized()};
}

namespace {

[[nodiscard]] Mat4d look_at_matrix(const Vec3d& eye, const Vec3d& target, const Vec3d& up) {
  const Vec3d f = (target - eye).normalized();
  const Vec3d s = f.cross(up).normalized();
  const Vec3d u = s.cross(f);
  Mat4d v = Mat4d::Identity();
  v.block<1, 3>(0, 0) = s.transpose();
  v.block<1, 3>(1, 0) = u.transpose();
  v.block<1, 3>(2, 0) = -f.transpose();
  v(0, 3) = -s.dot(eye);
  v(1, 3) = -u.dot(eye);
  v(2, 3) = f.dot(eye);
  return v;
}

}  // namespace

Camera Camera::look_at(const Vec3d& eye, const Vec3d& target, const Vec3d& up, double fov_y_deg, int w, int h,
                       double near_z, double far_z) {
  const double dist = (target - eye).norm();
  if (!(near_z > 0)) near_z = 1e-3 * dist;
  if (!(far_z > near_z)) far_z = 1e3 * dist;
  Camera c;
  c.width = w;
  c.height = h;
  c.view = look_at_matrix(eye, target, up);
  const double f = 1.0 / std::tan(0.5 * fov_y_deg * std::numbers::pi / 180.0), aspect = double(w) / double(h);
  Mat4d p = Mat4d::Zero();
  p(0, 0) = f / aspect;
  p(1, 1) = f;
  p(2, 2) = (far_z + near_z) / (near_z - far_z);
  p(2, 3) = 2.0 * far_z * near_z / (near_z - far_z);
  p(3, 2) = -1.0;
  c.projection = p;
  return c;
}

Camera Camera::orthographic(const Vec3d& eye, const Vec3d& target, const Vec3d& up, double half_height, int w, int h,
                            double near_z, double far_z) {
  const double dist = (target - eye).norm();
  if (near_z == 0 && far_z == 0) {
    near_z = -1e3 * dist;
    far_z = 1e3 * dist;
  }
  Camera c;
  c.width = w;
  c.height = h;
  c.view = look_at_matrix(eye, target, up);
  const double half_width = half_height * double(w) / double(h);
  Mat4d p = Mat4d::Identity();
  p(0, 0) = 1.0 / half_width;
  p(1, 1) = 1.0 / half_height;
  p(2, 2) = -2.0 / (far_z - near_z);
  p(2, 3) = -(far_z + near_z) / (far_z - near_z);
  c.projection = p;
  return c;
}


namespace {

/// The view matrix of an orthonormal frame (rows right, up, -forward), so
/// that frame() reads the same vectors back.
Mat4d view_of_frame(const Vec3d& eye, const Vec3d& forward, const Vec3d& up, const Vec3d& right) {
  Mat4d v = Mat4d::Identity();
  v.block<1, 3>(0, 0) = right.transpose();
  v.block<1, 3>(1, 0) = up.transpose();
  v.block<1, 3>(2, 0) = -forward.transpose();
  v(0, 3) = -right.dot(eye);
  v(1, 3) = -up.dot(eye);
  v(2, 3) = forward.dot(eye);
  return v;
}

}  // namespace

Expected<CameraFrame> Camera::frame() const {
  if (!view.allFinite() || !projection.allFinite())
    return Status(ErrorCode::kUnsupported, "camera: non-finite matrices");
  const Eigen::Matrix3d r = view.block<3, 3>(0, 0);
  if (!((r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9) || !(r.determinant() > 0))
    return Status(ErrorCode::kUnsupported, "camera: the view matrix is not a rigid motion");
  if (view.row(3) != Vec4d(0, 0, 0, 1).transpose())
    return Status(ErrorCode::kUnsupported, "camera: the view matrix's last row is not (0, 0, 0, 1)");
  const Mat4d& p = projection;
  // Centred pinhole or orthographic: no shear, no offset of the image centre.
  if (p(0, 1) != 0 || p(1, 0) != 0 || p(0, 2) != 0 || p(1, 2) != 0 || p(3, 0) != 0 || p(3, 1) != 0 ||
      !(p(1, 1) > 0) || !(p(0, 0) > 0))
    return Status(ErrorCode::kUnsupported, "camera: an oblique or off-centre projection has no pinhole frame");
  CameraFrame f;
  f.right = r.row(0).transpose();
  f.up = r.row(1).transpose();
  f.forward = -r.row(2).transpose();
  // eye = -R^T t (exact for the axis-aligned frames of frame_box).
  f.eye = -(f.right * view(0, 3) + f.up * view(1, 3) - f.forward * view(2, 3));
  if (perspective()) {
    if (p(3, 2) != -1.0 || p(3, 3) != 0 || p(0, 3) != 0 || p(1, 3) != 0)
      return Status(ErrorCode::kUnsupported, "camera: not a pinhole perspective projection");
    f.projection = Projection::kPerspective;
    f.tan_half_fov = 1.0 / p(1, 1);
  } else {
    if (p(3, 3) != 1.0 || p(0, 3) != 0 || p(1, 3) != 0)
      return Status(ErrorCode::kUnsupported, "camera: not a centred orthographic projection");
    f.projection = Projection::kOrthographic;
    f.half_height = 1.0 / p(1, 1);
  }
  return f;
}

Status Camera::check() const {
  if (!(width > 0) || !(height > 0))
    return {ErrorCode::kInvalidArgument, "camera: the viewport must be positive (" + std::to_string(width) + " x " +
                                             std::to_string(height) + ")"};
  if (!view.allFinite()) return {ErrorCode::kInvalidArgument, "camera: the view matrix has a non-finite entry"};
  if (!projection.allFinite())
    return {ErrorCode::kInvalidArgument, "camera: the projection matrix has a non-finite entry"};
  const Mat4d pv = projection * view;
  const double det = pv.determinant();
  const double scale = pv.cwiseAbs().maxCoeff();
  if (!(std::abs(det) > 1e-300) || !(std::abs(det) > 1e-14 * scale * scale * scale * scale))
    return {ErrorCode::kInvalidArgument, "camera: projection * view is singular"};
  return {};
}

Expected<Camera> frame_box(const Box3d& box, View view, Projection projection, std::uint32_t width,
                           std::uint32_t height, double margin, double fov_degrees) {
  if (box.empty() || !box.lo.allFinite() || !box.hi.allFinite())
    return Status(ErrorCode::kInvalidArgument, "frame_box: empty or non-finite box");
  if (width == 0 || height == 0) return Status(ErrorCode::kInvalidArgument, "frame_box: zero picture size");
  if (!(margin >= 0.0) || !std::isfinite(margin)) return Status(ErrorCode::kInvalidArgument, "frame_box: bad margin");
  if (projection == Projection::kPerspective && !(fov_degrees > 0.0 && fov_degrees < 170.0))
    return Status(ErrorCode::kInvalidArgument, "frame_box: field of view outside (0, 170) degrees");
  const double aspect = static_cast<double>(width) / static_cast<double>(height);
  const Vec3d up = Vec3d::UnitY();
  Vec3d forward = -Vec3d::UnitZ();
  switch (view) {
    case View::kFront: forward = -Vec3d::UnitZ(); break;
    case View::kSide: forward = -Vec3d::UnitX(); break;
    case View::kBack: forward = Vec3d::UnitZ(); break;
  }
  const Vec3d right = forward.cross(up);
  const Vec3d centre = 0.5 * (box.lo + box.hi);
  const Vec3d ext = box.hi - box.lo;
  const double diag = std::max(ext.norm(), 1e-12);
  // Extents of the box on the picture's axes (absolute values: axis aligned).
  const double w = std::abs(right.dot(ext)), h = std::abs(up.dot(ext));
  const double pad = margin * std::max(w, h);
  const double half_h = std::max({0.5 * h + pad, (0.5 * w + pad) / aspect, 1e-12});
  Camera c;
  c.width = static_cast<int>(width);
  c.height = static_cast<int>(height);
  Mat4d p = Mat4d::Zero();
  Vec3d eye;
  if (projection == Projection::kOrthographic) {
    eye = centre - forward * diag;  // rays start in front of the whole box
    const double near_z = 0.0, far_z = 3.0 * diag;
    p(0, 0) = 1.0 / (half_h * aspect);
    p(1, 1) = 1.0 / half_h;
    p(2, 2) = -2.0 / (far_z - near_z);
    p(2, 3) = -(far_z + near_z) / (far_z - near_z);
    p(3, 3) = 1.0;
  } else {
    const double tan_half = std::tan(0.5 * fov_degrees * std::numbers::pi / 180.0);
    // Bounding sphere of radius diag/2 fits the smaller half-angle.
    const double tan_min = tan_half * std::min(1.0, aspect);
    const double r = 0.5 * diag * (1.0 + margin);
    const double dist = r * std::sqrt(1.0 + 1.0 / (tan_min * tan_min));
    eye = centre - forward * dist;
    const double near_z = 1e-3 * dist, far_z = dist + 2.0 * diag;
    p(0, 0) = 1.0 / (tan_half * aspect);
    p(1, 1) = 1.0 / tan_half;
    p(2, 2) = (far_z + near_z) / (near_z - far_z);
    p(2, 3) = 2.0 * far_z * near_z / (near_z - far_z);
    p(3, 2) = -1.0;
  }
  c.view = view_of_frame(eye, forward, up, right);
  c.projection = p;
  return c;
}

}  // namespace atelier
