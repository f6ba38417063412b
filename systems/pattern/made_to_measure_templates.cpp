#include <atelier/engine/parallel.h>
#include <atelier/systems/pattern/made_to_measure_templates.h>

#include "made_to_measure_detail.h"

namespace atelier {

Expected<std::vector<TemplatePatterns>> prepare_made_to_measure_patterns(std::span<const ProfileTemplate> templates,
                                                                         const ReferenceBody& reference,
                                                                         const Box3d& roi, const RegenParams& params,
                                                                         const MadeToMeasureOptions& options,
                                                                         const ExecContext& ctx) {
  if (Status st = pattern_detail::check_named_lines(options); !st) return st;
  // The reference regenerated like a body of the job (its own positions):
  // its garments have the bodies' topology.
  auto garments =
      regenerate_on_body(templates, reference, reference.model.nodes.position, roi, params, {.use_grid = false}, ctx);
  if (!garments) return garments.status();
  std::vector<TemplatePatterns> out(templates.size());
  for (TemplatePatterns& t : out) t.options = options;
  // One template per task, each prepared sequentially: its bits do not
  // depend on the thread count (MadeToMeasurePatterns::prepare).
  ExecContext per_template = ctx;
  per_template.sequential_threshold = 2;
  per_template.grain = 1;
  par::for_each_n(per_template, templates.size(), [&](std::size_t k) {
    ExecContext inner = ExecContext::sequential();
    inner.cancel = ctx.cancel;
    out[k].reason = out[k].batch.prepare((*garments)[k].model, options, inner);
  });
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "made-to-measure patterns: cancelled");
  return out;
}

Expected<MadeToMeasureReport> write_template_patterns(const TemplatePatterns& patterns, const Model& garment,
                                                      const std::filesystem::path& dir, const ExecContext& ctx) {
  return patterns.batch.prepared() ? patterns.batch.write(garment, dir, ctx)
                                   : write_made_to_measure_pattern(garment, patterns.options, dir, ctx);
}

}  // namespace atelier
