// The camera: what a stroke file holds (view and projection matrices,
// OpenGL conventions, and a viewport in pixels with the origin at the top
// left, y down) and what pictures are rendered through. One type for
// strokes, profiles drawn on bodies, picking and rendering.
//
// Reads and writes nothing but itself.
#pragma once

#include <cstdint>
#include <utility>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>

namespace atelier {

/// Standard views for the mannequin/MakeHuman axes (y up, z to the front,
/// +x the body's left): kFront looks along -z, kSide along -x (the body's
/// left side, its front to the left of the picture), kBack along +z.
enum class View : std::uint8_t { kFront, kSide, kBack };
enum class Projection : std::uint8_t { kOrthographic, kPerspective };

/// A pinhole or orthographic camera's frame, read off its matrices:
/// forward, up and right orthonormal (right = forward x up). Rays of an
/// orthographic frame start on the plane through `eye` orthogonal to
/// forward; perspective rays start at `eye`.
struct CameraFrame {
  Projection projection = Projection::kOrthographic;
  Vec3d eye = Vec3d::Zero();
  Vec3d forward{0, 0, -1};
  Vec3d up{0, 1, 0};
  Vec3d right{1, 0, 0};
  double half_height = 1.0;    // orthographic: half the picture height in world units
  double tan_half_fov = 0.27;  // perspective: tan of half the vertical field of view

  /// Ray through the pixel point (px, py) of a width x height picture; dir
  /// is unit. A few operations per pixel (the renderer's rays).
  void ray(double px, double py, std::uint32_t width, std::uint32_t height, Vec3d& origin, Vec3d& dir) const noexcept;
};

/// pixel = viewport(projection * view * [p; 1]), (0, 0) at the top-left
/// corner of the top-left pixel, x to the right, y down; the camera looks
/// down its -z axis, NDC in [-1, 1]^3.
struct Camera {
  Mat4d view = Mat4d::Identity(), projection = Mat4d::Identity();
  int width = 1024, height = 1024;

  /// (x_px, y_px, ndc depth); NaN for points on or behind the eye plane (w <= 0).
  [[nodiscard]] Vec3d project(const Vec3d& p) const;
  /// World origin (on the near plane) and unit direction through a pixel
  /// point, for any projection matrix (through its inverse).
  [[nodiscard]] std::pair<Vec3d, Vec3d> ray(const Vec2d& px) const;
  /// True for a perspective projection (w depends on depth).
  [[nodiscard]] bool perspective() const noexcept { return projection(3, 2) != 0.0; }
  /// The frame of a centred pinhole or orthographic camera. Errors
  /// (kUnsupported) for an oblique or off-centre projection, a view matrix
  /// that is not a rigid motion, or non-finite matrices.
  [[nodiscard]] Expected<CameraFrame> frame() const;
  /// Checks the matrices and viewport: finite, an invertible projection *
  /// view, a positive viewport. The message names what is wrong.
  [[nodiscard]] Status check() const;

  /// Perspective camera (gluLookAt + gluPerspective). near/far <= 0 pick
  /// 1e-3 and 1e3 times the eye-target distance.
  [[nodiscard]] static Camera look_at(const Vec3d& eye, const Vec3d& target, const Vec3d& up, double fov_y_deg, int w,
                                      int h, double near_z = 0, double far_z = 0);
  /// Orthographic camera looking from eye at target; half_height is the world
  /// half-extent of the image vertically (horizontally scaled by w / h).
  /// near/far <= 0 pick -1e3 and 1e3 times the eye-target distance.
  [[nodiscard]] static Camera orthographic(const Vec3d& eye, const Vec3d& target, const Vec3d& up, double half_height,
                                           int w, int h, double near_z = 0, double far_z = 0);
};

/// A w x h camera looking at `box` from `view`, framing it with `margin`
/// (fraction of the box's size) on every side. Perspective cameras use the
/// vertical field of view `fov_degrees` and stand far enough for the box's
/// bounding sphere to fit. kInvalidArgument for an empty or non-finite box
/// or a bad size, margin or field of view.
[[nodiscard]] Expected<Camera> frame_box(const Box3d& box, View view, Projection projection, std::uint32_t width,
                                         std::uint32_t height, double margin = 0.05, double fov_degrees = 30.0);

}  // namespace atelier
