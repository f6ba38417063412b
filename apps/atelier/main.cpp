// atelier: the command-line tool.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "commands.h"
#include "extrude_cmd.h"
#include "flatten_cmd.h"
#include "measure_cmd.h"
#include "net_cmd.h"
#include "regen_cmd.h"
#include "render_cmd.h"
#include "sketch_cmd.h"
#include "surface_cmd.h"
#include <atelier/engine/memory.h>
#include <atelier/engine/status.h>

#ifndef ATELIER_VERSION
#define ATELIER_VERSION "0.1.0"
#endif

int main(int argc, char** argv) {
  using namespace atelier::cli;
  // Batch work frees and re-allocates the same large columns per body: keep
  // freed memory mapped instead of re-faulting it (engine/memory.h).
  (void)atelier::apply_memory_policy();
  CLI::App app{"atelier: feature-based freeform modelling around reference bodies"};
  app.set_version_flag("--version", std::string("atelier ") + ATELIER_VERSION);
  app.require_subcommand(1);
  Common common;
  app.add_option("--threads", common.threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber);
  app.add_option("--seed", common.seed, "random seed for sampled bodies");
  app.add_flag("--quiet", common.quiet, "only warnings and errors");
  app.add_flag("--log-json", common.log_json, "log lines as JSON on stderr (for pipelines)");
  // Global options may come after the subcommand too (`atelier regen
  // --threads 2`): subcommands made below inherit fallthrough and the footer
  // that lists them in every --help.
  app.fallthrough();
  app.footer(kGlobalOptionsHelp);

  DemoOptions demo;
  auto* demo_cmd = app.add_subcommand("demo", "sample mannequin bodies and regenerate the project's templates on each");
  demo_cmd->add_option("--bodies", demo.bodies, "number of bodies")->check(CLI::PositiveNumber);
  demo_cmd->add_option("--chunk", demo.chunk, "bodies per chunk (bounds memory)")->check(CLI::PositiveNumber);
  demo_cmd->add_option("--meshes", demo.meshes, "write OBJ meshes of the first N bodies");
  demo_cmd->add_option("--out", demo.out, "output folder");

  std::string validate_file;
  auto* validate_cmd = app.add_subcommand("validate", "read a mesh or model file and check every invariant");
  validate_cmd->add_option("file", validate_file, "OBJ, PLY, OFF or .atm file")->required();

  std::string convert_in, convert_out;
  auto* convert_cmd = app.add_subcommand("convert", "convert between OBJ, PLY, OFF and the native .atm format");
  convert_cmd->add_option("input", convert_in)->required();
  convert_cmd->add_option("output", convert_out)->required();

  BodiesOptions bodies;
  auto* bodies_cmd = app.add_subcommand("bodies", "sample or load a body set and export its measurements");
  bodies_cmd->add_option("--source", bodies.source, "mannequin, makehuman, or a directory of OBJ bodies");
  bodies_cmd->add_option("--count", bodies.count, "bodies to sample (mannequin, makehuman)")->check(body_count_check());
  bodies_cmd->add_option("--meshes", bodies.meshes, "write OBJ meshes of the first N bodies");
  bodies_cmd->add_option("--out", bodies.out, "output folder");
  bodies_cmd->add_option("--data", bodies.data, "the shared data folder (for makehuman)");
  bodies_cmd->add_option("--reference", bodies.reference, "reference body OBJ (directory sources)");
  bodies_cmd->add_option("--scale", bodies.scale, "file units to metres (directory sources)");
  bodies_cmd->add_option("--up", bodies.up, "the files' up axis, y or z (directory sources)")
      ->check(CLI::IsMember({"y", "z"}));

  RenderOptions render_opt;
  auto* render_cmd = add_render_subcommand(app, render_opt);
  EncodeOptions encode_opt;
  auto* encode_cmd = add_encode_subcommand(app, encode_opt);
  MeasureOptions measure_opt;
  auto* measure_cmd = add_measure_subcommand(app, measure_opt);
  RegenOptions regen_opt;
  auto* regen_cmd = add_regen_subcommand(app, regen_opt);
  NetBooleanOptions boolean_opt;
  auto* boolean_cmd = add_boolean_subcommand(app, boolean_opt);
  NetTrimOptions trim_opt;
  auto* trim_cmd = add_trim_subcommand(app, trim_opt);
  NetRoundOptions round_opt;
  auto* round_cmd = add_round_subcommand(app, round_opt);
  SketchOptions sketch_opt;
  auto* sketch_cmd = add_sketch_subcommand(app, sketch_opt);
  FlattenCmdOptions flatten_opt;
  auto* flatten_cmd = add_flatten_subcommand(app, flatten_opt);
  SurfaceOptions surface_opt;
  auto* surface_cmd = add_surface_subcommand(app, surface_opt);
  ExtrudeCmdOptions extrude_opt;
  auto* extrude_cmd = add_extrude_subcommand(app, extrude_opt);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (const std::string unknown = unknown_subcommand(app, argc, argv); !unknown.empty()) {
      std::fprintf(stderr, "%s\n", unknown.c_str());
      return kExitUsage;
    }
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }
  Log log(common.quiet, common.log_json);
  try {
    if (*demo_cmd) return run_demo(common, demo, log);
    if (*validate_cmd) return run_validate(common, validate_file, log);
    if (*convert_cmd) return run_convert(common, convert_in, convert_out, log);
    if (*bodies_cmd) return run_bodies(common, bodies, log);
    if (*render_cmd) return run_render(common, render_opt, log);
    if (*encode_cmd) return run_encode(common, encode_opt, log);
    if (*regen_cmd) return run_regen(common, regen_opt, log);
    if (*measure_cmd) return run_measure(common, measure_opt, log);
    if (*boolean_cmd) return run_boolean(common, boolean_opt, log);
    if (*trim_cmd) return run_trim(common, trim_opt, log);
    if (*round_cmd) return run_round(common, round_opt, log);
    if (*sketch_cmd) return run_sketch(common, sketch_opt, log);
    if (*flatten_cmd) return run_flatten(common, flatten_opt, log);
    if (*surface_cmd) return run_surface(common, surface_opt, log);
    if (*extrude_cmd) return run_extrude(common, extrude_opt, log);
  } catch (const atelier::Error& e) {
    log.error(e.what());
    const auto c = e.status().code();
    // Errors of the engine's own state are internal; every other error at
    // this entry point comes from the input (files, options, meshes).
    return c == atelier::ErrorCode::kInternal || c == atelier::ErrorCode::kStaleHandle ? kExitInternal : kExitInput;
  } catch (const std::exception& e) {
    log.error(std::string("internal error: ") + e.what());
    return kExitInternal;
  }
  return kExitUsage;
}
