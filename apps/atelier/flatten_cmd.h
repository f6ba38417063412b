// `atelier flatten`: 2D patterns of a model's pieces (issue 22), one piece per
// surface, through write_pattern_files (systems/pattern/pattern_files.h), e.g.
//   atelier flatten --mesh dress.atm --out patterns
//   atelier flatten --mesh skirt.obj --out p --seam-allowance 15 --dxf --json p/flatten.json
// Writes <piece>.svg, <piece>_strain.png, pattern.atm (the model with its
// pattern in the nodes' uv) and, with --dxf, pattern.dxf. Exit code 1 when a
// seam fails the sewability check or a piece has flipped triangles or a
// self-crossing boundary; 3 for a piece that cannot be flattened (closed,
// non-manifold, degenerate), named in the message.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"

namespace atelier::cli {

struct FlattenCmdOptions {
  std::filesystem::path mesh, out, json;
  double seam_allowance_mm = 10;
  double hem_allowance_mm = -1;  // negative: the seam allowance
  double notch_spacing_mm = 0;
  double scale = 1.0;  // file units to metres
  bool dxf = false;
  bool allow_holes = false;
  bool no_strain_maps = false;
  bool free_seams = false;  // FlattenOptions::seam_lengths off
  std::vector<std::string> surfaces;  // pieces by surface name (default: all with faces)
  std::vector<std::string> mirror;    // pieces also written mirrored
  std::vector<double> grain;          // 3D grain direction x y z
};

CLI::App* add_flatten_subcommand(CLI::App& app, FlattenCmdOptions& opt);
int run_flatten(const Common& common, const FlattenCmdOptions& opt, Log& log);

}  // namespace atelier::cli
