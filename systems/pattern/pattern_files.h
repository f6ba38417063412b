// Pattern files (issue 22): SVG at 1:1 in millimetres, DXF after ASTM D6673
// (AAMA layers), a strain-map PNG per piece, and the one call that flattens a
// model's pieces and writes them all.
//
// Layers (SVG group ids and DXF layer names; AAMA layer numbers where AAMA
// has one):
//   content                                   SVG id          DXF layer
//   boundary: the cut line (sew line plus      boundary        1
//     seam allowance), closed
//   sew line: the flattened boundary, closed   sew_line        14
//   seam allowance: each run's offset edge     seam_allowance  SEAM_ALLOWANCE
//     (per seam member or hem), open
//   notches: slits from the sew line across    notches         4
//     the allowance to the cut line
//   grain line                                 grain_line      7
//   piece label (the piece's name)             piece_label     15
// Coordinates are millimetres. SVG: one file per piece, width and height in
// mm with a viewBox in mm (1 user unit = 1 mm), x = u and y = -v (SVG's y
// points down). DXF: one file for all pieces, AutoCAD R12 ASCII, $INSUNITS
// 4 (millimetres) and $MEASUREMENT 1 (metric); each piece is a BLOCK named
// after it, in pattern coordinates (u, v), placed by an INSERT (pieces side
// by side, 20 mm apart). Numbers are written in the shortest form that reads
// back to the same double. Files are written through AtomicFile (all or
// nothing).
//
// Strain map: the piece's triangles coloured by the principal stretch that
// departs most from 1 (sigma - 1 from flatten.h's per-triangle stretches):
// blue for compression, red for stretch, light grey at 0, saturated at
// +-`strain_map_range`; the sew line in black, on white.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/io/png.h>
#include <atelier/storage/model.h>
#include <atelier/systems/pattern/flatten.h>
#include <atelier/systems/pattern/pattern.h>

#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace atelier {

/// The SVG text of one piece / the DXF text of a set (see above).
[[nodiscard]] std::string pattern_svg(const PatternPiece& piece);
[[nodiscard]] std::string pattern_dxf(const PatternSet& set);
void write_pattern_svg(const PatternPiece& piece, const std::filesystem::path& path);
void write_pattern_dxf(const PatternSet& set, const std::filesystem::path& path);

/// The strain map of a flattened piece (pattern in m.nodes.uv).
/// Throws Error(kInvalidArgument) for a resolution out of range.
[[nodiscard]] RgbImage strain_map(const Model& m, const PieceFlattening& piece, double units_to_mm,
                                  double px_per_mm = 2, double range = 0.05);

struct PatternFileOptions {
  FlattenOptions flatten;
  PatternOptions pattern;
  bool svg = true;
  bool dxf = false;
  bool strain_maps = true;
  /// Also write the model with its pattern in nodes.uv (pattern.atm).
  bool model = true;
  double strain_map_px_per_mm = 2;
  double strain_map_range = 0.05;
};

struct PatternFilesReport {
  FlattenReport flattening;
  PatternSet pattern;
  std::vector<std::filesystem::path> files;  // written, in order
};

/// Flattens the pieces (flatten_surfaces: writes m.nodes.uv), makes the
/// pattern (make_pattern) and writes into `dir` (created if missing):
/// <piece>.svg per piece (mirrored pieces as <piece>_mirrored.svg),
/// pattern.dxf, <piece>_strain.png, pattern.atm. File names keep letters,
/// digits, '-' and '_' of the piece's name (others become '_'), made unique.
/// Errors: those of flatten_surfaces and make_pattern (nothing written);
/// file-system failures throw Error(kIo).
[[nodiscard]] Expected<PatternFilesReport> write_pattern_files(Model& m, const PatternFileOptions& opt,
                                                               const std::filesystem::path& dir,
                                                               const ExecContext& ctx = {});

/// The same for a model already flattened (its pattern in nodes.uv,
/// `flattening` the report of that flattening; opt.flatten is not read):
/// the pattern and the files only. Reads m; writes files in `dir` only.
[[nodiscard]] Expected<PatternFilesReport> write_pattern_files(const Model& m, FlattenReport flattening,
                                                               const PatternFileOptions& opt,
                                                               const std::filesystem::path& dir);

}  // namespace atelier
