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

/// Declares the subcommand and its options on `app` (filled into `opt`).
CLI::App* add_render_subcommand(CLI::App& app, RenderOptions& opt);
/// Reads the meshes (OBJ, PLY or OFF), renders and writes the PNG atomically.
int run_render(const Common& common, const RenderOptions& opt, Log& log);

}  // namespace atelier::cli
