// What defines a `regen` job, kept in its output folder so that a rerun
// resumes only its own job (issue 27: a rerun with another seed used to
// report seed 2 over seed-1 rows).
//
//   <out>/job.json   the job's definition: format version, seed, the body
//                    source and its parameters, count, each template's file
//                    name, size and CRC-32 of its contents, levels,
//                    clearance, meshes. Bodies read from files are
//                    identified by contents in their own records
//                    (body_input_identity). Thread count and chunk size are not
//                    part of it: they do not change any output.
//
// A rerun with the same definition resumes (bodies with an "ok" record are
// skipped, failed ones are retried); a rerun with another definition is
// refused (exit 2, the differences named) unless --no-resume. A --no-resume
// run removes job.json first and writes it when it ends, so a folder whose
// --no-resume run was killed (old and new records mixed) has no job.json
// and its records are not trusted.
//
// Also the per-body check of a run's results (require_finite).
#pragma once

#include <atelier/storage/model.h>

#include <filesystem>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "regen_cmd.h"

namespace atelier::cli {

/// The version of job.json and of the records it vouches for.
inline constexpr int kRegenJobFormat = 1;

/// The definition of the job `opt` asks for (reads the template files).
[[nodiscard]] nlohmann::json describe_regen_job(const Common& common, const RegenOptions& opt);

/// "" when a run of `job` may use the output folder `out` (its own job, a
/// fresh folder, or --no-resume); otherwise why not, naming each
/// difference. `writer`: this process writes job.json (rank 0): for a fresh
/// folder now, for --no-resume it removes the old one.
[[nodiscard]] std::string claim_regen_folder(const std::filesystem::path& out, const nlohmann::json& job,
                                             bool no_resume, bool writer);

/// Writes out/job.json (atomically) at the end of a run.
void record_regen_job(const std::filesystem::path& out, const nlohmann::json& job);

/// What a body read from `file` is made from (its name, size and CRC-32),
/// kept in the body's record as "input"; null for a generated body (empty
/// path) or an unreadable file.
[[nodiscard]] nlohmann::json body_input_identity(const std::filesystem::path& file);

/// True when `record` (a body's <name>.json) exists and says "ok" (and,
/// with `patterns`, holds the body's made-to-measure patterns; with a
/// non-null `input`, was made from that input): a failed or unreadable
/// record, one written before `--patterns` was asked for, or one of a body
/// file edited since, is computed again.
[[nodiscard]] bool body_record_complete(const std::filesystem::path& record, bool patterns = false,
                                        const nlohmann::json& input = nullptr);

/// Throws Error(kDegenerate) naming the template and the node when a
/// regenerated position (of the live nodes of `model` when given) or a
/// quality figure is not finite. Checked on every body, so its outcome never
/// depends on what is written (--meshes): a result is never "ok" with
/// non-finite values (issue 27).
void require_finite(const std::string& name, const std::vector<Vec3d>& positions,
                    std::initializer_list<std::pair<const char*, double>> figures, const Model* model = nullptr);


}  // namespace atelier::cli
