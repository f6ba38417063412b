// The atelier subcommands. Each returns a process exit code:
//   0 success, 1 partial failure (some bodies failed, or validation found
//   problems), 2 usage error, 3 bad input, 4 internal error.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "log.h"
#include <atelier/engine/exec_context.h>
#include <atelier/systems/body/body_set.h>

namespace atelier::cli {

enum ExitCode : int { kExitOk = 0, kExitPartial = 1, kExitUsage = 2, kExitInput = 3, kExitInternal = 4 };

struct Common {
  int threads = 0;
  std::uint64_t seed = 1;
  bool quiet = false;
  bool log_json = false;
  [[nodiscard]] ExecContext context() const {
    ExecContext c;
    c.threads = threads;
    return c;
  }
};

struct DemoOptions {
  std::size_t bodies = 1000;
  std::size_t chunk = 64;
  std::size_t meshes = 5;
  std::filesystem::path out = "out/demo";
};
int run_demo(const Common& common, const DemoOptions& opt, Log& log);

/// Reads OBJ, PLY, OFF or the native .atm by extension; Error(kIo) for a
/// missing file, Error(kInvalidArgument) for an unknown extension.
[[nodiscard]] Model read_mesh_file(const std::filesystem::path& p);
/// Refuses an output path whose extension is not .obj, .ply, .off or .atm
/// (before any work is done).
void check_mesh_output(const std::filesystem::path& p);
/// Writes the model in the format its extension names, atomically; OFF
/// merges surfaces, which is logged as a warning.
void write_mesh_file(const Model& m, const std::filesystem::path& p, const Log& log);

/// Creates the output folder `dir` (and its parents). Error(kIo), exit 3,
/// naming the path when it cannot: a file where a folder should be (that
/// file named), no permission. std::filesystem's own exception would be an
/// "internal error" (exit 4) at the entry point.
void make_output_dir(const std::filesystem::path& dir);

/// Removes the temporaries a killed run left in `out` and every folder
/// under it (io/atomic_file.h remove_stale_temporaries: only those whose
/// writer is gone). Called by the commands that write a tree of outputs
/// (regen, bodies, demo) once their own writers are done. Returns the
/// number removed; never throws.
std::size_t remove_stale_output_temporaries(const std::filesystem::path& out) noexcept;

int run_validate(const Common& common, const std::filesystem::path& file, Log& log);
int run_convert(const Common& common, const std::filesystem::path& in, const std::filesystem::path& out, Log& log);

/// The most bodies one job may ask for: beyond it a count is a typo (or a
/// negative number wrapped around), not a job.
inline constexpr std::size_t kMaxBodyCount = 100'000'000;
/// The largest clearance a template may be regenerated with, in metres.
inline constexpr double kMaxClearance = 1.0;
/// `--count`: a whole number in [1, kMaxBodyCount]; "-1" and 2^64 are usage
/// errors instead of an endless job.
[[nodiscard]] CLI::Validator body_count_check();
/// `--clearance`: a finite distance in [0, kMaxClearance] metres.
[[nodiscard]] CLI::Validator clearance_check();

/// The footer of every --help: the global options, which may stand before
/// or after the subcommand.
inline constexpr const char* kGlobalOptionsHelp =
    "Global options (before or after the subcommand):\n"
    "  --threads N    worker threads (0 = all cores)\n"
    "  --seed S       random seed for sampled bodies\n"
    "  --quiet        only warnings and errors\n"
    "  --log-json     log lines as JSON on stderr (for pipelines)\n"
    "  --version      print the version and exit";
/// When a parse failed because the first word that is not an option (nor
/// the value of a global option) names no subcommand: the error naming it
/// and the subcommands there are. Empty otherwise.
[[nodiscard]] std::string unknown_subcommand(const CLI::App& app, int argc, const char* const* argv);

struct BodiesOptions {
  std::string source = "mannequin";  // mannequin | makehuman | a directory of OBJ files
  std::size_t count = 100;
  std::size_t meshes = 0;            // OBJ files of the first N bodies
  std::filesystem::path out = "out/bodies";
  std::filesystem::path data = "../shared/data";
  std::filesystem::path reference;   // OBJ of the reference body (directory sources)
  double scale = 1.0;                // file units to metres (directory sources)
  std::string up = "y";              // the files' up axis (directory sources): y | z
  std::filesystem::path features;    // feature-curve JSON for the reference (directory sources; regen)
};
int run_bodies(const Common& common, const BodiesOptions& opt, Log& log);
/// `--scale S --up y|z` as a BodyFrame; throws Error(kInvalidArgument)
/// naming the option.
[[nodiscard]] BodyFrame body_frame(double scale, const std::string& up);
/// The body source named by opt.source (mannequin, makehuman, or a directory
/// of OBJ files with opt.reference); throws Error on bad input.
[[nodiscard]] std::unique_ptr<BodySource> make_body_source(const Common& common, const BodiesOptions& opt);

}  // namespace atelier::cli
