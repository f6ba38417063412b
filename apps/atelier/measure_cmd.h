// `atelier measure`: the fit of a garment mesh on a body (issue 6), by the
// definitions of systems/fit_measure.h, e.g.
//   atelier measure --body body.obj --garment shirt.obj
//   atelier measure --body b.obj --garment g.obj --source-body ref.obj --source-garment design.obj --json fit.json
// Exit code 1 when a vertex is deeper inside the body than --tolerance.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>

#include "commands.h"

namespace atelier::cli {

struct MeasureOptions {
  std::filesystem::path body, garment;
  std::filesystem::path source_body, source_garment;  // optional pair: the design
  std::filesystem::path json;                         // optional report file
  double scale = 1.0;                                 // file units to metres
  double tolerance = 0.001;                           // "inside" beyond this depth fails
};

CLI::App* add_measure_subcommand(CLI::App& app, MeasureOptions& opt);
int run_measure(const Common& common, const MeasureOptions& opt, Log& log);

}  // namespace atelier::cli
