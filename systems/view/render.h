// Ray-cast pictures of bodies and garments (issue #6: front and side views of
// sample and worst bodies, no GPU or display needed).
//
// One primary ray per pixel sample through each mesh's BodyBvh (Embree stays
// inside body_bvh.cpp); the nearest hit over all meshes wins (ties go to the
// lower mesh index). Shading is two-sided Lambert with a little ambient light
// and a headlight slightly above and left of the camera, then sRGB encoded.
// Optional outlines darken pixels where the mesh index changes or the depth
// jumps (silhouettes and occluding contours).
//
// Reads: the meshes' BVHs (positions as of their last commit). Writes: a new
// image. Rows are rendered in parallel (engine/parallel.h); every pixel is a
// pure function of its coordinates, so the output is identical for any
// thread count.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/io/png.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/view/camera.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace atelier {

/// One mesh of a scene: a committed BVH (not owned) and its colour (linear
/// RGB in [0, 1]), or one colour per BVH position (issue 26: a garment
/// coloured by a per-vertex figure, systems/view/colour_map.h), interpolated
/// barycentrically over each triangle.
struct RenderMesh {
  const BodyBvh* bvh = nullptr;
  Vec3d colour{0.8, 0.8, 0.8};
  /// Empty: `colour` everywhere; else one linear RGB colour per position.
  std::span<const Vec3d> vertex_colours;
  /// How much of the lighting applies: 1 shades as below (ambient plus
  /// Lambert); 0 shows the colour itself (a figure read against a colour
  /// bar); in between, colour * (1 - s + s * light).
  double shading = 1.0;
};

struct RenderParams {
  std::uint32_t width = 480;
  std::uint32_t height = 640;
  View view = View::kFront;
  Projection projection = Projection::kOrthographic;
  double fov_degrees = 30.0;
  double margin = 0.05;
  /// Frame this box; when empty, the union of the meshes' bounds.
  Box3d frame;
  /// Samples per pixel along each axis (k x k jittered-free grid, box filter).
  int supersample = 1;
  Vec3d background{1.0, 1.0, 1.0};
  double ambient = 0.15;
  /// Outline pixels where the mesh changes or the depth jumps by more than
  /// outline_depth_jump times the framed box's diagonal.
  bool outlines = false;
  double outline_depth_jump = 0.02;
  Vec3d outline_colour{0.1, 0.1, 0.1};
};

/// The picture and, per pixel (row-major, top row first), the index of the
/// mesh hit by the ray through the pixel centre (-1 for background) and its
/// distance along the ray (infinity for background).
struct RenderResult {
  RgbImage image;
  Camera camera;
  std::vector<std::int32_t> mesh;
  std::vector<double> depth;
  std::size_t covered_pixels = 0;  // pixels whose centre ray hits a mesh
};

/// Working memory of render_scene for a width x height picture, in bytes:
/// the picture (3 bytes a pixel), the per-pixel mesh index (4), depth (8),
/// colour (24) and outline flag (1), 40 bytes a pixel. The supersample adds
/// time, not memory: a pixel's samples are summed, never stored.
[[nodiscard]] std::size_t render_scene_bytes(std::uint32_t width, std::uint32_t height) noexcept;

/// Renders the scene. kInvalidArgument for no meshes, a null or empty BVH,
/// vertex colours not one per position (or not finite), a shading outside
/// [0, 1], a zero size or a bad supersample; kCancelled when ctx is cancelled (polled
/// per row). Progress: stage "render", rows done.
[[nodiscard]] Expected<RenderResult> render_scene(std::span<const RenderMesh> meshes, const RenderParams& params,
                                                  const ExecContext& ctx = {});
/// The same with an explicit camera (a centred pinhole or orthographic one:
/// Camera::frame()); the picture has the camera's viewport size and
/// params.width/height/view/projection/frame are ignored.
[[nodiscard]] Expected<RenderResult> render_scene(std::span<const RenderMesh> meshes, const Camera& camera,
                                                  const RenderParams& params, const ExecContext& ctx = {});

/// A mesh given as arrays (e.g. a body of a BodySet and a decoded garment):
/// render_scene builds a BVH over it for the call.
struct RenderTriangles {
  std::span<const Vec3d> positions;
  std::span<const Triangle> triangles;
  Vec3d colour{0.8, 0.8, 0.8};
  std::span<const Vec3d> vertex_colours;  // as RenderMesh: empty or one per position
  double shading = 1.0;
};
/// Builds one BVH per mesh (errors name the mesh), then renders as above.
[[nodiscard]] Expected<RenderResult> render_scene(std::span<const RenderTriangles> meshes, const RenderParams& params,
                                                  const ExecContext& ctx = {});

/// Pictures placed left to right, top aligned, `gap` pixels apart, on the
/// background colour (e.g. front and side views in one report picture).
/// kInvalidArgument when empty or an image is malformed.
[[nodiscard]] Expected<RgbImage> side_by_side(std::span<const RgbImage> images, std::uint32_t gap = 8,
                                              const Vec3d& background = Vec3d::Ones());

/// Renders the scene once per view (params with its view replaced) and
/// places the pictures side by side: the reports' front-and-side picture.
/// Errors as render_scene and side_by_side (kInvalidArgument for no views).
[[nodiscard]] Expected<RgbImage> render_views(std::span<const RenderTriangles> meshes, std::span<const View> views,
                                              const RenderParams& params, const ExecContext& ctx = {});

/// Default colours: skin for bodies, then a palette for garments.
[[nodiscard]] Vec3d body_colour() noexcept;
[[nodiscard]] Vec3d garment_colour(std::size_t i) noexcept;

}  // namespace atelier
