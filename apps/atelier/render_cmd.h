// `atelier render`: ray-cast pictures of a body and its garments (issue #6),
// e.g. `atelier render --body body.obj --garment shirt.obj --out front.png`.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"

namespace atelier::cli {

struct RenderOptions {
  std::filesystem::path body;                   // optional when garments are given
  std::vector<std::filesystem::path> garments;  // drawn in the palette's colours
  std::filesystem::path out = "render.png";
  std::string view = "front";                   // front | side | back | both
  std::uint32_t width = 480;
  std::uint32_t height = 640;
  int supersample = 2;
  bool perspective = false;
  bool no_outlines = false;
};

/// The most memory `render` may plan to use, in bytes (2 GiB): a larger
/// picture is refused before any work, with its cost (issue 27: 8192 x 8192,
/// both views, grew past 2.5 GB).
inline constexpr std::size_t kRenderMaxBytes = std::size_t{2} << 30;
/// Peak memory of `render` for these options: one view's render_scene
/// buffers (systems/view/render.h), the pictures kept, their side-by-side
/// copy and the PNG's bytes (at most 6 a pixel).
[[nodiscard]] std::size_t render_cost_bytes(const RenderOptions& opt) noexcept;

/// Declares the subcommand and its options on `app` (filled into `opt`).
CLI::App* add_render_subcommand(CLI::App& app, RenderOptions& opt);
/// Reads the meshes (OBJ, PLY or OFF), renders and writes the PNG atomically.
int run_render(const Common& common, const RenderOptions& opt, Log& log);

}  // namespace atelier::cli
