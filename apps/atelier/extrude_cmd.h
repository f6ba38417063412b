// `atelier extrude`: sketch extrusion (seed 002) driven by a stroke file
// (docs/strokes.md: a run of "extrude" strokes, the base stroke then one or
// two extruding strokes, each through its own camera or the file's), e.g.
//   atelier extrude --mesh cup.obj --strokes dome.json --out dome.obj --json report.json
//   atelier extrude --mesh top.atm --strokes sleeve.json --out top.atm --as-surface --body body.obj
//   atelier extrude --mesh top.obj --strokes sleeve.json --out top2.obj --mirror x   (both sleeves)
//   atelier extrude --mesh top.obj --strokes sleeve.json --out top2.obj --recipe-out sleeve.recipe.json
//   atelier extrude --mesh other_top.obj --replay sleeve.recipe.json --out other2.obj --body other.obj
// (--replay: replay_extrusion, systems/sketch/extrude_recipe.h, instead of
// the strokes: the same part relative to B on a mesh of the same topology.)
// Thin over extrude (systems/sketch/extrude.h). Exit codes: 0 ok, 2 usage,
// 3 bad input (mesh, stroke file, or strokes the extrusion refuses on this
// mesh: no mesh is written, the --json report holds the error), 4 internal.
#pragma once

#include <atelier/systems/sketch/extrude.h>

#include <CLI/CLI.hpp>
#include <cstddef>
#include <filesystem>
#include <string>

#include "commands.h"

namespace atelier::cli {

struct ExtrudeCmdOptions {
  std::filesystem::path mesh, strokes, out, json;
  std::filesystem::path recipe_out, replay;  // write the recipe / replay one instead of strokes
  std::size_t first = 0;  // index of the run's first (base) stroke
  double pick_radius = 12.0;
  bool no_optimise = false;
  bool as_surface = false;
  std::filesystem::path body;  // a closed mesh the extruded part is kept outside of
  double clearance = 0.002;
  int body_smoothing = ExtrudeOptions{}.body_smoothing;  // the library's defaults
  int settle_rounds = ExtrudeOptions{}.settle_rounds;
  std::string mirror;        // "x", "y" or "z": the plane through the origin normal to that axis
  std::string mirror_plane;  // "px,py,pz,nx,ny,nz"
};

CLI::App* add_extrude_subcommand(CLI::App& app, ExtrudeCmdOptions& opt);
int run_extrude(const Common& common, const ExtrudeCmdOptions& opt, Log& log);

}  // namespace atelier::cli
