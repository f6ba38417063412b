#include <atelier/engine/parallel.h>
#include <atelier/systems/view/render.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>

namespace atelier {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Area-weighted vertex normals (the cross product's length is twice the
// area) for smooth shading; points used by no triangle keep a zero normal.
std::vector<Vec3d> vertex_normals(const BodyBvh& bvh) {
  const auto pos = bvh.positions();
  std::vector<Vec3d> n(pos.size(), Vec3d::Zero());
  for (const Triangle& t : bvh.triangles()) {
    const Vec3d fn = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
    for (std::uint32_t c : t) n[c] += fn;
  }
  for (Vec3d& v : n) {
    const double len = v.norm();
    if (len > 0.0) v /= len;
  }
  return n;
}

struct Hit {
  std::int32_t mesh = -1;
  double t = kInf;
  Vec3d normal = Vec3d::Zero();
  Vec3d colour = Vec3d::Zero();  // the surface's colour at the hit
};

double srgb_encode(double c) noexcept {
  c = std::clamp(c, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}

std::uint8_t to_byte(double c) noexcept {
  return static_cast<std::uint8_t>(std::lround(srgb_encode(c) * 255.0));
}

Status check_meshes(std::span<const RenderMesh> meshes) {
  if (meshes.empty()) return {ErrorCode::kInvalidArgument, "render: no meshes"};
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    if (!meshes[i].bvh || meshes[i].bvh->empty())
      return {ErrorCode::kInvalidArgument, "render: mesh " + std::to_string(i) + " has no committed BVH"};
    const auto& vc = meshes[i].vertex_colours;
    if (!vc.empty() && vc.size() != meshes[i].bvh->positions().size())
      return {ErrorCode::kInvalidArgument, "render: mesh " + std::to_string(i) + " has " + std::to_string(vc.size()) +
                                               " vertex colours for " +
                                               std::to_string(meshes[i].bvh->positions().size()) + " positions"};
    for (std::size_t v = 0; v < vc.size(); ++v)
      if (!vc[v].allFinite())
        return {ErrorCode::kInvalidArgument,
                "render: mesh " + std::to_string(i) + " vertex colour " + std::to_string(v) + " is not finite"};
    if (!(meshes[i].shading >= 0.0 && meshes[i].shading <= 1.0))
      return {ErrorCode::kInvalidArgument, "render: mesh " + std::to_string(i) + " shading is not in [0, 1]"};
  }
  return {};
}

}  // namespace

Expected<RenderResult> render_scene(std::span<const RenderMesh> meshes, const RenderParams& params,
                                    const ExecContext& ctx) {
  if (Status s = check_meshes(meshes); !s) return s;
  if (params.width == 0 || params.height == 0) return Status(ErrorCode::kInvalidArgument, "render: zero image size");
  Box3d box = params.frame;
  if (box.empty()) {
    for (const RenderMesh& m : meshes) {
      const Box3d b = m.bvh->bounds();
      box.extend(b.lo);
      box.extend(b.hi);
    }
  }
  if (params.width > (1u << 15) || params.height > (1u << 15))
    return Status(ErrorCode::kInvalidArgument, "render: image too large");
  auto cam =
      frame_box(box, params.view, params.projection, params.width, params.height, params.margin, params.fov_degrees);
  if (!cam) return cam.status();
  return render_scene(meshes, *cam, params, ctx);
}

std::size_t render_scene_bytes(std::uint32_t width, std::uint32_t height) noexcept {
  // RgbImage 3 + mesh int32 4 + depth double 8 + colour Vec3d 24 + edge 1.
  return std::size_t{40} * width * height;
}

Expected<RenderResult> render_scene(std::span<const RenderMesh> meshes, const Camera& camera,
                                    const RenderParams& params, const ExecContext& ctx) {
  if (Status s = check_meshes(meshes); !s) return s;
  if (camera.width <= 0 || camera.height <= 0) return Status(ErrorCode::kInvalidArgument, "render: zero image size");
  const auto W = static_cast<std::uint32_t>(camera.width), H = static_cast<std::uint32_t>(camera.height);
  auto framed = camera.frame();
  if (!framed) return Status(ErrorCode::kInvalidArgument, "render: " + framed.status().message());
  // Rays from the camera's frame: a few operations per pixel, where the
  // matrix path (Camera::ray) inverts a 4x4 matrix.
  const CameraFrame& frame = *framed;
  if (W > (1u << 15) || H > (1u << 15)) return Status(ErrorCode::kInvalidArgument, "render: image too large");
  if (params.supersample < 1 || params.supersample > 8)
    return Status(ErrorCode::kInvalidArgument, "render: supersample must be in [1, 8]");

  std::vector<std::vector<Vec3d>> normals(meshes.size());
  for (std::size_t m = 0; m < meshes.size(); ++m) normals[m] = vertex_normals(*meshes[m].bvh);
  Box3d scene;
  for (const RenderMesh& m : meshes) {
    const Box3d b = m.bvh->bounds();
    scene.extend(b.lo);
    scene.extend(b.hi);
  }
  const double scene_diag = (scene.hi - scene.lo).norm();
  // Headlight above and to the left of the viewer (direction towards the light).
  const Vec3d light = (-frame.forward + 0.45 * frame.up - 0.3 * frame.right).normalized();

  auto trace = [&](double px, double py) {
    Vec3d o, d;
    frame.ray(px, py, W, H, o, d);
    Hit best;
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      const RayHit h = meshes[m].bvh->ray_first_hit(o, d, best.t);
      if (h.hit && h.t < best.t) {
        best.mesh = static_cast<std::int32_t>(m);
        best.t = h.t;
        const Triangle& tri = meshes[m].bvh->triangles()[h.triangle];
        const auto& vn = normals[m];
        Vec3d n = h.barycentric[0] * vn[tri[0]] + h.barycentric[1] * vn[tri[1]] + h.barycentric[2] * vn[tri[2]];
        // Smooth normals can vanish on folded meshes: keep the geometric one.
        best.normal = n.squaredNorm() > 1e-12 ? Vec3d(n.normalized()) : h.normal;
        // Two-sided: garments are open, their inner side may face the camera.
        if (h.normal.dot(d) > 0.0) best.normal = -best.normal;
        if (best.normal.dot(d) > 0.0) best.normal = -best.normal;
        const auto& vc = meshes[m].vertex_colours;
        best.colour =
            vc.empty()
                ? meshes[m].colour
                : Vec3d(h.barycentric[0] * vc[tri[0]] + h.barycentric[1] * vc[tri[1]] + h.barycentric[2] * vc[tri[2]]);
      }
    }
    return best;
  };
  auto shade = [&](const Hit& h) -> Vec3d {
    if (h.mesh < 0) return params.background;
    const double lambert = std::max(0.0, h.normal.dot(light));
    const double lit = params.ambient + (1.0 - params.ambient) * lambert;
    const double s = meshes[static_cast<std::size_t>(h.mesh)].shading;
    return h.colour * (s == 1.0 ? lit : 1.0 - s + s * lit);
  };

