// `atelier sketch`: the sketch tools of seed 001 section 5 (painting,
// penetrated painting, cutting, partitioning) driven by a stroke file
// (docs/strokes.md), e.g.
//   atelier sketch --mesh dress.obj --strokes neckline.json --out dress-cut.obj --json report.json
// Pieces of a partition become OBJ groups. Thin over apply_strokes
// (systems/sketch/sketch.h). Exit codes: 0 ok, 1 some strokes failed
// (--keep-going), 2 usage, 3 bad input (mesh, stroke file, or a stroke the
// tools refuse on this mesh: nothing is written but the --json report), 4
// internal.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"

namespace atelier::cli {

struct SketchOptions {
  std::filesystem::path mesh, strokes, out, json;
  std::vector<std::string> surfaces;  // paint only on these surfaces (names)
  bool keep_going = false;
};

CLI::App* add_sketch_subcommand(CLI::App& app, SketchOptions& opt);
int run_sketch(const Common& common, const SketchOptions& opt, Log& log);

}  // namespace atelier::cli
