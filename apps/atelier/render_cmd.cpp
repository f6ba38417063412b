#include "render_cmd.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <deque>

#include <atelier/io/obj.h>
#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include <atelier/io/png.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/view/render.h>
#include <atelier/systems/mesh/fan_triangulation.h>

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

// A mesh's triangles in a BVH; the model stays with it (the BVH reads its
// position column at commit time).
struct SceneMesh {
  Model model;
  BodyBvh bvh;
};

void load(const fs::path& p, SceneMesh& m) {
  m.model = read_mesh_file(p);
  auto tri = fan_triangulate(m.model);
  if (!tri) throw Error(Status(ErrorCode::kInvalidArgument, p.string() + ": " + tri.status().message()));
  if (tri->triangles.empty()) throw Error(Status(ErrorCode::kInvalidArgument, p.string() + ": no faces to render"));
  const Status s = m.bvh.build(std::span<const Vec3d>(m.model.nodes.position), tri->triangles);
  if (!s) throw Error(Status(ErrorCode::kInvalidArgument, p.string() + ": " + s.message()));
}

}  // namespace

CLI::App* add_render_subcommand(CLI::App& app, RenderOptions& opt) {
  auto* cmd = app.add_subcommand("render", "ray-cast a PNG picture of a body and its garments (no GPU needed)");
  cmd->add_option("--body", opt.body, "body mesh (OBJ, PLY or OFF)");
  cmd->add_option("--garment", opt.garments, "garment mesh; repeat for several");
  cmd->add_option("--out", opt.out, "output PNG");
  cmd->add_option("--view", opt.view, "front, side, back, or both (front and side next to each other)")
      ->check(CLI::IsMember({"front", "side", "back", "both"}));
  cmd->add_option("--width", opt.width, "picture width in pixels")->check(CLI::Range(1u, 8192u));
  cmd->add_option("--height", opt.height, "picture height in pixels")->check(CLI::Range(1u, 8192u));
  cmd->add_option("--supersample", opt.supersample, "samples per pixel along each axis")->check(CLI::Range(1, 8));
  cmd->add_flag("--perspective", opt.perspective, "perspective instead of orthographic projection");
  cmd->add_flag("--no-outlines", opt.no_outlines, "no silhouette outlines");
  return cmd;
}

std::size_t render_cost_bytes(const RenderOptions& opt) noexcept {
  const std::size_t views = opt.view == "both" ? 2 : 1;
  const std::size_t pixels = std::size_t{opt.width} * opt.height;
  return render_scene_bytes(opt.width, opt.height) + pixels * views * (3 + 3 + 6);
}

int run_render(const Common& common, const RenderOptions& opt, Log& log) {
  if (opt.body.empty() && opt.garments.empty()) {
    log.error("render: give --body and/or --garment");
    return kExitUsage;
  }
  if (const std::size_t cost = render_cost_bytes(opt); cost > kRenderMaxBytes) {
    const double rays = static_cast<double>(opt.width) * opt.height * (opt.view == "both" ? 2 : 1) *
                        (1 + (opt.supersample > 1 ? opt.supersample * opt.supersample : 0));
    char msg[400];
    std::snprintf(msg, sizeof msg,
                  "render: a %u x %u picture (%s view) needs about %.1f GB of memory and %.2g rays per mesh; the "
                  "limit is %.1f GB: use a smaller --width/--height",
                  opt.width, opt.height, opt.view.c_str(), static_cast<double>(cost) / 1e9, rays,
                  static_cast<double>(kRenderMaxBytes) / 1e9);
    log.error(msg);
    return kExitUsage;
  }
  ExecContext ctx = common.context();
  // std::deque keeps addresses stable for the RenderMesh pointers.
  std::deque<SceneMesh> scene;
  std::vector<RenderMesh> meshes;
  if (!opt.body.empty()) {
    load(opt.body, scene.emplace_back());
    meshes.push_back({&scene.back().bvh, body_colour()});
  }
  for (std::size_t g = 0; g < opt.garments.size(); ++g) {
    load(opt.garments[g], scene.emplace_back());
    meshes.push_back({&scene.back().bvh, garment_colour(g)});
  }
  RenderParams p;
  p.width = opt.width;
  p.height = opt.height;
  const std::vector<View> views = opt.view == "both"   ? std::vector<View>{View::kFront, View::kSide}
                                  : opt.view == "side" ? std::vector<View>{View::kSide}
                                  : opt.view == "back" ? std::vector<View>{View::kBack}
                                                       : std::vector<View>{View::kFront};
  p.projection = opt.perspective ? Projection::kPerspective : Projection::kOrthographic;
  p.supersample = opt.supersample;
  p.outlines = !opt.no_outlines;
  ctx.progress = [&log](std::string_view stage, std::size_t done, std::size_t total) {
    log.progress(stage, done, total);
  };
  std::vector<RgbImage> pictures;
  std::size_t covered = 0;
  for (View v : views) {
    p.view = v;
    auto res = render_scene(meshes, p, ctx);
    log.end_progress();
    if (!res) throw Error(res.status());
    covered += res->covered_pixels;
    pictures.push_back(std::move(res->image));
  }
  auto image = side_by_side(pictures);
  if (!image) throw Error(image.status());
  write_png(*image, opt.out);
  std::printf("%s: %ux%u %s view, %zu meshes, %zu of %zu pixels covered\n", opt.out.string().c_str(), image->width,
              image->height, opt.view.c_str(), meshes.size(), covered, std::size_t{p.width} * p.height * views.size());
  return kExitOk;
}

}  // namespace atelier::cli
