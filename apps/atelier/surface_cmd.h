// `atelier surface`: a network of curves to a Catmull-Clark surface through
// them (issue 23, seed 003), thin over surface_from_curves
// (systems/curvenet/curve_surface.h), e.g.
//   atelier surface --curves roof_75.txt --levels 2 --out roof.obj --json roof.json
//   atelier surface --curves hill_3.txt --mesh hill.obj --levels 3 --out hill_surface.obj --control hill_cage.obj
// Exit codes: 0 done; 1 done but the paper's cycle search (--cycles paper)
// left segments in fewer than two cycles; 2 usage; 3 bad input (the message
// names the file, line or curve); 4 internal error.
#pragma once

#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>

#include "commands.h"

namespace atelier::cli {

struct SurfaceOptions {
  std::filesystem::path curves;   // CURVE i text or OBJ `l` polylines
  std::filesystem::path mesh;     // optional traced mesh (OBJ, PLY, OFF, .atm)
  std::filesystem::path out;      // the subdivided surface (OBJ, PLY, OFF or .atm)
  std::filesystem::path control;  // optional: the control mesh
  std::filesystem::path json;     // optional: the report
  int levels = 2;
  std::string cycles = "angular";  // angular | paper
  std::size_t n0 = 3;
  double density_c = 0;     // 0: automatic
  double tolerance = 1e-6;  // intersection tolerance, relative to the network's size
  bool no_fairing = false;
};

CLI::App* add_surface_subcommand(CLI::App& app, SurfaceOptions& opt);
int run_surface(const Common& common, const SurfaceOptions& opt, Log& log);

}  // namespace atelier::cli
