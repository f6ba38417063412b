// The sketch tools driven by a stroke file (systems/view/strokes.h,
// docs/strokes.md): the one call behind `atelier sketch`, and the place
// where a stroke's tool becomes painting, cutting or partitioning (seed 001
// section 5).
//
//  - "paint" / "paint-through": paint_stroke (visible / penetrated); the
//    curves stay in the model as attribute edges.
//  - "cut": the stroke's curve (visible painting, or penetrated with
//    "through": true), then cut_along_curves. A following "pick" stroke
//    chooses the side removed (the surface point under it, located before
//    the cut); without one, every piece but the largest is removed.
//  - "partition": consecutive partition strokes are painted together, then
//    partition_along_curves splits the surfaces along all their curves at
//    once (crossings included).
//  - "extrude": a run of 2 or 3 extrude strokes is one extrusion
//    (systems/sketch/extrude.h, seed 002).
//
// A stroke with its own camera is drawn through it, else the file's.
//
// Reads: the stroke file, the model. Writes: the model (see the tools).
// Transactional as a whole: when a stroke fails the model is left as it
// was before the call and the error names the stroke (index, tool, name);
// with SketchOptions::keep_going a failing stroke is reported and skipped
// instead (each tool is transactional on its own) and the call succeeds.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/sketch/cut.h>
#include <atelier/systems/view/strokes.h>

#include <cstddef>
#include <string>
#include <vector>

namespace atelier {

struct SketchOptions {
  /// Surfaces to paint on (empty: all).
  std::vector<SurfaceIdx> surfaces;
  /// Report and skip failing strokes instead of failing the call.
  bool keep_going = false;
  RetriangulateOptions retriangulate;
};

/// What one tool did (a cut with its pick, or a run of partition strokes,
/// is one tool; its report sits at its first stroke).
struct StrokeReport {
  std::size_t stroke = 0;   // index in the file
  std::size_t strokes = 1;  // strokes this tool used
  StrokeTool tool = StrokeTool::kPaint;
  bool through = false;
  std::string name;
  Status status;  // not ok: the tool failed and changed nothing
  std::vector<double> curve_lengths;
  std::vector<bool> curve_closed;
  std::vector<AttribEdge> curves;  // painting: the attribute edges made
  std::size_t faces_added = 0, nodes_added = 0, faces_removed = 0, crossings = 0;
  std::vector<Piece> pieces;
  double removed_area = 0;
};

struct SketchReport {
  std::vector<StrokeReport> tools;
  std::size_t failed = 0;
};

/// Applies the strokes in order (see above).
[[nodiscard]] Expected<SketchReport> apply_strokes(Model& model, const StrokeFile& file,
                                                   const SketchOptions& options = {}, const ExecContext& ctx = {});

}  // namespace atelier