  RenderResult out;
  out.camera = camera;
  out.image = RgbImage(W, H);
  out.mesh.assign(std::size_t{W} * H, -1);
  out.depth.assign(std::size_t{W} * H, kInf);
  std::vector<Vec3d> colour(std::size_t{W} * H);
  const int k = params.supersample;

  ExecContext rows_ctx = ctx;
  rows_ctx.sequential_threshold = 2;
  rows_ctx.grain = 1;
  std::atomic<std::size_t> rows_done{0};
  std::atomic<bool> cancelled{false};
  std::mutex progress_mutex;
  par::for_each_n(rows_ctx, H, [&](std::size_t y) {
    if (cancelled.load(std::memory_order_relaxed) || ctx.cancelled()) {
      cancelled.store(true, std::memory_order_relaxed);
      return;
    }
    for (std::uint32_t x = 0; x < W; ++x) {
      const std::size_t i = y * W + x;
      const Hit centre = trace(x + 0.5, y + 0.5);
      out.mesh[i] = centre.mesh;
      out.depth[i] = centre.t;
      if (k == 1) {
        colour[i] = shade(centre);
        continue;
      }
      Vec3d sum = Vec3d::Zero();
      for (int sy = 0; sy < k; ++sy)
        for (int sx = 0; sx < k; ++sx) sum += shade(trace(x + (sx + 0.5) / k, y + (sy + 0.5) / k));
      colour[i] = sum / static_cast<double>(k * k);
    }
    const std::size_t done = rows_done.fetch_add(1, std::memory_order_relaxed) + 1;
    if (ctx.progress) {
      std::lock_guard lock(progress_mutex);
      ctx.report("render", done, H);
    }
  });
  if (cancelled.load() || ctx.cancelled()) return Status(ErrorCode::kCancelled, "render: cancelled");

