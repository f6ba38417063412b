// A self-contained HTML report (issue #6): pictures embedded as base64 PNG
// data URIs, a summary table, per-column statistics, with no external
// resource (no fonts, styles, scripts or images fetched). Issue 26 ("reports
// people read"): every key is shown as a label with its unit and a precision
// chosen per figure (describe_figure, format_figure); each numeric column
// gets an inline SVG histogram (histogram(): deterministic bins) and a short
// table of its worst rows; all rows go to a CSV file beside the page
// (bodies.csv, RFC 4180), linked from it; a picture may carry a colour bar
// (systems/view/colour_map.h) with its range and unit. `demo` and
// `regen --report` both build their page here.
//
// Input: a JSON object of this generic shape (every key but "rows" optional):
//
//   {
//     "title":    "Garment regeneration on 100 bodies",
//     "row_noun": "bodies",          (what a row is; default "rows")
//     "summary":  {"bodies": 100, "failed": 0, "method": "detail template"},
//     "columns":  ["name", "max_penetration_mm", "mean_offset_mm"],
//     "rows":     [{"name": "body_0000", "max_penetration_mm": 0.3, ...}, ...],
//     "pictures": [{"title": "body_0000 front", "path": "body_0000_front.png",
//                   "caption": "worst max_penetration_mm",
//                   "colour_bar": {"map": "viridis", "min": 0, "max": 4.2,
//                                  "label": "edge strain", "unit": "%"}}, ...]
//   }
//
// "summary" values are scalars (number, string, bool, null). "rows" are
// objects of scalars; "columns" fixes the column order (default: the union of
// the rows' keys, each row's in nlohmann::json's order, i.e. alphabetical). Statistics (count, min, mean, median,
// 95th percentile, max) are computed for every column whose non-null values
// are all numbers. Picture paths are relative to a base directory (default:
// the report's directory) or absolute; each must be a readable PNG.
//
// A column with one value gets a line instead of a chart and a table; a
// column's worst rows are its largest values unless describe_figure says the
// lowest is the worst (smallest clearance, smallest distance).
//
// The page carries a short inline script that, once every image has decoded
// (naturalWidth > 0), sets data-images-decoded="<count>" on <body> (or
// "failed"): a headless browser check reads it back from the dumped DOM.
//
// Malformed input throws Error(kInvalidArgument) naming the offending key;
// missing or damaged pictures throw Error(kIo)/Error(kParse) naming the path.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/systems/view/render.h>

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace atelier {

/// The reports' pictures (demo and regen --report): the scene seen from the
/// front and from the side, 360 x 560 each, outlined, side by side.
[[nodiscard]] inline Expected<RgbImage> render_report_views(std::span<const RenderTriangles> scene,
                                                            const ExecContext& ctx) {
  RenderParams rp;
  rp.width = 360;
  rp.height = 560;
  rp.outlines = true;
  constexpr View kFrontAndSide[] = {View::kFront, View::kSide};
  return render_views(scene, kFrontAndSide, rp, ctx);
}

struct ColumnStats {
  std::string column;
  std::size_t count = 0;  // numeric values (nulls are skipped)
  double min = 0, mean = 0, median = 0, p95 = 0, max = 0;
};

/// Column names: report["columns"], or the union of the rows' keys (sorted
/// within a row, as nlohmann::json stores them) in order of first appearance.
[[nodiscard]] std::vector<std::string> report_columns(const nlohmann::json& report);

/// Statistics of every numeric column (order of report_columns). Percentiles
/// interpolate linearly between order statistics (type 7 of Hyndman & Fan).
[[nodiscard]] std::vector<ColumnStats> column_statistics(const nlohmann::json& report);

/// Indices of the k rows with the largest (or smallest) numeric value in
/// `column`, worst first; ties go to the lower row index; rows without a
/// number there are skipped. For choosing which bodies to picture.
[[nodiscard]] std::vector<std::size_t> worst_rows(const nlohmann::json& report, std::string_view column, std::size_t k,
                                                  bool largest = true);

/// Standard base64 (RFC 4648, with padding).
[[nodiscard]] std::string base64_encode(std::string_view bytes);

/// How a key is shown: its label, its unit, the factor from the stored
/// value to the shown one (metres stored, millimetres shown: 1000), the
/// significant digits, and which end is the worst.
struct FigureLabel {
  std::string label;  // "Mean decode time per body"
  std::string unit;   // "ms", "mm", "%", "bodies/s"; empty for counts
  double scale = 1;
  int digits = 3;
  bool lower_is_worse = false;  // a smallest clearance: the lowest value is the worst
  bool timing = false;          // differs between runs: never chooses a picture
};

/// The label of a report key: a table of the keys `demo` and `regen` write
/// (summary and per-body columns, with a garment's or template's name as a
/// prefix: "shorts_min_clearance_mm" is "shorts: smallest clearance", mm),
/// else the key humanised (underscores to spaces, first letter capitalised)
/// with the unit of its suffix (_mm, _m as mm, _ms, _s, _per_s, _pct;
/// "strain" fractions as %).
[[nodiscard]] FigureLabel describe_figure(std::string_view key);

/// `v` rounded to `digits` significant digits in fixed notation ("0.30",
/// "1235", "-12.5"); scientific when |v| < 1e-4 or >= 1e9; integers stay
/// integers when digits would cut them ("123456").
[[nodiscard]] std::string format_significant(double v, int digits);
/// A stored value as shown: scaled, rounded, with its unit ("0.30 ms",
/// "12 %", "3"); integral values of unscaled counts as integers.
[[nodiscard]] std::string format_figure(double stored, const FigureLabel& label);

/// Bin edges (bins + 1, increasing) and counts: value v is in bin i when
/// edges[i] <= v < edges[i + 1], the last bin also holding edges.back().
struct Histogram {
  std::vector<double> edges;
  std::vector<std::size_t> counts;
};
/// Deterministic bins of the finite values (non-finite ones are skipped):
/// integers spanning fewer than 30 values get one bin per integer (edges
/// at k - 0.5); otherwise `bins` equal bins from min to max (0: Sturges'
/// rule, ceil(log2 n) + 1, at most 30). Equal values get one bin of width 1
/// around them. No finite value: no bins.
[[nodiscard]] Histogram histogram(std::span<const double> values, std::size_t bins = 0);

/// The rows as CSV (RFC 4180): a header of the column keys, one record per
/// row in report_columns order, CRLF line ends; fields holding a comma, a
/// quote, CR or LF are quoted with quotes doubled; numbers in their
/// shortest round-trip form, nulls and missing values empty, booleans
/// true/false.
[[nodiscard]] std::string rows_csv(const nlohmann::json& report);

struct HtmlReportOptions {
  /// Rows shown per figure in the worst-rows tables.
  std::size_t worst_rows = 10;
  /// Base directory of relative picture paths; empty = the report's folder.
  std::filesystem::path picture_dir;
  /// The CSV of all rows, beside the page (write_html_report writes it,
  /// html_report links it); empty: none.
  std::string csv_name = "bodies.csv";
};

/// The HTML text. Relative picture paths resolve against opt.picture_dir
/// (current directory when empty).
[[nodiscard]] std::string html_report(const nlohmann::json& report, const HtmlReportOptions& opt = {});
/// Writes opt.csv_name (rows_csv, when there are rows) then the page
/// (html_report), each atomically, beside each other.
void write_html_report(const nlohmann::json& report, const std::filesystem::path& path,
                       const HtmlReportOptions& opt = {});

}  // namespace atelier
