// Made-to-measure patterns of profile templates for a job of many bodies
// (issue 26): the batch form (made_to_measure.h, MadeToMeasurePatterns)
// prepared per template on the template regenerated on the reference body,
// and one body's pattern set written by it, or by the one-shot form
// (write_made_to_measure_pattern) for a template whose batch form is not
// prepared. What `atelier regen --patterns` runs in a job of 8 bodies or
// more and Python's `prepare_made_to_measure_patterns`; the job's policy
// (from how many bodies the preparation pays: docs/performance.md, mtm13)
// and the warnings stay with the caller.
//
// The reference is regenerated like any body of the job (the caller gives
// the same RegenParams and roi as for the bodies), so its garment has the
// bodies' topology: MadeToMeasurePatterns::write() accepts the bodies'
// garments, and each body's pattern set depends on the reference and that
// body only.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/body/reference_body.h>
#include <atelier/systems/pattern/made_to_measure.h>
#include <atelier/systems/profile/profile_template.h>
#include <atelier/systems/profile/regenerate.h>

#include <filesystem>
#include <span>
#include <vector>

namespace atelier {

/// One template's made-to-measure patterns for the bodies of a job: the
/// batch form when `batch` is prepared, else the one-shot form with
/// `options`. Made by prepare_made_to_measure_patterns, or by the caller
/// with `options` only (every body one-shot). Read-only once made: several
/// bodies may be written at once (write_template_patterns).
struct TemplatePatterns {
  MadeToMeasureOptions options;  // the pattern sets' (the batch form was prepared with them)
  MadeToMeasurePatterns batch;   // prepared, or not
  /// Why `batch` is not prepared: the error of MadeToMeasurePatterns::prepare
  /// on the template's reference garment (ok when it is prepared, or when no
  /// preparation was tried).
  Status reason;
};

/// Per template (in order), the batch form of its made-to-measure patterns
/// prepared on the template regenerated on `reference` (its own positions,
/// with `params` and a collider over `roi`: the same as the job's bodies
/// are regenerated with), or the reason it could not be (then its bodies
/// take the one-shot form). The templates are regenerated together
/// (regenerate_on_body, with ctx) and prepared in parallel, one template per
/// task (each sequential): the result is the same bits for any thread
/// count, and a body's pattern set written from it the same bits whichever
/// thread writes it, in any order.
/// Reads: the templates, the reference body. Writes: nothing.
/// Errors: kInvalidArgument (a named line's fraction outside [0, 1] or not
/// finite, naming it), those of regenerate_on_body (the templates could not
/// be regenerated on the reference: naming the template; the caller may
/// fall back to the one-shot form for every template), kCancelled.
[[nodiscard]] Expected<std::vector<TemplatePatterns>> prepare_made_to_measure_patterns(
    std::span<const ProfileTemplate> templates, const ReferenceBody& reference, const Box3d& roi,
    const RegenParams& params, const MadeToMeasureOptions& options, const ExecContext& ctx = {});

/// The made-to-measure pattern set of `garment` (the template regenerated
/// on one body) in `dir`: MadeToMeasurePatterns::write when `patterns.batch`
/// is prepared, else write_made_to_measure_pattern with `patterns.options`.
/// May run for several bodies at once.
/// Reads: the garment. Writes: files in `dir` only.
/// Errors: those of the form it takes (a garment of another topology than
/// the prepared reference's: kInvalidArgument); file-system failures throw
/// Error(kIo).
[[nodiscard]] Expected<MadeToMeasureReport> write_template_patterns(const TemplatePatterns& patterns,
                                                                    const Model& garment,
                                                                    const std::filesystem::path& dir,
                                                                    const ExecContext& ctx = {});

}  // namespace atelier
