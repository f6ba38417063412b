// The net-modelling subcommands (seed 004; issue 24), each thin over one
// library call of systems/net:
//   atelier boolean --op union|intersection|difference|b-a A B [B2 ...] --out OUT
//                   [--mode exact|paper] [--correspondence visual|...] [--json FILE] [--seam-out FILE]
//                   (several B: A op B op B2 ..., each net prepared once)
//   atelier trim --mesh A --curve CURVE --out OUT [--height H] [--keep-enclosed] [--json FILE]
//   atelier round --mesh A --seam SEAM --out OUT [--mu M] [--nu N] [--rings R] [--json FILE]
// Nothing is written unless the operation succeeds (atomic files).
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"

namespace atelier::cli {

struct NetBooleanOptions {
  std::string op = "union";
  std::filesystem::path a, out, json, seam_out;
  std::vector<std::filesystem::path> b;  // one B, or a chain: A op B1 op B2 ...
  std::string mode = "exact";
  std::string correspondence = "visual";
  std::string join = "cut";
  std::string rule = "a";
  bool no_self_check = false;
  bool exact_refinement = false;  // BooleanOptions::exact_refinement
  bool check_result = false;      // --check-result: BooleanOptions::check_result (on by default: accepted, no effect)
  bool no_check_result = false;   // --no-check-result: BooleanOptions::check_result off
};
struct NetTrimOptions {
  std::filesystem::path mesh, curve, out, json, band_out;
  double height = 0.0;
  bool keep_enclosed = false;
};
struct NetRoundOptions {
  std::filesystem::path mesh, seam, out, json;
  double mu = 1.0, nu = 1.0;
  int rings = 1;
};

CLI::App* add_boolean_subcommand(CLI::App& app, NetBooleanOptions& opt);
CLI::App* add_trim_subcommand(CLI::App& app, NetTrimOptions& opt);
CLI::App* add_round_subcommand(CLI::App& app, NetRoundOptions& opt);
int run_boolean(const Common& common, const NetBooleanOptions& opt, Log& log);
int run_trim(const Common& common, const NetTrimOptions& opt, Log& log);
int run_round(const Common& common, const NetRoundOptions& opt, Log& log);

}  // namespace atelier::cli
