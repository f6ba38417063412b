// Curves that follow the garment: painted curves are stored in surface
// coordinates (ATTRIB_EDGENODE: halfedge and u; ATTRIB_FACENODE: face, fan
// triangle and areal coordinates; ATTRIB_NODE: node), never by position, so
// they mean the same place on every model with the same topology: the same
// profile template regenerated on another body (systems/profile/regenerate:
// the template refined `levels` times by the uniform 1-to-4 split, a pure
// function of the template's topology, then nodes moved), or a detail
// template decoded on another body (systems/garment: the garment's own mesh,
// moved).
//
// The mapping (docs/strokes.md, "Curves on regenerated garments"): paint once
// on the regenerated reference result (the refined model, where the curve's
// fan triangles and edges are those of every regeneration at that level),
// then copy the attribute curves by element and parameters onto each
// regenerated model and cut or partition there. Curve crossings are computed
// in areal coordinates of the fan triangle holding both segments
// (retriangulate.h) and the re-triangulation of a fan triangle with B
// boundary and I inner points always has B - 2 + 2I triangles, so the pieces
// have the same face counts on every body. A curve painted on a model of
// another level is refused (kMismatch): regenerate the reference at the
// level you cut at.
//
// Reads: `from`'s attribute curves and both models' topology. Writes: `to`'s
// attribute nodes and edges (appended; p_3d computed on `to`). Transactional.
#pragma once

#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

#include <span>
#include <vector>

namespace atelier {

/// kMismatch naming the first difference when a and b do not have the same
/// topology (live slots, halfedge tails, faces and their cycles, surfaces of
/// nodes and faces); ok otherwise. O(model).
[[nodiscard]] Status check_same_topology(const Model& a, const Model& b);

/// Copies the attribute edges `curves` of `from` (and their nodes) onto `to`
/// by element and parameters. Errors: kStaleHandle, kMismatch (topologies
/// differ). Returns the new attribute edges, in order.
[[nodiscard]] Expected<std::vector<AttribEdge>> transfer_curves(const Model& from, std::span<const AttribEdge> curves,
                                                                Model& to);

}  // namespace atelier
