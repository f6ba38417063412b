// Made-to-measure patterns (issue 22): the pattern set of one garment
// regenerated on one body, what `atelier regen --patterns` writes per body
// and per template, in one call.
//
// Steps: open_seams (seams.h: cut along the seams the template marks, a
// surface they separate becoming several pieces, e.g. the top's front and
// back body and yoke; then tubes and multi-loop pieces left opened along
// seams chosen from the topology alone, so every body gets the same seams),
// then write_pattern_files (pattern_files.h: flatten every piece, make the
// pattern with allowances and notches, write SVG per piece and one DXF),
// then the piece measurements as CSV.
//
// Named lines: the lines across a piece, perpendicular to its grain line,
// at given fractions of the piece's height along the grain (0 at the
// lowest point of its sew line, 1 at the highest); a width at a named line
// is the length of that line inside the sew line (outer loop minus holes;
// several intervals add up), in mm. The default lines are "hem" 0.02,
// "low" 0.25, "middle" 0.5, "high" 0.75 and "top" 0.98: the grain runs
// along the body's up axis (the mannequin's and MakeHuman's +y), so on a
// skirt or a trouser leg they are horizontal girth lines of the flat piece.
//
// measurements.csv (one row per measurement, header first):
//   piece,kind,name,pattern_mm,body_mm
//   kind "height": name "grain", the piece's extent along its grain line;
//   kind "width":  name the named line, its width (body_mm empty);
//   kind "seam":   name "joint<j>" (the seam's joint in the opened model:
//                  the same for every body of one garment), the member's
//                  length on the pattern and on the 3D garment.
// Numbers have 4 decimals (0.1 micrometre). Every file is written
// atomically (io/atomic_file.h): a killed run leaves whole files or none.
//
// Reads: the garment's faces, nodes.position, mesh edges and joints.
// Writes: files in `dir` only (the garment is not modified).
// Errors: those of open_seams, flatten_surfaces and make_pattern, and
// kInvalidArgument for a named line's fraction outside [0, 1] or a
// non-finite one; file-system failures throw Error(kIo).
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/pattern/pattern_files.h>
#include <atelier/systems/pattern/seams.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace atelier {

struct NamedLine {
  std::string name;
  double fraction = 0.5;  // of the piece's height along its grain
};

struct MadeToMeasureOptions {
  SeamOptions seams;
  /// Flattening, pattern and files (defaults: grain +y, sew-line springs
  /// 300 times stiffer with up to 2000 phase 2 iterations, SVG and DXF, no
  /// strain maps, no model file).
  PatternFileOptions files = [] {
    PatternFileOptions f;
    f.flatten.grain = Vec3d::UnitY();
    f.flatten.boundary_stiffness = 300;  // sew lines keep their lengths: seams stay sewable
    f.flatten.max_iterations = 2000;     // the stiffer system needs more L-BFGS iterations
    f.dxf = true;
    f.strain_maps = false;
    f.model = false;
    return f;
  }();
  std::vector<NamedLine> lines = {{"hem", 0.02}, {"low", 0.25}, {"middle", 0.5}, {"high", 0.75}, {"top", 0.98}};
  bool csv = true;
  /// MadeToMeasurePatterns only: flatten each body warm from the reference
  /// body (its pattern fitted by one affine map to the body's 3D lengths,
  /// its seam multipliers and factor) instead of cold. A piece whose warm
  /// start has its first steps all cut by the flip guard is flattened cold
  /// instead (PieceFlattening::warm_abandoned_iterations): on the project
  /// templates the trouser legs. On: the top's body pieces, which start
  /// from Tutte cold and run to the 2000-iteration cap, take 360-1000
  /// iterations warm at a lower E (docs/performance.md, flat11). Off: cold,
  /// as write_made_to_measure_pattern, the same bits on every piece
  /// (MadeToMeasure.PreparedPatternsGiveTheSameBitsInAnyOrderAndThreadCount,
  /// MadeToMeasure.PreparedColdGivesTheOneShotBitsOnEveryPieceHowever...).
  bool warm_start = true;
};