  if (params.outlines) {
    // Outline pixels lie on a mesh next to a different mesh, the background
    // or a depth jump (occluding contour); reading neighbours of the centre
    // buffers only, so the pass is order independent.
    const double jump = params.outline_depth_jump * std::max(scene_diag, 1e-12);
    std::vector<std::uint8_t> edge(std::size_t{W} * H, 0);
    par::for_each_n(rows_ctx, H, [&](std::size_t y) {
      for (std::uint32_t x = 0; x < W; ++x) {
        const std::size_t i = y * W + x;
        if (out.mesh[i] < 0) continue;
        auto differs = [&](std::size_t j) {
          return out.mesh[j] != out.mesh[i] || std::abs(out.depth[j] - out.depth[i]) > jump;
        };
        edge[i] = (x > 0 && differs(i - 1)) || (x + 1 < W && differs(i + 1)) || (y > 0 && differs(i - W)) ||
                  (y + 1 < H && differs(i + W));
      }
    });
    for (std::size_t i = 0; i < edge.size(); ++i)
      if (edge[i]) colour[i] = params.outline_colour;
  }
  for (std::size_t i = 0; i < colour.size(); ++i) {
    std::uint8_t* p = out.image.pixels.data() + 3 * i;
    for (int c = 0; c < 3; ++c) p[c] = to_byte(colour[i][c]);
    out.covered_pixels += out.mesh[i] >= 0;
  }
  return out;
}

Expected<RenderResult> render_scene(std::span<const RenderTriangles> meshes, const RenderParams& params,
                                    const ExecContext& ctx) {
  if (meshes.empty()) return Status(ErrorCode::kInvalidArgument, "render: no meshes");
  std::vector<BodyBvh> bvhs(meshes.size());
  std::vector<RenderMesh> scene(meshes.size());
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    if (Status s = bvhs[m].build(meshes[m].positions, meshes[m].triangles, {}, ctx); !s)
      return Status(s.code(), "render: mesh " + std::to_string(m) + ": " + s.message());
    scene[m] = {&bvhs[m], meshes[m].colour, meshes[m].vertex_colours, meshes[m].shading};
  }
  return render_scene(scene, params, ctx);
}

Expected<RgbImage> side_by_side(std::span<const RgbImage> images, std::uint32_t gap, const Vec3d& background) {
  if (images.empty()) return Status(ErrorCode::kInvalidArgument, "side_by_side: no images");
  std::uint64_t width = 0;
  std::uint32_t height = 0;
  for (const RgbImage& im : images) {
    if (im.width == 0 || im.height == 0 || im.pixels.size() != std::size_t{3} * im.width * im.height)
      return Status(ErrorCode::kInvalidArgument, "side_by_side: malformed image");
    width += im.width;
    height = std::max(height, im.height);
  }
  width += std::uint64_t{gap} * (images.size() - 1);
  if (width > (1u << 16)) return Status(ErrorCode::kInvalidArgument, "side_by_side: result too wide");
  RgbImage out(static_cast<std::uint32_t>(width), height);
  const std::uint8_t bg[3] = {to_byte(background[0]), to_byte(background[1]), to_byte(background[2])};
  for (std::size_t i = 0; i < out.pixels.size(); i += 3) std::copy(bg, bg + 3, out.pixels.data() + i);
  std::uint32_t x0 = 0;
  for (const RgbImage& im : images) {
    for (std::uint32_t y = 0; y < im.height; ++y) std::copy(im.at(0, y), im.at(0, y) + 3 * im.width, out.at(x0, y));
    x0 += im.width + gap;
  }
  return out;
}

Expected<RgbImage> render_views(std::span<const RenderTriangles> meshes, std::span<const View> views,
                                const RenderParams& params, const ExecContext& ctx) {
  if (views.empty()) return Status(ErrorCode::kInvalidArgument, "render_views: no views");
  std::vector<RgbImage> pictures;
  pictures.reserve(views.size());
  RenderParams p = params;
  for (View view : views) {
    p.view = view;
    auto r = render_scene(meshes, p, ctx);
    if (!r) return r.status();
    pictures.push_back(std::move(r->image));
  }
  return side_by_side(pictures);
}

Vec3d body_colour() noexcept {
  return {0.80, 0.62, 0.50};
}

Vec3d garment_colour(std::size_t i) noexcept {
  static constexpr double kPalette[][3] = {
      {0.20, 0.35, 0.75}, {0.75, 0.22, 0.20}, {0.22, 0.60, 0.30}, {0.70, 0.55, 0.15}, {0.50, 0.30, 0.65}};
  const auto& c = kPalette[i % std::size(kPalette)];
  return {c[0], c[1], c[2]};
}

}  // namespace atelier
