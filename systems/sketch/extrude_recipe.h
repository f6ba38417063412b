// Extrusion recipes (issue 21, beyond seed 002): an extrusion of an open
// base curve recorded relative to B, so that the extruded part (a sleeve
// from an armhole, a dress from a hem, a ring collar from a neckline) is
// grown again on another model with the same topology without redrawing
// strokes, e.g. on the same profile template regenerated on another body
// (profile regeneration keeps the refined model's node indices on every
// body: the same B is the same node list).
//
// B's frame (seed 002 eq. 1, the frame O* of the sweep): origin P1*, scale
// |P1*P2*|, axes [n_p, e, n_p x e] with e = (P2* - P1*) / |P1*P2*| and
// n_p = sign * unit(e x n_B), n_B the normal of B's least-squares plane
// turned to agree with B's order (its Newell normal: the eigenvector's sign
// is arbitrary). P1*, P2* are kept as (segment of B, parameter), the copies'
// similarities (eq. 2) in that frame: x_loc' = t + s R x_loc with
// x_loc = F^T (x - P1*) / |P1*P2*|. Replaying maps each copy back through
// B's frame on the new model (R' = F' R F'^T, translations scaled by the
// new |P1*P2*|), then sews, pushes out of options.body, optimises and
// splits off exactly as extrude() does (the same code). On the model the
// recipe was recorded on the copies are the original ones to rounding; on
// another body the part follows B's position, orientation and size (a
// similarity of the designed part), not the arm or legs beyond it:
// options.body keeps it outside.
//
// Recording reads the model and the report of extrude(); replaying reads
// and writes what extrude() does (transactional: on error the model is
// unchanged). Errors: recording kUnsupported (a painted and cut base, whose
// nodes are made by the cut and exist on no other model; a mirrored pair),
// kInvalidArgument (a report without base or copies); replaying
// kInvalidArgument (base nodes out of range or dead, consecutive base nodes
// not joined by a faceless halfedge of the model, parameters out of range or
// not finite, options.mirror set), kDegenerate (B straight, P1* = P2*), and
// those of extrude's sewing, push, optimisation and split.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/sketch/extrude.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace atelier {

/// The recipe of an extrusion `report` made on `model` (after extrude()):
/// report.recipe, checked (ExtrusionRecipe is declared in extrude.h).
[[nodiscard]] Expected<ExtrusionRecipe> extrusion_recipe(const Model& model, const ExtrudeReport& report);

/// Grows the recipe's part on `model` (see above); options as for extrude()
/// (body, clearance, optimisation, as_surface; not mirror).
[[nodiscard]] Expected<ExtrudeReport> replay_extrusion(Model& model, const ExtrusionRecipe& recipe,
                                                       const ExtrudeOptions& options = {},
                                                       const ExecContext& ctx = {});

/// The recipe as JSON text (docs/strokes.md, "Extrusion recipes"); numbers
/// written to round trip bit for bit.
[[nodiscard]] std::string extrusion_recipe_json(const ExtrusionRecipe& recipe);

/// Parses extrusion_recipe_json's text. kInvalidArgument naming `source` and
/// the field (not JSON, a missing or mistyped field, tables of different
/// sizes, a non-finite number).
[[nodiscard]] Expected<ExtrusionRecipe> parse_extrusion_recipe(std::string_view text, const std::string& source);

}  // namespace atelier