struct PieceMeasurements {
  std::string piece;
  double height_mm = 0;
  std::vector<double> widths_mm;  // per named line
};

struct MadeToMeasureReport {
  std::size_t seams_opened = 0;
  PatternFilesReport files;  // flattening figures, the pattern set, files written (CSV last)
  std::vector<PieceMeasurements> measurements;
  // Summary over the pieces.
  std::size_t flipped = 0;
  std::size_t failed_seams = 0;
  double max_length_error = 0;        // largest E_L over pieces
  double max_seam_difference_mm = 0;  // largest partner-length difference over seams
};

/// The made-to-measure pattern set of one garment model (see above),
/// written into `dir` (created if missing).
[[nodiscard]] Expected<MadeToMeasureReport> write_made_to_measure_pattern(const Model& garment,
                                                                          const MadeToMeasureOptions& opt,
                                                                          const std::filesystem::path& dir,
                                                                          const ExecContext& ctx = {});

/// Made-to-measure patterns of one garment topology (a template) for many
/// bodies: the batch form of write_made_to_measure_pattern, same files and
/// report. prepare() once with the garment on a reference body: the seams
/// are opened (they depend on the topology only), every piece's flattening
/// built (topology, springs, symbolic Cholesky analysis) and the reference
/// garment flattened cold (with MadeToMeasureOptions::warm_start, to 3
/// times the iteration cap). write() per body then opens the body's seams
/// (the reference's seams, chosen from the topology; but open_seams fans a
/// polygon from a corner it picks from the geometry, seams.cpp fan_start,
/// and on sampled bodies a quad of each trouser leg is fanned from another
/// corner than on the reference: the body's fans are the one-shot's
/// triangles) and flattens it with a built workspace (no topology checks,
/// springs or symbolic analysis; built for the body when its fans are not
/// the reference's, the factor then not shared): with
/// warm_start (the default) from the reference: its pattern fitted to the
/// body (no phase 1; a piece whose warm start stalls is flattened cold),
/// its seam multipliers and its Cholesky factor (kept while no spring's
/// stiffness moved by 25%); without, cold (as
/// write_made_to_measure_pattern, the same bits). Every body starts from the reference,
/// never from the body before: write()'s result depends on the reference
/// and the body only (the same bits in any order, for 1 or 2 threads), and
/// write() may run for several bodies at once (each takes a flattening
/// workspace from a pool).
/// Reads: the garments' positions (write) and topology (prepare). Writes:
/// files in `dir` only.
class MadeToMeasurePatterns {
 public:
  MadeToMeasurePatterns();
  ~MadeToMeasurePatterns();
  MadeToMeasurePatterns(MadeToMeasurePatterns&&) noexcept;
  MadeToMeasurePatterns& operator=(MadeToMeasurePatterns&&) noexcept;

  /// Errors: as write_made_to_measure_pattern's (the reference's).
  [[nodiscard]] Status prepare(const Model& reference, const MadeToMeasureOptions& opt = {},
                               const ExecContext& ctx = {});
  /// The pattern set of `garment` (the reference's topology, other
  /// positions) into `dir`. Errors: kInvalidArgument (not prepared, or a
  /// garment of another topology), and those of the flattening and
  /// make_pattern; file-system failures throw Error(kIo).
  [[nodiscard]] Expected<MadeToMeasureReport> write(const Model& garment, const std::filesystem::path& dir,
                                                    const ExecContext& ctx = {}) const;
  [[nodiscard]] bool prepared() const noexcept { return impl_ != nullptr; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The width of a piece's sew line at height v (mm, pattern coordinates):
/// the total length of the line v = const inside it (even-odd over loops).
[[nodiscard]] double sew_line_width(const PatternPiece& piece, double v) noexcept;

}  // namespace atelier
